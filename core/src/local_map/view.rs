//! Read access to the map: voxel lookup and its points (the search is in `search`).

use super::codec::PointCodec;
use super::layout::MapLayout;
use super::layout::BLOCK;
use super::state::{MapState, NONE};
use crate::error::ConfigError;
use crate::geometry::Point;
use crate::scalar::Real;
use crate::voxel::{home_slot, next_slot, table_hash, VoxelKey};

/// Read access to a local map: correspondence search and its points.
pub struct MapView<'a, T: Real, P: PointCodec<T>> {
    pub(super) st: MapState<T>,
    pub(super) keys: &'a [VoxelKey],
    pub(super) heads: &'a [u32],
    pub(super) counts: &'a [u8],
    pub(super) points: &'a [P::Stored],
    pub(super) links: &'a [u32],
}

impl<'a, T: Real, P: PointCodec<T>> MapView<'a, T, P> {
    /// A view of the map whose buffers start at `words[0]`.
    pub(crate) fn of(
        st: &MapState<T>,
        layout: &MapLayout,
        words: &'a [u64],
    ) -> Result<Self, ConfigError> {
        let s = layout.split_ref::<P::Stored>(words)?;
        Ok(Self {
            st: *st,
            keys: s.keys,
            heads: s.heads,
            counts: s.counts,
            points: s.points,
            links: s.links,
        })
    }

    /// A view of no voxel at all, with `st`'s parameters: what a storage that no longer holds
    /// the layout reads as (instead of a panic).
    pub(crate) fn empty(st: &MapState<T>) -> Self {
        Self {
            st: MapState {
                slots: 1,
                voxels: 0,
                n_points: 0,
                ..*st
            },
            keys: &[[0; 3]],
            heads: &[0],
            counts: &[0],
            points: &[],
            links: &[],
        }
    }

    /// Voxel size `v`.
    pub fn voxel_size(&self) -> T {
        self.st.voxel_size
    }
    /// Occupied voxels.
    pub fn voxels(&self) -> usize {
        self.st.voxels
    }
    /// Stored points.
    pub fn points(&self) -> usize {
        self.st.n_points
    }
    /// Whether the map holds no voxel.
    pub fn is_empty(&self) -> bool {
        self.st.voxels == 0
    }
    /// Most voxels ever held.
    pub fn high_water_voxels(&self) -> usize {
        self.st.high_water_voxels()
    }
    /// Most point slots (blocks * BLOCK) ever in use.
    pub fn high_water_point_slots(&self) -> usize {
        self.st.high_water_point_slots()
    }
    /// Voxel capacity.
    pub fn voxel_capacity(&self) -> usize {
        self.st.max_voxels
    }
    /// The most work one search can do, in `Nearest::work` units: the query, 27 lookups and
    /// `N_max` points in each voxel.
    pub fn search_work_bound(&self) -> u32 {
        1 + 27 * (1 + self.st.max_points)
    }
    /// Point slot capacity.
    pub fn point_capacity(&self) -> usize {
        self.st.blocks * BLOCK
    }

    /// The slot holding `key`, or `None`. Probing stops at an empty slot; the load cap of 3/4
    /// guarantees one, and the probe count is bounded anyway, so a broken invariant gives a
    /// wrong answer that tests catch rather than an endless loop.
    #[inline]
    pub(crate) fn find(&self, key: &VoxelKey) -> Option<usize> {
        let slots = self.st.slots;
        let mut i = home_slot(table_hash(key), slots);
        for _ in 0..slots {
            if self.counts[i] == 0 {
                return None;
            }
            if self.keys[i] == *key {
                return Some(i);
            }
            i = next_slot(i, slots);
        }
        None
    }

    /// Calls `f` on each point of the voxel in `slot`, in insertion order, until it returns
    /// `false`.
    #[inline]
    pub(super) fn for_each_in(&self, slot: usize, f: impl FnMut(Point<T>) -> bool) {
        for_each_in::<T, P>(
            self.st.voxel_size,
            &self.keys[slot],
            self.counts[slot],
            self.heads[slot],
            self.points,
            self.links,
            f,
        );
    }

    /// Every stored point, voxel by voxel in table order.
    pub fn for_each_point(&self, mut f: impl FnMut(&VoxelKey, Point<T>)) {
        for slot in 0..self.st.slots {
            if self.counts[slot] != 0 {
                let key = self.keys[slot];
                self.for_each_in(slot, |p| {
                    f(&key, p);
                    true
                });
            }
        }
    }
}

/// Calls `f` on each of `count` points chained from block `head`, until it returns `false`.
#[inline]
pub(super) fn for_each_in<T: Real, P: PointCodec<T>>(
    v: T,
    key: &VoxelKey,
    count: u8,
    head: u32,
    points: &[P::Stored],
    links: &[u32],
    mut f: impl FnMut(Point<T>) -> bool,
) {
    let mut left = count as usize;
    let mut b = head as usize;
    while left > 0 {
        let base = b * BLOCK;
        let n = left.min(BLOCK);
        let Some(block) = points.get(base..base + n) else {
            return;
        };
        for s in block {
            if !f(P::decode(s, key, v)) {
                return;
            }
        }
        left -= n;
        b = links.get(b).copied().unwrap_or(NONE) as usize;
    }
}
