//! Step 3 (Sec. III-C): the local map, a voxel hash map of points, and correspondence search.
//!
//! Voxels of size `v` hold at most `N_max` points each. A scan's merge cloud, registered into
//! the world frame, is added point by point with the reference's admission rule: a point is
//! skipped if its voxel is full or already holds a point closer than `sqrt(v^2 / N_max)`.
//! After each update, voxels whose first point is `r_max` or more from the sensor are removed.
//!
//! Storage is fixed: an open-addressing table of voxel keys (linear probing, load at most 3/4,
//! backward-shift deletion, so no tombstones accumulate over hours) and a pool of
//! [`BLOCK`]-point blocks chained per voxel, so a voxel holding 3 points costs one block, not
//! `N_max` slots. When the table or the pool is full, the new voxel or point is dropped and
//! counted; existing map content is never evicted to make room.
//!
//! The map is its bookkeeping ([`MapState`], a few words) plus five buffers in named regions
//! ([`MapLayout`]). [`MapView`] reads them (correspondence search, every point); the update
//! works on a mutable view. [`LocalMap`] owns (or borrows) storage for a map on its own; inside
//! [`crate::Odometry`] the regions are part of the pipeline's one storage.

mod codec;
mod search;

pub use codec::{Exact, PointCodec, Quantized};
pub use search::Nearest;

use crate::error::ConfigError;
use crate::scalar::{sqrt_lt, Real};
use crate::storage::{split_off, view, view_ref, words_for, Carver, Region, Storage};
use crate::voxel::{home_slot, next_slot, point_to_voxel, slots_for, table_hash, VoxelKey};
use crate::{Point, Pose};
use core::marker::PhantomData;

/// Points per map block; a voxel owns a chain of blocks, so memory follows the points a voxel
/// really holds instead of reserving `N_max` for each one.
pub const BLOCK: usize = 4;

const NONE: u32 = u32::MAX;

/// Where the map's buffers sit, in `u64` words: the voxel table (slots for `voxels` at load
/// <= 3/4) and the block pool (`points / BLOCK` blocks, rounded up).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MapLayout {
    /// Slots of the voxel table.
    pub slots: usize,
    /// Blocks in the point pool.
    pub blocks: usize,
    /// Voxel keys, 12 bytes a slot.
    pub keys: Region,
    /// First block of each slot's chain, 4 bytes a slot.
    pub heads: Region,
    /// Points in each slot's voxel (0: empty slot), 1 byte a slot.
    pub counts: Region,
    /// The block pool, `BLOCK` stored points a block.
    pub points: Region,
    /// Next block of each block's chain (or of the free list), 4 bytes a block.
    pub links: Region,
}

impl MapLayout {
    /// The layout for `voxels` voxels and `points` points of `stored_size` bytes each, placed at
    /// the carver's position.
    pub(crate) const fn carve(
        voxels: usize,
        points: usize,
        stored_size: usize,
        c: &mut Carver,
    ) -> Self {
        let slots = slots_for(voxels);
        let blocks = points.div_ceil(BLOCK);
        Self {
            slots,
            blocks,
            keys: c.take(words_for(slots * 12)),
            heads: c.take(words_for(slots * 4)),
            counts: c.take(words_for(slots)),
            points: c.take(words_for(blocks * BLOCK * stored_size)),
            links: c.take(words_for(blocks * 4)),
        }
    }

    /// The layout of a map on its own storage (regions from word 0).
    pub const fn new(voxels: usize, points: usize, stored_size: usize) -> Self {
        Self::carve(voxels, points, stored_size, &mut Carver::new())
    }

    /// Words from the first region's start to the last one's end.
    pub const fn words(&self) -> usize {
        self.links.end() - self.keys.start
    }

    /// The map's buffers in `words`, which start at the first region.
    fn split<'w, P: bytemuck::Pod>(
        &self,
        words: &'w mut [u64],
    ) -> Result<MapBuffers<'w, P>, ConfigError> {
        let (k, rest) = split_off(words, self.keys)?;
        let (h, rest) = split_off(rest, self.heads)?;
        let (c, rest) = split_off(rest, self.counts)?;
        let (p, rest) = split_off(rest, self.points)?;
        let (l, _) = split_off(rest, self.links)?;
        Ok(MapBuffers {
            keys: view(k, self.slots)?,
            heads: view(h, self.slots)?,
            counts: view(c, self.slots)?,
            points: view(p, self.blocks * BLOCK)?,
            links: view(l, self.blocks)?,
        })
    }

    /// Read-only [`Self::split`].
    fn split_ref<'w, P: bytemuck::Pod>(
        &self,
        words: &'w [u64],
    ) -> Result<MapSlices<'w, P>, ConfigError> {
        let at = |r: Region| words.get(r.start - self.keys.start..r.end() - self.keys.start);
        let short = ConfigError::ArenaTooSmall;
        Ok(MapSlices {
            keys: view_ref(at(self.keys).ok_or(short)?, self.slots)?,
            heads: view_ref(at(self.heads).ok_or(short)?, self.slots)?,
            counts: view_ref(at(self.counts).ok_or(short)?, self.slots)?,
            points: view_ref(at(self.points).ok_or(short)?, self.blocks * BLOCK)?,
            links: view_ref(at(self.links).ok_or(short)?, self.blocks)?,
        })
    }
}

/// The map's buffers, mutable.
pub(crate) struct MapBuffers<'a, S> {
    keys: &'a mut [VoxelKey],
    heads: &'a mut [u32],
    counts: &'a mut [u8],
    points: &'a mut [S],
    links: &'a mut [u32],
}

/// The map's buffers, read-only.
struct MapSlices<'a, S> {
    keys: &'a [VoxelKey],
    heads: &'a [u32],
    counts: &'a [u8],
    points: &'a [S],
    links: &'a [u32],
}

/// What one map update did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct UpdateStats {
    /// Points added.
    pub added: usize,
    /// New voxels refused because the voxel table was at capacity.
    pub dropped_voxels: usize,
    /// Points refused because the point pool had no free block.
    pub dropped_points: usize,
    /// Voxels removed for being beyond `r_max`.
    pub pruned_voxels: usize,
}

/// The map's parameters and bookkeeping: everything but the buffers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MapState<T> {
    voxel_size: T,
    max_distance: T,
    max_points: u32,
    resolution: T,
    slots: usize,
    blocks: usize,
    max_voxels: usize,
    free: u32,
    voxels: usize,
    blocks_used: usize,
    n_points: usize,
    high_voxels: usize,
    high_blocks: usize,
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

/// Read access to a local map: correspondence search and its points.
pub struct MapView<'a, T: Real, P: PointCodec<T>> {
    st: MapState<T>,
    keys: &'a [VoxelKey],
    heads: &'a [u32],
    counts: &'a [u8],
    points: &'a [P::Stored],
    links: &'a [u32],
}

/// Write access to a local map (the pipeline's update).
pub(crate) struct MapMut<'a, T: Real, P: PointCodec<T>> {
    st: &'a mut MapState<T>,
    buf: MapBuffers<'a, P::Stored>,
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
    fn for_each_in(&self, slot: usize, f: impl FnMut(Point<T>) -> bool) {
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
fn for_each_in<T: Real, P: PointCodec<T>>(
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

impl<'a, T: Real, P: PointCodec<T>> MapMut<'a, T, P> {
    /// Write access to the map whose buffers start at `words[0]`.
    pub(crate) fn of(
        st: &'a mut MapState<T>,
        layout: &MapLayout,
        words: &'a mut [u64],
    ) -> Result<Self, ConfigError> {
        Ok(Self {
            st,
            buf: layout.split(words)?,
        })
    }

    /// Read access to the same map.
    pub(crate) fn view(&self) -> MapView<'_, T, P> {
        MapView {
            st: *self.st,
            keys: self.buf.keys,
            heads: self.buf.heads,
            counts: self.buf.counts,
            points: self.buf.points,
            links: self.buf.links,
        }
    }

    /// Removes every voxel.
    pub(crate) fn clear(&mut self) {
        self.buf.counts.fill(0);
        let n = self.buf.links.len();
        for (i, l) in self.buf.links.iter_mut().enumerate() {
            *l = if i + 1 < n { (i + 1) as u32 } else { NONE };
        }
        self.st.free = if n > 0 { 0 } else { NONE };
        self.st.voxels = 0;
        self.st.blocks_used = 0;
        self.st.n_points = 0;
    }

    fn alloc_block(&mut self) -> Option<u32> {
        let b = self.st.free;
        if b == NONE {
            return None;
        }
        self.st.free = self.buf.links[b as usize];
        self.buf.links[b as usize] = NONE;
        self.st.blocks_used += 1;
        self.st.high_blocks = self.st.high_blocks.max(self.st.blocks_used);
        Some(b)
    }

    /// Adds world-frame points in order with the reference's admission rule.
    pub(crate) fn add_points(&mut self, points: impl Iterator<Item = Point<T>>) -> UpdateStats {
        let mut st = UpdateStats::default();
        for p in points {
            self.add_point(&p, &mut st);
        }
        st
    }

    fn add_point(&mut self, p: &Point<T>, st: &mut UpdateStats) {
        let key = point_to_voxel(p, self.st.voxel_size);
        let slots = self.st.slots;
        let mut i = home_slot(table_hash(&key), slots);
        let mut probes = 0;
        while self.buf.counts[i] != 0 {
            if self.buf.keys[i] == key {
                return self.append(i, &key, p, st);
            }
            i = next_slot(i, slots);
            probes += 1;
            if probes >= slots {
                // No empty slot (cannot happen below the 3/4 load cap): drop, never spin.
                st.dropped_voxels += 1;
                return;
            }
        }
        if self.st.voxels >= self.st.max_voxels {
            st.dropped_voxels += 1;
            return;
        }
        let Some(b) = self.alloc_block() else {
            st.dropped_points += 1;
            return;
        };
        self.buf.keys[i] = key;
        self.buf.heads[i] = b;
        self.buf.counts[i] = 1;
        self.buf.points[b as usize * BLOCK] = P::encode(p, &key, self.st.voxel_size);
        self.st.voxels += 1;
        self.st.high_voxels = self.st.high_voxels.max(self.st.voxels);
        self.st.n_points += 1;
        st.added += 1;
    }

    fn append(&mut self, slot: usize, key: &VoxelKey, p: &Point<T>, st: &mut UpdateStats) {
        let count = self.buf.counts[slot] as usize;
        if count as u32 >= self.st.max_points {
            return;
        }
        let mut too_close = false;
        let res = self.st.resolution;
        self.view().for_each_in(slot, |q| {
            too_close = sqrt_lt((q - p).norm_squared(), res);
            !too_close
        });
        if too_close {
            return;
        }
        // Find the last block of the chain.
        let mut b = self.buf.heads[slot];
        for _ in 0..(count - 1) / BLOCK {
            b = self.buf.links[b as usize];
        }
        if count % BLOCK == 0 {
            let Some(nb) = self.alloc_block() else {
                st.dropped_points += 1;
                return;
            };
            self.buf.links[b as usize] = nb;
            b = nb;
        }
        self.buf.points[b as usize * BLOCK + count % BLOCK] = P::encode(p, key, self.st.voxel_size);
        self.buf.counts[slot] += 1;
        self.st.n_points += 1;
        st.added += 1;
    }

    /// Removes voxels whose first point is at least `r_max` from `origin` (squared distances
    /// compared, as the reference does).
    pub(crate) fn remove_far_from(&mut self, origin: &Point<T>) -> usize {
        let max2 = self.st.max_distance * self.st.max_distance;
        let mut removed = 0;
        let mut i = 0;
        while i < self.st.slots {
            // A removal shifts a later voxel into slot i: look at slot i again.
            while self.buf.counts[i] != 0 {
                let key = self.buf.keys[i];
                let first = P::decode(
                    &self.buf.points[self.buf.heads[i] as usize * BLOCK],
                    &key,
                    self.st.voxel_size,
                );
                if (first - origin).norm_squared() >= max2 {
                    self.remove_slot(i);
                    removed += 1;
                } else {
                    break;
                }
            }
            i += 1;
        }
        removed
    }

    fn remove_slot(&mut self, mut hole: usize) {
        // Return the chain to the free list.
        let mut left = self.buf.counts[hole] as usize;
        let mut b = self.buf.heads[hole];
        while left > 0 {
            let next = self.buf.links[b as usize];
            self.buf.links[b as usize] = self.st.free;
            self.st.free = b;
            self.st.blocks_used -= 1;
            left = left.saturating_sub(BLOCK);
            b = next;
        }
        self.st.n_points -= self.buf.counts[hole] as usize;
        self.st.voxels -= 1;
        self.buf.counts[hole] = 0;
        // Backward-shift deletion: pull later members of the probe run into the hole.
        let slots = self.st.slots;
        let mut j = hole;
        loop {
            j = next_slot(j, slots);
            if self.buf.counts[j] == 0 {
                return;
            }
            let home = home_slot(table_hash(&self.buf.keys[j]), slots);
            let stays = if hole <= j {
                hole < home && home <= j
            } else {
                hole < home || home <= j
            };
            if !stays {
                self.buf.keys[hole] = self.buf.keys[j];
                self.buf.heads[hole] = self.buf.heads[j];
                self.buf.counts[hole] = self.buf.counts[j];
                self.buf.counts[j] = 0;
                hole = j;
            }
        }
    }

    /// The reference's `Update`: transforms the merge cloud `local` by `pose`, adds it, then
    /// prunes voxels beyond `r_max` from the pose's position.
    pub(crate) fn update(&mut self, local: &[[T; 3]], pose: &Pose<T>) -> UpdateStats {
        let mut st = self.add_points(local.iter().map(|p| pose * Point::from(*p)));
        st.pruned_voxels = self.remove_far_from(&Point::from(pose.translation.vector));
        st
    }
}

/// A local map on storage of its own (owned or borrowed), for using the map as a stage: the
/// cross-check, benches and bindings that mirror the reference's `VoxelHashMap`.
pub struct LocalMap<T: Real, P: PointCodec<T>, S: Storage> {
    state: MapState<T>,
    layout: MapLayout,
    storage: S,
    _codec: PhantomData<P>,
}

impl<T: Real, P: PointCodec<T>, S: Storage> LocalMap<T, P, S> {
    /// Words of storage for `voxels` voxels and `points` points.
    pub const fn words(voxels: usize, points: usize) -> usize {
        MapLayout::new(voxels, points, core::mem::size_of::<P::Stored>()).words()
    }

    /// An empty map with voxels of `voxel_size`, pruned beyond `max_distance`, holding at most
    /// `max_points_per_voxel` points per voxel (1..=255), `voxels` voxels and `points` points, in
    /// `storage` (at least [`Self::words`] words).
    pub fn new(
        voxel_size: T,
        max_distance: T,
        max_points_per_voxel: u32,
        voxels: usize,
        points: usize,
        mut storage: S,
    ) -> Result<Self, ConfigError> {
        let layout = MapLayout::new(voxels, points, core::mem::size_of::<P::Stored>());
        let mut state = MapState::new(
            voxel_size,
            max_distance,
            max_points_per_voxel,
            voxels,
            &layout,
        )
        .ok_or(ConfigError::PointsPerVoxel)?;
        MapMut::<T, P>::of(&mut state, &layout, storage.as_mut())?.clear();
        Ok(Self {
            state,
            layout,
            storage,
            _codec: PhantomData,
        })
    }

    /// Read access.
    pub fn view(&self) -> MapView<'_, T, P> {
        // `new` checked the storage's length; a storage whose length changed since reads as an
        // empty map rather than panicking.
        MapView::of(&self.state, &self.layout, self.storage.as_ref())
            .unwrap_or_else(|_| MapView::empty(&self.state))
    }

    fn with_mut<R: Default>(&mut self, f: impl FnOnce(&mut MapMut<'_, T, P>) -> R) -> R {
        match MapMut::of(&mut self.state, &self.layout, self.storage.as_mut()) {
            Ok(mut m) => f(&mut m),
            Err(_) => R::default(),
        }
    }

    /// Removes every voxel.
    pub fn clear(&mut self) {
        self.with_mut(|m| m.clear())
    }

    /// Adds world-frame points in order with the reference's admission rule.
    pub fn add_points(&mut self, points: impl Iterator<Item = Point<T>>) -> UpdateStats {
        self.with_mut(|m| m.add_points(points))
    }

    /// Removes voxels whose first point is at least `r_max` from `origin`.
    pub fn remove_far_from(&mut self, origin: &Point<T>) -> usize {
        self.with_mut(|m| m.remove_far_from(origin))
    }

    /// The reference's `Update`: adds `local` moved by `pose`, then prunes around the pose.
    pub fn update(&mut self, local: &[[T; 3]], pose: &Pose<T>) -> UpdateStats {
        self.with_mut(|m| m.update(local, pose))
    }

    /// The closest map point to `query` within `max_distance`, with its squared distance.
    pub fn closest_neighbor(&self, query: &Point<T>, max_distance: T) -> Option<(Point<T>, T)> {
        self.view().closest_neighbor(query, max_distance)
    }

    /// Occupied voxels.
    pub fn voxels(&self) -> usize {
        self.state.voxels
    }

    /// Stored points.
    pub fn points(&self) -> usize {
        self.state.n_points
    }
}

#[cfg(test)]
mod tests;
