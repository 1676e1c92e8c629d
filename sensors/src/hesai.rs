//! Hesai PandarXT-32, XT-16 and XT32M (UDP protocol 6.1), PandarQT128 (3.2), Pandar128 and
//! OT128 (1.4), Pandar40P, Pandar64, PandarQT64 (3.1) and PandarAT128 (4.3): packets to timed
//! points, sweeps cut by azimuth (the AT128's: its mirror frames).
//!
//! The facts come from the sensors' user manuals and Hesai's SDK: the packet layouts
//! ([`wire`], [`wire128`]), the return modes and how dual returns pair their blocks, the
//! firing times ([`Model::point_offset_ns`]; the 128-channel models' channel times from
//! Hesai's firing-time files, the Pandar128's by the return's distance too), and the XT32's nominal channel elevations (15 to -16 degrees,
//! one apart, no azimuth offsets). Hesai's angle correction file replaces those per unit and
//! is needed for the 128-channel models ([`Calibration`]; the host reads the CSV). Each point
//! takes its block's azimuth plus its channel's offset, as Hesai's SDK and TIER IV's nebula
//! do; the AT128's returns take their directions from its mirror-frame correction instead
//! (`at128.rs`). The packet time is UTC with the sensor's clock; point times are exact to the
//! nanosecond from it.

mod angles;
mod at128;
mod decoder;
mod firetimes;
mod identify;
mod model;
mod timing;
pub mod wire;
pub mod wire128;
pub mod wire_fixed;

pub use angles::{Angles, ChannelAngles, MirrorAngles};
pub use at128::{
    At128Correction, ADJUST_STEPS, ADJUST_STEP_UNITS, AT128_CHANNELS, MAX_FRAMES, TURN_UNITS,
    UNITS_PER_DEG,
};
pub use decoder::{Decoder, GAP_NS};
pub use identify::identify;
pub use model::{
    point_offset_ns, Calibration, Config, Firing, Model, ReturnMode, CHANNELS, CHANNEL_NS,
    DISTANCE_UNIT_M, FIRING_NS, MAX_CHANNELS, PANDAR128_NEAR_M,
};
pub use wire::Packet;
