//! The text form of a frame's result, shared (through `#[path]`) by the program and by
//! `tests/tests/embedded.rs`, so the emulated targets, the host twin and the workspace build
//! of the core are compared on exactly the same characters.
//!
//! Numbers use `{:e}`: Rust prints the shortest decimal that reads back to the same bits, so
//! equal text means bit-identical values.

use core::fmt::{self, Display, LowerExp};
use kiss_odom_core::{FrameReport, Pose, Real};

/// `frame <i> status=... iterations=... ...`: the report of frame `i` with `points` input points.
pub struct FrameLine<'a, T: Real>(pub usize, pub usize, pub &'a FrameReport<T>);

impl<T: Real + LowerExp> Display for FrameLine<'_, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let FrameLine(i, points, r) = *self;
        write!(
            f,
            "frame {} status={} iterations={} work={} correspondences={} points={} merge={} source={} map_voxels={} map_points={} map_radius={:e} sigma={:e} rms={:e}",
            i,
            r.status,
            r.iterations,
            r.work,
            r.correspondences,
            points,
            r.merge_points,
            r.source_points,
            r.map_voxels,
            r.map_points,
            r.map_radius,
            r.sigma,
            r.rms
        )
    }
}

/// `pose <i>` and the 12 numbers of `[R | t]`, row major (the KITTI pose-file order).
pub struct PoseLine<'a, T: Real>(pub usize, pub &'a Pose<T>);

impl<T: Real + LowerExp> Display for PoseLine<'_, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = self.1.to_homogeneous();
        write!(f, "pose {}", self.0)?;
        for r in 0..3 {
            for c in 0..4 {
                write!(f, " {:e}", m[(r, c)])?;
            }
        }
        Ok(())
    }
}
