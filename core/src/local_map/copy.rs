//! A map copied into a table and pool of another size: what moving the odometry into larger
//! storage does to the map (see `Odometry::rehome`).
//!
//! Nothing the pipeline computes depends on where the table keeps a voxel or which pool block
//! holds a point: search, admission and pruning reach voxels by key and a voxel's points in
//! insertion order. So a copy that keeps each voxel's key and points in order, at positions of
//! the new table's own probing, answers every later query as the original would have.

use super::codec::PointCodec;
use super::layout::BLOCK;
use super::state::MapState;
use super::update::{next_occupied, MapMut};
use super::view::MapView;
use crate::scalar::Real;
use crate::voxel::{home_slot, next_slot, table_hash};

impl<T: Real, P: PointCodec<T>> MapMut<'_, T, P> {
    /// Replaces this map's content with `src`'s: every voxel with its points in order, the
    /// radius in force and the high-water marks. `false` (and an empty map) if they do not fit.
    pub(crate) fn copy_from(&mut self, src: &MapView<'_, T, P>) -> bool {
        self.clear();
        if src.st.voxels > self.st.max_voxels || src.st.blocks_used > self.st.blocks {
            return false;
        }
        let mut from = 0;
        while let Some(s) = next_occupied(src.counts, from) {
            from = s + 1;
            if !self.copy_voxel(src, s) {
                self.clear();
                return false;
            }
        }
        self.st.limit2 = src.st.limit2;
        self.st.high_voxels = self.st.high_voxels.max(src.st.high_voxels);
        self.st.high_blocks = self.st.high_blocks.max(src.st.high_blocks);
        true
    }

    /// Copies `src`'s voxel in slot `s` into an empty slot of this table: its key, its count
    /// and its chain of blocks, point for point as stored.
    fn copy_voxel(&mut self, src: &MapView<'_, T, P>, s: usize) -> bool {
        let key = src.keys[s];
        let slots = self.st.slots;
        let mut i = home_slot(table_hash(&key), slots);
        let mut probes = 0;
        while self.buf.counts[i] != 0 {
            i = next_slot(i, slots);
            probes += 1;
            if probes >= slots {
                return false;
            }
        }
        let count = src.counts[s];
        let mut left = count as usize;
        let mut from_block = src.heads[s] as usize;
        let mut last: Option<u32> = None;
        while left > 0 {
            let Some(b) = self.alloc_block() else {
                return false;
            };
            match last {
                None => self.buf.heads[i] = b,
                Some(prev) => self.buf.links[prev as usize] = b,
            }
            let n = left.min(BLOCK);
            let (at, to) = (from_block * BLOCK, b as usize * BLOCK);
            let (Some(pts), Some(dst)) = (
                src.points.get(at..at + n),
                self.buf.points.get_mut(to..to + n),
            ) else {
                return false;
            };
            dst.copy_from_slice(pts);
            left -= n;
            last = Some(b);
            from_block = src.links.get(from_block).copied().unwrap_or(u32::MAX) as usize;
        }
        self.buf.keys[i] = key;
        self.buf.counts[i] = count;
        self.st.voxels += 1;
        self.st.n_points += count as usize;
        true
    }
}

impl<T: Real> MapState<T> {
    /// `self`'s parameters over a table and pool of `layout`'s sizes, empty.
    pub(crate) fn resized(&self, voxels: usize, layout: &super::MapLayout) -> Option<Self> {
        Self::new(
            self.voxel_size,
            self.max_distance,
            self.max_points,
            voxels,
            layout,
        )
    }
}
