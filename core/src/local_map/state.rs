//! The map's bookkeeping: its parameters, fill and high-water marks ([`MapState`]), what an
//! update did ([`UpdateStats`]) and which capacity filled ([`MapCapacity`]).

use super::layout::{MapLayout, BLOCK};
use crate::scalar::Real;

pub(super) const NONE: u32 = u32::MAX;

/// One of the map's two capacities: what filled when an insertion found no room.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MapCapacity {
    /// The voxel table (`Capacities::map_voxels`).
    Voxels,
    /// The point pool (`Capacities::map_points`).
    Points,
}

impl MapCapacity {
    /// The capacity's name, as `Capacities` calls it.
    pub const fn name(self) -> &'static str {
        match self {
            MapCapacity::Voxels => "map_voxels",
            MapCapacity::Points => "map_points",
        }
    }
}

/// What one map update did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct UpdateStats {
    /// Points added.
    pub added: usize,
    /// New voxels refused because the voxel table was at capacity (even after eviction).
    pub dropped_voxels: usize,
    /// Points refused because the point pool had no free block (even after eviction).
    pub dropped_points: usize,
    /// Voxels removed for being beyond the map's radius after the update.
    pub pruned_voxels: usize,
    /// The capacity an insertion first found full, if any did.
    pub filled: Option<MapCapacity>,
    /// Whether the update evicted (at most once per update).
    pub evicted: bool,
    /// Voxels evicted to make room, farthest first.
    pub evicted_voxels: usize,
    /// Points not added because they lay beyond a radius shrunk below `r_max`.
    pub beyond_radius: usize,
}

impl UpdateStats {
    /// Counts a point refused by `full`.
    pub(super) fn count_drop(&mut self, full: MapCapacity) {
        match full {
            MapCapacity::Voxels => self.dropped_voxels += 1,
            MapCapacity::Points => self.dropped_points += 1,
        }
    }
}

/// The map's parameters and bookkeeping: everything but the buffers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MapState<T> {
    pub(super) voxel_size: T,
    pub(super) max_distance: T,
    pub(super) max_points: u32,
    pub(super) resolution: T,
    pub(super) slots: usize,
    pub(super) blocks: usize,
    pub(super) max_voxels: usize,
    pub(super) free: u32,
    pub(super) voxels: usize,
    pub(super) blocks_used: usize,
    pub(super) n_points: usize,
    pub(super) high_voxels: usize,
    pub(super) high_blocks: usize,
    /// The squared radius in force: `max_distance^2` until the map fills (see `update`).
    pub(super) limit2: T,
}

impl<T: Real> MapState<T> {
    /// An empty map of `layout`'s size; `max_voxels` is capped at 3/4 of the table slots.
    /// `None` if `max_points_per_voxel` is not in `1..=255`.
    pub(crate) fn new(
        voxel_size: T,
        max_distance: T,
        max_points_per_voxel: u32,
        max_voxels: usize,
        layout: &MapLayout,
    ) -> Option<Self> {
        if max_points_per_voxel == 0 || max_points_per_voxel > 255 || layout.slots == 0 {
            return None;
        }
        Some(Self {
            voxel_size,
            max_distance,
            max_points: max_points_per_voxel,
            resolution: (voxel_size * voxel_size / T::of(max_points_per_voxel as f64)).sqrt_l(),
            slots: layout.slots,
            blocks: layout.blocks,
            max_voxels: max_voxels.min(layout.slots * 3 / 4),
            free: NONE,
            voxels: 0,
            blocks_used: 0,
            n_points: 0,
            high_voxels: 0,
            high_blocks: 0,
            limit2: max_distance * max_distance,
        })
    }

    /// Occupied voxels.
    pub(crate) fn voxels(&self) -> usize {
        self.voxels
    }

    /// Stored points.
    pub(crate) fn points(&self) -> usize {
        self.n_points
    }

    /// The radius in force: `r_max`, or less after the map filled (see [`MapMut::update`]).
    pub(crate) fn radius(&self) -> T {
        if self.limit2 < self.max_distance * self.max_distance {
            self.limit2.sqrt_l()
        } else {
            self.max_distance
        }
    }

    /// Point blocks in use.
    pub(crate) fn blocks_in_use(&self) -> usize {
        self.blocks_used
    }

    /// Most voxels ever held.
    pub(crate) fn high_water_voxels(&self) -> usize {
        self.high_voxels
    }

    /// Most point slots (blocks * BLOCK) ever in use.
    pub(crate) fn high_water_point_slots(&self) -> usize {
        self.high_blocks * BLOCK
    }

    /// Forgets the high-water marks (a reset odometry starts afresh).
    pub(crate) fn reset_high_water(&mut self) {
        self.high_voxels = 0;
        self.high_blocks = 0;
    }
}
