//! KISS-ICP LiDAR odometry (Vizzo et al., RA-L 2023) for targets without an allocator.
//!
//! The crate is `#![no_std]`, links no `alloc`, and never grows: every buffer lives in one
//! caller-provided arena of `u64` words (smoltcp style) whose size a `const fn` computes from
//! [`Capacities`], so it can be a `static` on a microcontroller or a `Vec` on a workstation.
//!
//! The pipeline follows the paper's four steps, one module each, with data flowing one way:
//!
//! | step | paper | module |
//! |---|---|---|
//! | motion prediction and deskewing | Sec. III-A, Eq. (1)-(4) | [`deskew`], [`preprocess`] |
//! | double voxel downsampling | Sec. III-B | [`downsample`] |
//! | local map and correspondences | Sec. III-C | [`local_map`] |
//! | adaptive threshold | Sec. III-D, Eq. (5)-(8) | [`threshold`] |
//! | robust point-to-point ICP | Sec. III-E, Eq. (9)-(13) | [`registration`] |
//!
//! [`Odometry`] runs them in that order for each scan and returns a [`FrameReport`]. Where the
//! paper is silent, the reference implementation `kiss-icp` 1.3.0 decides; the differences from
//! the paper's text are listed in the docs of [`Config`].
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod arena;
pub mod config;
pub mod degeneracy;
pub mod deskew;
pub mod downsample;
pub mod error;
pub mod lie;
pub mod local_map;
pub mod odometry;
pub mod preprocess;
pub mod registration;
pub mod report;
pub mod scalar;
pub mod threshold;
pub mod voxel;

#[cfg(test)]
mod testutil;

pub use config::{Capacities, Config};
pub use error::{ConfigError, FrameError};
pub use local_map::{Exact, PointCodec, Quantized};
pub use odometry::{FrameInput, Odometry};
pub use registration::{Executor, Sequential};
pub use report::{Dropped, FrameReport, HighWater, Status};
pub use scalar::Real;

/// Rigid transform used for every pose: a unit quaternion and a translation.
pub type Pose<T> = nalgebra::Isometry3<T>;
/// A 3D point.
pub type Point<T> = nalgebra::Point3<T>;
