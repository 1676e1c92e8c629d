//! Velodyne VLP-16, Puck Hi-Res, VLP-32C, VLP-32A/B, HDL-32E, HDL-64E S2/S3 and VLS-128
//! (Alpha Prime): packets to timed points, sweeps cut by azimuth.
//!
//! The per-model facts come from the sensors' manuals (VLP-16 63-9243 Rev E, VLP-32C 63-9325,
//! HDL-32E 63-9277 and its timing application note, HDL-64E S2 and S3, VLS-128 63-9483):
//! vertical angles, azimuth offsets, distance units, block layouts (`layout.rs`) and the
//! firing timing tables that give each return its own capture time. The azimuth of a return
//! is the manuals' precision azimuth (section 9.5): its firing group's block azimuth plus the
//! rotation to the next group's, in proportion to the firing's time in the group, rounded to
//! the 0.01 degree the sensor reports.
//!
//! A sensor whose lasers differ from the manual's nominal angles takes a [`Calibration`]
//! (the host reads Velodyne's XML or the ROS YAML files into it); the HDL-64E, VLS-128 and
//! VLP-32A/B always need the unit's file.

mod calibration;
mod decoder;
mod layout;
mod model;
mod point;
pub mod wire;

pub use calibration::{Calibration, Config, Laser};
pub use decoder::{Decoder, GAP_NS};
pub use layout::{Blocks, Layout};
pub use model::{Model, BANK_FLAGS, MAX_LASERS};
pub use wire::Packet;
