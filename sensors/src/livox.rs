//! Livox SDK 1 sensors (Mid-40, Mid-70, Horizon, Tele-15, Avia): packets to timed points,
//! frames cut by time.
//!
//! A Livox sensor does not spin: its prisms draw a non-repeating pattern, and the packets
//! carry Cartesian (or spherical) points already in the sensor frame, x forward, y left, z up.
//! There is no sweep to end, so frames are cut by time, every [`Config::frame_period_ns`]
//! (the Livox ROS driver's 0.1 s by default) from the first packet's time; a packet belongs to
//! the frame its first point falls in. Each point's time is the packet's timestamp (its first
//! point's) plus its firing's index times the model's firing interval (Livox SDK 1
//! documentation: 10 us on the Mid-40/70, 100,000 points a second; 4.167 us on the
//! Horizon, Tele-15 and Avia, 240,000). Tags (the noise flags) and return numbers are kept
//! ([`crate::PointMeta`]); points at the origin (no return) are dropped. IMU packets (data
//! type 6, sent to the same port) are not points: [`Packet::imu`] reads them.

mod decoder;
pub mod wire;

pub use decoder::{Decoder, GAP_NS};
pub use wire::{ImuSample, Packet};

/// The model, for its firing interval.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Model {
    /// Mid-40 and Mid-70: 100,000 firings a second.
    Mid40,
    /// Horizon, Tele-15 and Avia: 240,000 firings a second.
    #[default]
    Horizon,
}

impl Model {
    /// Time from one firing to the next, ns.
    pub const fn firing_ns(self) -> f64 {
        match self {
            Self::Mid40 => 10_000.0,
            Self::Horizon => 1e9 / 240_000.0,
        }
    }
}

/// Decoder settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// The model (its firing interval).
    pub model: Model,
    /// Length of a frame, ns.
    pub frame_period_ns: u64,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            model: Model::default(),
            frame_period_ns: 100_000_000,
        }
    }
}
