//! Hesai PandarXT-32 (UDP protocol 6.1), PandarQT128 (3.2), Pandar128 and OT128 (1.4):
//! packets to timed points, sweeps cut by azimuth.
//!
//! The facts come from the sensors' user manuals and Hesai's SDK: the packet layouts
//! ([`wire`], [`wire128`]), the return modes and how dual returns pair their blocks, the
//! firing times ([`Model::point_offset_ns`]; the 128-channel models' channel times from
//! Hesai's firing-time files, the Pandar128's by the return's distance too), and the XT32's nominal channel elevations (15 to -16 degrees,
//! one apart, no azimuth offsets). Hesai's angle correction file replaces those per unit and
//! is needed for the 128-channel models ([`Calibration`]; the host reads the CSV). Each point
//! takes its block's azimuth plus its channel's offset, as Hesai's SDK and TIER IV's nebula
//! do. The packet time is UTC with the sensor's clock; point times are exact to the
//! nanosecond from it.

mod decoder;
mod firetimes;
mod identify;
mod model;
mod timing;
pub mod wire;
pub mod wire128;
pub mod wire_fixed;

pub use decoder::{Decoder, GAP_NS};
pub use identify::identify;
pub use model::{
    point_offset_ns, Calibration, Config, Firing, Model, ReturnMode, CHANNELS, CHANNEL_NS,
    DISTANCE_UNIT_M, FIRING_NS, MAX_CHANNELS, PANDAR128_NEAR_M,
};
pub use wire::Packet;
