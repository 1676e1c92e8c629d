//! Error enums: small, `Copy`, each variant saying what the caller should do.

/// A configuration or storage problem found when an [`crate::Odometry`] is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// `max_range` must be positive and at most [`crate::Config::MAX_RANGE_LIMIT`], and
    /// `0 <= min_range < max_range`: fix the ranges.
    Range,
    /// `voxel_size`, `alpha` and `beta` must be positive and finite.
    VoxelSize,
    /// `max_points_per_voxel` must be in `1..=255`.
    PointsPerVoxel,
    /// Threshold parameters must be finite, `initial_threshold`, `kernel_scale` and
    /// `max_correspondence_factor` positive, the others non-negative.
    Threshold,
    /// `convergence_criterion` must be finite and non-negative and `max_iterations` at least 1.
    Iterations,
    /// Every capacity must be non-zero (and below 2^30 points): pick capacities from
    /// [`crate::Capacities`]'s sizing rules.
    Capacity,
    /// The arena is shorter than [`crate::Capacities::arena_words`]: give it that many words.
    ArenaTooSmall,
    /// Robust mode needs [`crate::Capacities::plane_terms`]: set it (or use
    /// [`crate::Capacities::ROBUST`]).
    PlaneTerms,
    /// The capacities cannot hold what the odometry holds now (`Odometry::rehome`): give each
    /// at least [`crate::Odometry::room_needed`]'s.
    Holds,
}

/// Why a frame produced no pose. The odometry state is unchanged; the caller can drop the
/// frame, or call [`crate::Odometry::skip_frame`] to advance by the constant-velocity model
/// (what the reference does with an empty scan).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FrameError {
    /// No point survived the finite check and the range crop.
    EmptyScan,
    /// The storage no longer holds the layout the odometry was built with (its `AsMut` now
    /// gives fewer words than at construction). Nothing was changed; rebuild the odometry.
    Storage,
    /// A buffer would have dropped or evicted, and the odometry was told to refuse such a frame
    /// ([`crate::WhenFull::Refuse`]). Nothing was changed: move the odometry into storage of
    /// [`crate::Odometry::room_needed`]'s capacities ([`crate::Odometry::rehome`]) and register
    /// the frame again.
    Full,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let s = match self {
            Self::Range => "max_range must be in (0, 1e6] m and min_range in [0, max_range)",
            Self::VoxelSize => "voxel_size, alpha and beta must be positive",
            Self::PointsPerVoxel => "max_points_per_voxel must be in 1..=255",
            Self::Threshold => "threshold and kernel parameters out of range",
            Self::Iterations => "convergence_criterion must be >= 0 and max_iterations >= 1",
            Self::Capacity => "every capacity must be non-zero and below 2^30",
            Self::ArenaTooSmall => "arena shorter than Capacities::arena_words",
            Self::PlaneTerms => "robust mode needs Capacities::plane_terms",
            Self::Holds => "the capacities cannot hold what the odometry holds now",
        };
        f.write_str(s)
    }
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::EmptyScan => f.write_str("no finite point within [min_range, max_range)"),
            Self::Storage => f.write_str("the storage shrank below the odometry's layout"),
            Self::Full => f.write_str("a buffer is full and the odometry refuses such frames"),
        }
    }
}
