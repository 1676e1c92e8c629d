//! KISS-ICP LiDAR odometry (Vizzo et al., RA-L 2023) for targets without an allocator.
//!
//! The crate is `#![no_std]`, links no `alloc` (unless the host opts into the `alloc` feature
//! for `Odometry::boxed`), and never grows: every buffer lives in one run of `u64` words whose
//! length a `const fn` computes from [`Capacities`] ([`Capacities::arena_words`]). The words can
//! be borrowed (`&mut [u64]`), owned in place ([`Words`], const-constructible, so a `static` can
//! hold them) or boxed on a host; see [`storage`].
//!
//! # Where to start
//!
//! [`Odometry`] is the pipeline: build it from a [`Config`] (the paper's Table I; [`Config::new`]
//! gives the reference defaults for a maximum range), [`Capacities`] and storage, then call
//! [`Odometry::register_frame`] once per scan (or [`Odometry::begin_frame`] to feed a sweep in
//! pieces). Each call returns a [`FrameReport`]: the end-of-sweep pose, a [`Status`] set of
//! [`Flag`]s and what every buffer held and dropped.
//!
//! ```
//! use kiss_odom_core::{Capacities, Config, Exact, Odometry, Words};
//! const CAPS: Capacities = Capacities { scan_points: 1000, merge_points: 512,
//!     source_points: 128, map_voxels: 1024, map_points: 4096, plane_terms: false };
//! const N: usize = CAPS.arena_words::<f64, Exact>();
//! let mut words = Words::<N>::new();
//! let mut odom = Odometry::<f64, Exact, _>::new(Config::new(50.0), CAPS, &mut words).unwrap();
//! let report = odom.register_frame(&[[5.0, 1.0, 0.5], [6.0, -2.0, 0.1]], None).unwrap();
//! assert!(report.status.is_ok());
//! ```
//!
//! # The paper's steps
//!
//! The pipeline follows the paper's four steps, one module each, with data flowing one way:
//!
//! | step | paper | module |
//! |---|---|---|
//! | motion prediction and deskewing | Sec. III-A, Eq. (1)-(4) | `deskew`, `preprocess` |
//! | double voxel downsampling | Sec. III-B | `downsample` |
//! | local map and correspondences | Sec. III-C | `local_map` |
//! | adaptive threshold | Sec. III-D, Eq. (5)-(8) | `threshold` |
//! | robust point-to-point ICP | Sec. III-E, Eq. (9)-(13) | `registration` |
//! | one scan, in that order | Sec. III | `odometry::frame` |
//! | (opt-in) the prediction's rotation from a gyroscope | beyond Sec. III-A | `imu` ([`GyroPrior`]) |
//!
//! The stage functions are reachable through [`stages`], the unstable surface used by the
//! cross-check against the reference, the benchmarks and bindings. Where the paper is silent,
//! the reference implementation `kiss-icp` 1.3.0 decides; the differences from the paper's
//! text are listed in the docs of [`Config`].
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]
// No panic a caller did not ask for: every failure is an `Error` value (tests may unwrap).
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

#[cfg(feature = "alloc")]
extern crate alloc;
// Unit tests print what they measured.
#[cfg(test)]
extern crate std;

mod config;
mod deskew;
mod downsample;
mod eigen;
mod error;
mod geometry;
mod imu;
mod lie;
mod local_map;
pub mod localize;
mod observability;
mod odometry;
mod one_plane;
mod preprocess;
pub mod prior_map;
mod registration;
mod report;
mod scalar;
pub mod storage;
mod threshold;
mod voxel;

#[cfg(test)]
mod testutil;

pub use config::{Capacities, Config, Degeneracy, Robust};
pub use deskew::{StampProblem, SweepRotation, SWEEP_KNOTS};
pub use error::{ConfigError, FrameError};
pub use geometry::{widen_pose, Point, Pose};
pub use imu::{GyroPrior, ImuConfig, ImuSample, Prior};
pub use local_map::{Exact, MapCapacity, MapView, PointCodec, Quantized, Voxels};
pub use odometry::{FrameInput, Layout, Odometry, WhenFull};
pub use registration::{Executor, Sequential};
pub use report::{Dropped, Flag, FrameReport, HighWater, Status};
pub use scalar::Real;
pub use storage::{Storage, Words};

/// The pipeline's stages one by one: the **unstable** surface.
///
/// What the cross-check against the reference, the per-stage benchmarks, the property tests and
/// bindings that mirror the reference's building blocks (its `VoxelHashMap`, `Preprocessor`,
/// `Registration`, `AdaptiveThreshold`) call. Names and signatures here may change between
/// versions without notice; applications use [`Odometry`].
pub mod stages {
    pub use crate::deskew::{Deskewer, SweepMotion, TimeSpan};
    pub use crate::downsample::{
        cloud_words, grid_slots_for, reference_order, reference_order_bytes, robin_bucket_count,
        scratch_words_for, voxel_downsample, Dedup, Downsampled,
    };
    pub use crate::lie::{
        hat, left_jacobian, left_jacobian_inverse, renormalize, rotation_angle, se3_exp, se3_log,
        so3_exp, so3_log,
    };
    pub use crate::local_map::{
        LocalMap, MapLayout, UpdateStats, BLOCK, EVICT_TO, GROW_BELOW, GROW_STEP, RADIUS_BINS,
    };
    pub use crate::observability::{observability, RING_SINE, SAMPLES};
    pub use crate::preprocess::{preprocess, Drop, Preprocessed, Preprocessor};
    pub use crate::registration::{
        align_points_to_map, chunk_len, chunks_for, moved_points, work_words, Alignment, Chunk,
        IcpParams, MotionPrior, PlaneChunk, CHUNK, CHUNK_LEN, CYCLE_LEN, MIN_POINTS, PLANARITY,
        PLANE_CHUNK_LEN, PLANE_KERNEL_SCALE, SYSTEM_LEN,
    };
    pub use crate::scalar::{norm_lt, sqrt_lt};
    pub use crate::threshold::AdaptiveThreshold;
    pub use crate::voxel::{
        point_to_voxel, reference_hash, table_hash, VoxelKey, NEIGHBOUR_SHIFTS,
    };
}
