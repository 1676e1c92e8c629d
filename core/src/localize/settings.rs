//! What a localizer is built with: the rules of its judgement, its capacities, and why it can
//! refuse to be built.

use crate::config::Config;
use crate::scalar::Real;

/// The rules of the judgement and the tiles' reach.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings<T: Real> {
    /// Tiles within this of the pose are held (m); `r_max` by default.
    pub reach: T,
    /// A registered point within this of a map point is an inlier (m); half a voxel.
    pub inlier_distance: T,
    /// Inlier share of a good registration (0.5).
    pub good_share: T,
    /// Inlier share of a fair registration (0.3).
    pub fair_share: T,
    /// Conditioning of a good registration: the observability ratio's floor (0.02, the
    /// odometry's `degeneracy_ratio`).
    pub min_observability: T,
    /// The registration's gate never below this (m): 3 voxels.
    pub gate_floor: T,
    /// Good frames that confirm a fix from the search or the start (3); as many frames
    /// without a good registration lose a pose never confirmed.
    pub confirm_frames: u32,
    /// Travel without a fix after which the state is lost (m): 50, where an odometry that
    /// drifts 2 % of the distance (twice KISS-ICP's on KITTI) is 1 m off.
    pub lost_after_m: T,
    /// Frames without a fix after which the state is lost: 600 (a minute at 10 Hz).
    pub lost_after_frames: u32,
    /// Starts of the search registered per frame (16: the grid in 22 frames).
    pub search_per_frame: u32,
    /// The search's answer must beat any distinct one by this share (0.1).
    pub search_margin: T,
}

impl<T: Real> Settings<T> {
    /// The defaults for an odometry configured with `config`.
    pub fn for_config(config: &Config<T>) -> Self {
        Self {
            reach: config.max_range,
            inlier_distance: config.voxel_size * T::of(0.5),
            good_share: T::of(0.5),
            fair_share: T::of(0.3),
            min_observability: config.degeneracy_ratio,
            gate_floor: config.voxel_size * T::of(3.0),
            confirm_frames: 3,
            lost_after_m: T::of(50.0),
            lost_after_frames: 600,
            search_per_frame: 16,
            search_margin: T::of(0.1),
        }
    }
}

/// The localizer's room: what [`Localizer::words`](super::Localizer::words) sizes. The prior
/// map takes none: its tiles are read in place.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PriorCapacities {
    /// Points of `P^*` registered (more are not used).
    pub source_points: usize,
}

/// Why a localizer cannot be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LocalizeError {
    /// The map's voxel size is not the configuration's: build the map at the configuration's,
    /// or configure the map's.
    VoxelSize,
    /// The map is in another frame than the one asked for.
    Frame,
    /// The tiles within reach can number more than
    /// [`MAX_TILES_HELD`](super::MAX_TILES_HELD): build the map with larger tiles (or a
    /// smaller reach).
    TileSize,
    /// A capacity is zero or the storage is shorter than
    /// [`Localizer::words`](super::Localizer::words).
    Storage,
    /// A setting is out of range (a share outside `0..=1`, a distance not positive).
    Settings,
}

impl core::fmt::Display for LocalizeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::VoxelSize => "the map's voxel size differs from the configuration's",
            Self::Frame => "the map is in another frame than the one asked for",
            Self::TileSize => "the map's tiles are too small for the reach (too many to hold)",
            Self::Storage => "a capacity is zero or the storage is too short",
            Self::Settings => "a localization setting is out of range",
        })
    }
}
