//! Hesai PandarXT-32 (UDP protocol 6.1): packets to timed points, sweeps cut by azimuth.
//!
//! The facts come from the XT32 user manual's protocol and timing appendices: the packet
//! layout ([`wire`]), the return modes and how dual returns pair their blocks, the firing
//! times (the packet time stamps the last firing; firings 50 us apart; channel `c` fires
//! 0.368 + 1.512 c us into its firing), and the nominal channel elevations (15 to -16
//! degrees, one apart, no azimuth offsets), which Hesai's angle correction file replaces per
//! unit ([`Calibration`]; the host reads the CSV). Each point takes its block's azimuth plus
//! its channel's offset, as Hesai's own SDK does. The packet time is UTC with the sensor's
//! clock; point times are exact to the nanosecond from it.

mod decoder;
mod model;
pub mod wire;

pub use decoder::{Decoder, GAP_NS};
pub use model::{
    point_offset_ns, Calibration, Config, ReturnMode, CHANNELS, CHANNEL_NS, DISTANCE_UNIT_M,
    FIRING_NS,
};
pub use wire::Packet;
