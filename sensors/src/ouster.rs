//! Ouster OS-0/OS-1/OS-2: lidar packets to timed points in the sensor frame, sweeps by frame
//! id.
//!
//! The geometry is the sensor's: each beam has an altitude and an azimuth angle and starts
//! `lidar_origin_to_beam_origin_mm` from the lidar origin (or as `beam_to_lidar_transform`
//! says), the encoder angle of column `m` is `2 pi (1 - m / columns_per_frame)`, and
//! `lidar_to_sensor_transform` takes the lidar frame to the sensor frame, as ouster-sdk's
//! `XYZLut` computes it. Every point takes its column's timestamp. The host reads the
//! metadata JSON into a [`SensorInfo`]. IMU packets, on a port of their own, are read by
//! [`ImuPacket`].

mod decoder;
pub mod imu;
mod info;
pub mod wire;

pub use decoder::Decoder;
pub use imu::ImuPacket;
pub use info::{
    SensorInfo, MAX_BEAMS, MAX_BEAM_AZIMUTH_DEG, MAX_BEAM_ORIGIN_MM, MAX_COLUMNS,
    MAX_COLUMNS_PER_PACKET, MAX_OFFSET_MM,
};
pub use wire::{Layout, Packet, Profile};
