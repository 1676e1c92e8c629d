//! Velodyne VLP-16, Puck Hi-Res, VLP-32C and HDL-32E: packets to timed points, sweeps cut by
//! azimuth.
//!
//! The per-model facts come from the sensors' manuals (VLP-16 63-9243 Rev E, VLP-32C 63-9325,
//! HDL-32E 63-9277 and its timing application note): vertical angles, VLP-32C azimuth
//! offsets, distance units (2 mm; 4 mm on the VLP-32C) and the firing timing tables that give
//! each return its own capture time. The azimuth of a return between two block azimuths is
//! interpolated from the packet's rotation rate and rounded to 0.01 degree as
//! `velodyne-decoder` 3.1 does, so the two agree to float rounding.
//!
//! A sensor whose lasers differ from the manual's nominal angles takes a [`Calibration`]
//! (the host reads Velodyne's XML or the ROS YAML files into it).

mod decoder;
mod model;
pub mod wire;

pub use decoder::{Decoder, GAP_NS};
pub use model::{Calibration, Config, Laser, Model, MAX_LASERS};
pub use wire::Packet;
