//! What each frame returns: the pose, how registration went, what the buffers hold and what
//! they dropped.

use crate::deskew::StampProblem;
use crate::scalar::Real;
use crate::Pose;

/// Frame status: empty means ok; each set flag says how the frame was degraded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Status(pub u16);

impl Status {
    /// Timestamps were given but unusable (see [`FrameReport::stamp_problem`]); the scan was
    /// registered without deskewing.
    pub const TIMESTAMPS_IGNORED: u16 = 1 << 0;
    /// ICP stopped at the iteration cap before converging.
    pub const ITERATION_CAP: u16 = 1 << 1;
    /// No correspondence within the threshold: the pose is the constant-velocity prediction.
    pub const NO_CORRESPONDENCES: u16 = 1 << 2;
    /// A normal-equation system could not be solved (too few correspondences).
    pub const SINGULAR: u16 = 1 << 3;
    /// The scene constrains some direction weakly (corridor, open plane): the pose along it
    /// mostly follows the prediction. See [`FrameReport::observability`].
    pub const DEGENERATE: u16 = 1 << 4;
    /// Points with NaN or infinite coordinates were skipped.
    pub const INVALID_POINTS: u16 = 1 << 5;
    /// The scan had more points than `Capacities::scan_points`; the rest were ignored.
    pub const SCAN_TRUNCATED: u16 = 1 << 6;
    /// A downsampled cloud or the map was full and dropped content (see [`Dropped`]).
    pub const CAPACITY: u16 = 1 << 7;

    const NAMES: [(u16, &'static str); 8] = [
        (Self::TIMESTAMPS_IGNORED, "timestamps_ignored"),
        (Self::ITERATION_CAP, "iteration_cap"),
        (Self::NO_CORRESPONDENCES, "no_correspondences"),
        (Self::SINGULAR, "singular"),
        (Self::DEGENERATE, "degenerate"),
        (Self::INVALID_POINTS, "invalid_points"),
        (Self::SCAN_TRUNCATED, "scan_truncated"),
        (Self::CAPACITY, "capacity"),
    ];

    /// No flag set.
    pub fn is_ok(self) -> bool {
        self.0 == 0
    }
    /// Whether `flag` is set.
    pub fn has(self, flag: u16) -> bool {
        self.0 & flag != 0
    }
    /// Sets `flag` when `on`.
    pub fn set(&mut self, flag: u16, on: bool) {
        if on {
            self.0 |= flag;
        }
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for Status {
    /// The flag names, as in `Display`.
    fn format(&self, f: defmt::Formatter) {
        if self.is_ok() {
            defmt::write!(f, "ok");
        }
        let mut first = true;
        for (bit, name) in Self::NAMES {
            if self.has(bit) {
                if !first {
                    defmt::write!(f, "|");
                }
                defmt::write!(f, "{=str}", name);
                first = false;
            }
        }
    }
}

#[cfg(feature = "defmt")]
impl<T: Real> defmt::Format for FrameReport<T> {
    /// One line: frame, status, ICP figures, position and map occupancy.
    fn format(&self, f: defmt::Formatter) {
        let t = self.pose.translation.vector;
        defmt::write!(
            f,
            "frame {=u64} {} it={=u32} corr={=u32} sigma={=f64} t=({=f64}, {=f64}, {=f64}) map={=u32}/{=u32} dropped={}",
            self.index,
            self.status,
            self.iterations,
            self.correspondences,
            self.sigma.wide(),
            t.x.wide(),
            t.y.wide(),
            t.z.wide(),
            self.map_voxels,
            self.map_points,
            self.dropped
        );
    }
}

impl core::fmt::Display for Status {
    /// `ok`, or the set flags joined by `|` (e.g. `degenerate|capacity`).
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.is_ok() {
            return f.write_str("ok");
        }
        let mut first = true;
        for (bit, name) in Self::NAMES {
            if self.has(bit) {
                if !first {
                    f.write_str("|")?;
                }
                f.write_str(name)?;
                first = false;
            }
        }
        Ok(())
    }
}

/// Points and voxels dropped in one frame, by reason. Cropping by range is not a drop; it is
/// counted in [`FrameReport::out_of_range`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Dropped {
    /// Points with a NaN or infinite coordinate.
    pub non_finite: u32,
    /// Points past `Capacities::scan_points` (the first ones are kept).
    pub truncated: u32,
    /// New `alpha v` voxels once the merge cloud was full (first-seen voxels kept).
    pub merge_full: u32,
    /// New `beta v` voxels once the registration cloud was full (first-seen voxels kept).
    pub source_full: u32,
    /// New map voxels refused because the voxel table was full (existing voxels kept).
    pub map_voxels_full: u32,
    /// Map points refused because the block pool was empty (existing points kept).
    pub map_points_full: u32,
}

impl Dropped {
    /// Whether any capacity rule fired.
    pub fn capacity(&self) -> bool {
        self.merge_full + self.source_full + self.map_voxels_full + self.map_points_full > 0
    }
}

/// Largest occupancy seen since start, against capacity.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HighWater {
    /// Merge cloud points.
    pub merge_points: usize,
    /// Registration cloud points.
    pub source_points: usize,
    /// Map voxels.
    pub map_voxels: usize,
    /// Map point slots in use (whole blocks).
    pub map_point_slots: usize,
}

/// The result of registering one scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameReport<T: Real> {
    /// Frame number since start (skipped frames included).
    pub index: u64,
    /// Pose of the sensor at the end of the sweep, in the frame of the first scan.
    pub pose: Pose<T>,
    /// Ok, or how the frame was degraded.
    pub status: Status,
    /// Gauss-Newton iterations.
    pub iterations: u32,
    /// Correspondences in the last iteration.
    pub correspondences: u32,
    /// `sigma_t` used for this frame (threshold `3 sigma`, kernel `kernel_scale * sigma`).
    pub sigma: T,
    /// RMS residual of the last iteration's correspondences (m).
    pub rms: T,
    /// `delta(dT)` of this frame's model deviation (Eq. (5)).
    pub model_error: T,
    /// Weakest over strongest direction of the point-to-plane information sampled from map
    /// voxel normals (translation and rotation, the smaller); `None` on the first frame.
    pub observability: Option<T>,
    /// Points given.
    pub input_points: u32,
    /// Finite points outside the range shell.
    pub out_of_range: u32,
    /// Points in the merge cloud.
    pub merge_points: u32,
    /// Points in the registration cloud.
    pub source_points: u32,
    /// Voxels in the map after the update.
    pub map_voxels: u32,
    /// Points in the map after the update.
    pub map_points: u32,
    /// Voxels pruned for being beyond `r_max`.
    pub pruned_voxels: u32,
    /// What the capacity rules and input checks dropped.
    pub dropped: Dropped,
    /// Whether the scan was deskewed.
    pub deskewed: bool,
    /// Why timestamps were given but not used.
    pub stamp_problem: Option<StampProblem>,
}
