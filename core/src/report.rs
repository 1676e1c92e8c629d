//! What each frame returns: the pose, how registration went, what the buffers hold and what
//! they dropped.

use crate::deskew::StampProblem;
use crate::geometry::Pose;
use crate::local_map::MapCapacity;
use crate::scalar::Real;

/// One way a frame was degraded; a [`Status`] holds any set of them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u16)]
pub enum Flag {
    /// Timestamps were given but unusable (see [`FrameReport::stamp_problem`]); the scan was
    /// registered without deskewing.
    TimestampsIgnored = 1 << 0,
    /// ICP stopped at the iteration cap before converging.
    IterationCap = 1 << 1,
    /// No correspondence within the threshold: the pose is the constant-velocity prediction.
    NoCorrespondences = 1 << 2,
    /// A normal-equation system could not be solved (too few correspondences).
    Singular = 1 << 3,
    /// The scene constrains some direction weakly (corridor, open plane), or no structure was
    /// measured at all: the pose along it mostly follows the prediction. See
    /// [`FrameReport::observability`].
    Degenerate = 1 << 4,
    /// Points with NaN or infinite coordinates were skipped.
    InvalidPoints = 1 << 5,
    /// The scan had more points than `Capacities::scan_points`; the rest were ignored.
    ScanTruncated = 1 << 6,
    /// A downsampled cloud or the map was full and dropped content (see [`Dropped`]).
    Capacity = 1 << 7,
    /// ICP stopped at the frame's work budget (`Config::work_budget`) with its last complete
    /// iterate.
    Budget = 1 << 8,
    // Bit 9 is not assigned: a status logged as bits (the embedded receiver's datagrams)
    // keeps the meaning of every other bit.
    /// Robust mode registered the scan with point-to-plane terms where the map is planar: the
    /// reference registration found it degenerate (see `Robust::plane_gate`).
    Planes = 1 << 10,
    /// The map was full: its farthest voxels were evicted to make room, which may have shrunk
    /// its radius below `r_max` (see [`FrameReport::map_radius`] and
    /// [`FrameReport::map_filled`]).
    Evicted = 1 << 11,
    /// Robust mode's registration cloud lay on one plane, which measures nothing along it: the
    /// scan was not registered, its pose is the constant-velocity prediction.
    OnePlane = 1 << 12,
}

impl Flag {
    /// Every flag, in bit order.
    pub const ALL: [Flag; 12] = [
        Flag::TimestampsIgnored,
        Flag::IterationCap,
        Flag::NoCorrespondences,
        Flag::Singular,
        Flag::Degenerate,
        Flag::InvalidPoints,
        Flag::ScanTruncated,
        Flag::Capacity,
        Flag::Budget,
        Flag::Planes,
        Flag::Evicted,
        Flag::OnePlane,
    ];

    /// The flag's name in reports and `frames.csv` (`snake_case`).
    pub const fn name(self) -> &'static str {
        match self {
            Flag::TimestampsIgnored => "timestamps_ignored",
            Flag::IterationCap => "iteration_cap",
            Flag::NoCorrespondences => "no_correspondences",
            Flag::Singular => "singular",
            Flag::Degenerate => "degenerate",
            Flag::InvalidPoints => "invalid_points",
            Flag::ScanTruncated => "scan_truncated",
            Flag::Capacity => "capacity",
            Flag::Budget => "budget",
            Flag::Planes => "planes",
            Flag::Evicted => "evicted",
            Flag::OnePlane => "one_plane",
        }
    }

    /// The flag called `name`, if any.
    pub fn from_name(name: &str) -> Option<Flag> {
        Flag::ALL.into_iter().find(|f| f.name() == name)
    }
}

/// A frame's status: a set of [`Flag`]s; empty means ok.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Status(u16);

impl Status {
    /// No flag set.
    pub const OK: Status = Status(0);

    /// Whether no flag is set.
    pub const fn is_ok(self) -> bool {
        self.0 == 0
    }
    /// Whether `flag` is set.
    pub const fn contains(self, flag: Flag) -> bool {
        self.0 & flag as u16 != 0
    }
    /// Sets `flag` when `on`, clears it otherwise.
    pub fn set(&mut self, flag: Flag, on: bool) {
        if on {
            self.0 |= flag as u16;
        } else {
            self.0 &= !(flag as u16);
        }
    }
    /// This status with `flag` set.
    pub const fn with(self, flag: Flag) -> Status {
        Status(self.0 | flag as u16)
    }
    /// The set flags, in bit order.
    pub fn flags(self) -> impl Iterator<Item = Flag> {
        Flag::ALL.into_iter().filter(move |f| self.contains(*f))
    }
    /// The flags as bits (`Flag as u16` each), e.g. for a compact log.
    pub const fn bits(self) -> u16 {
        self.0
    }
}

impl FromIterator<Flag> for Status {
    fn from_iter<I: IntoIterator<Item = Flag>>(iter: I) -> Self {
        let mut s = Status::OK;
        for f in iter {
            s.set(f, true);
        }
        s
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for Status {
    /// The flag names, as in `Display`.
    fn format(&self, f: defmt::Formatter) {
        if self.is_ok() {
            defmt::write!(f, "ok");
        }
        for (i, flag) in self.flags().enumerate() {
            if i > 0 {
                defmt::write!(f, "|");
            }
            defmt::write!(f, "{=str}", flag.name());
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
        for (i, flag) in self.flags().enumerate() {
            if i > 0 {
                f.write_str("|")?;
            }
            f.write_str(flag.name())?;
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
    /// New map voxels refused because the voxel table was still full after eviction (the
    /// scan's nearest points kept, see [`FrameReport::map_radius`]).
    pub map_voxels_full: u32,
    /// Map points refused because the block pool was still empty after eviction.
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
    /// Gauss-Newton iterations completed (on the first registration against the map, with
    /// those of its start on the thinned cloud: see `Config::desired_source_points`).
    pub iterations: u32,
    /// ICP's work in units: one per correspondence query, plus one per voxel looked up and per
    /// map point compared when the query searched the map (a query that kept its last answer
    /// costs one), counted as `iterations` are. Never above `Config::work_budget`.
    pub work: u64,
    /// Correspondences in the last iteration.
    pub correspondences: u32,
    /// Of those, the point-to-plane ones (robust mode's plane terms; 0 in a registration
    /// without them).
    pub plane_correspondences: u32,
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
    /// Voxels pruned for being beyond the map's radius.
    pub pruned_voxels: u32,
    /// The map's radius after the update: `r_max`, or less once the map has filled and given
    /// up its farthest voxels (it grows back, `r_max / 20` a frame, while the map has room).
    pub map_radius: T,
    /// The map capacity an insertion found full in this frame, if any (the frame is then
    /// flagged [`Flag::Evicted`]).
    pub map_filled: Option<MapCapacity>,
    /// Voxels evicted, farthest first, to make room in this frame.
    pub evicted_voxels: u32,
    /// What the capacity rules and input checks dropped.
    pub dropped: Dropped,
    /// Whether the scan was deskewed.
    pub deskewed: bool,
    /// Whether it was deskewed a second time, with the motion its first registration found,
    /// and registered again ([`crate::Config::redeskew`]).
    pub redeskewed: bool,
    /// Why timestamps were given but not used.
    pub stamp_problem: Option<StampProblem>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_sets_and_clears_named_flags() {
        let mut s = Status::OK;
        assert!(s.is_ok());
        s.set(Flag::Degenerate, true);
        s.set(Flag::Capacity, true);
        assert!(s.contains(Flag::Degenerate) && s.contains(Flag::Capacity));
        assert!(!s.contains(Flag::Singular));
        s.set(Flag::Degenerate, false);
        assert_eq!(s.flags().count(), 1);
        assert_eq!(s.flags().next(), Some(Flag::Capacity));
        assert_eq!(s, Status::OK.with(Flag::Capacity));
        s.set(Flag::Capacity, false);
        assert!(s.is_ok());
    }

    #[test]
    fn flag_names_round_trip_and_flags_are_single_bits_in_order() {
        let mut bits = 0u16;
        for f in Flag::ALL {
            assert_eq!(Flag::from_name(f.name()), Some(f));
            let bit = f as u16;
            assert!(bit.is_power_of_two() && bit > bits, "{f:?}");
            bits |= bit;
        }
        assert_eq!(Flag::from_name("fine"), None);
        let all: Status = Flag::ALL.into_iter().collect();
        assert_eq!(all.bits(), bits);
        assert_eq!(all.flags().count(), Flag::ALL.len());
        // The bits a logged status was written with keep their names.
        assert_eq!(
            (Flag::Planes as u16, Flag::Evicted as u16),
            (1 << 10, 1 << 11)
        );
    }
}
