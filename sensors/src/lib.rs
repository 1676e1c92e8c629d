//! Sensor packets in, timed points out: the stage before the odometry.
//!
//! A spinning LiDAR sends UDP packets, each a slice of a sweep. This crate checks each packet
//! against its wire format (fixed byte ranges, [`velodyne::Packet::new_checked`],
//! [`ouster::Packet::new_checked`], [`hesai::Packet::new_checked`],
//! [`robosense::wire::Msop::new_checked`]), turns its returns into points in the sensor frame with
//! each point's capture time from the sensor's firing sequence, and assembles sweeps: points
//! go to a caller's [`SweepSink`] in small chunks as packets arrive, with times relative to the
//! sweep start, so a sweep never needs a second full copy. Sweeps end by azimuth (Velodyne,
//! Hesai, Robosense) or frame id (Ouster); lost, late, malformed and foreign packets are
//! counted per sweep in [`SweepStats`], never patched over.
//!
//! `#![no_std]`, no allocator, no panics on any input, no `unsafe`: every table has a
//! compile-time capacity ([`velodyne::MAX_LASERS`], [`ouster::MAX_BEAMS`],
//! [`ouster::MAX_COLUMNS`], [`CHUNK`]). Calibration files and metadata JSON are parsed by the
//! host into the plain numbers of [`velodyne::Calibration`] and [`ouster::SensorInfo`].
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]
// No panic on any input: every refusal is an error value (tests may unwrap).
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::unreachable,
        clippy::todo,
        clippy::unimplemented
    )
)]

pub mod error;
pub mod hesai;
pub mod livox;
pub mod ouster;
pub mod pose_datagram;
pub mod robosense;
pub mod sweep;
mod time;
mod timeline;
pub mod velodyne;

pub use error::{ConfigError, PacketError};
/// The fixed-capacity vectors of [`velodyne::Calibration`] and [`ouster::SensorInfo`].
pub use heapless;
pub use sweep::{
    Chunk, Decode, PointMeta, Pushed, Return, SweepEnd, SweepSink, SweepStart, SweepStats, CHUNK,
    RESYNC_PACKETS,
};
