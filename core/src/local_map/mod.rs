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

mod codec;
mod search;

pub use codec::{Exact, PointCodec, Quantized};

use crate::config::BLOCK;
use crate::scalar::{sqrt_lt, Real};
use crate::voxel::{point_to_voxel, table_hash, VoxelKey};
use crate::{Point, Pose};
use core::marker::PhantomData;

const NONE: u32 = u32::MAX;

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

/// The voxel hash map of the paper, over caller-owned buffers.
pub struct LocalMap<'a, T: Real, P: PointCodec<T>> {
    voxel_size: T,
    max_distance: T,
    max_points: u32,
    resolution: T,
    keys: &'a mut [VoxelKey],
    heads: &'a mut [u32],
    counts: &'a mut [u8],
    points: &'a mut [P::Stored],
    links: &'a mut [u32],
    mask: usize,
    max_voxels: usize,
    free: u32,
    voxels: usize,
    blocks_used: usize,
    n_points: usize,
    high_voxels: usize,
    high_blocks: usize,
    _codec: PhantomData<P>,
}

/// The buffers a [`LocalMap`] lives in; table slices have a power-of-two length.
pub struct MapBuffers<'a, T: Real, P: PointCodec<T>> {
    /// Voxel keys, one per table slot.
    pub keys: &'a mut [VoxelKey],
    /// First block of each slot's chain.
    pub heads: &'a mut [u32],
    /// Points in each slot's voxel (0 marks an empty slot).
    pub counts: &'a mut [u8],
    /// The block pool: `BLOCK` stored points per block.
    pub points: &'a mut [P::Stored],
    /// Next block in a chain (or in the free list).
    pub links: &'a mut [u32],
}

impl<'a, T: Real, P: PointCodec<T>> LocalMap<'a, T, P> {
    /// An empty map. `max_voxels` is capped at 3/4 of the table slots. Returns `None` if the
    /// table length is not a power of two or the pool slices disagree.
    pub fn new(
        voxel_size: T,
        max_distance: T,
        max_points_per_voxel: u32,
        max_voxels: usize,
        buf: MapBuffers<'a, T, P>,
    ) -> Option<Self> {
        let slots = buf.keys.len();
        if !slots.is_power_of_two()
            || buf.heads.len() != slots
            || buf.counts.len() != slots
            || buf.points.len() != buf.links.len() * BLOCK
            || max_points_per_voxel == 0
            || max_points_per_voxel > 255
        {
            return None;
        }
        let resolution = (voxel_size * voxel_size / T::of(max_points_per_voxel as f64)).sqrt_l();
        let mut map = Self {
            voxel_size,
            max_distance,
            max_points: max_points_per_voxel,
            resolution,
            keys: buf.keys,
            heads: buf.heads,
            counts: buf.counts,
            points: buf.points,
            links: buf.links,
            mask: slots - 1,
            max_voxels: max_voxels.min(slots / 4 * 3),
            free: NONE,
            voxels: 0,
            blocks_used: 0,
            n_points: 0,
            high_voxels: 0,
            high_blocks: 0,
            _codec: PhantomData,
        };
        map.clear();
        Some(map)
    }

    /// Removes every voxel.
    pub fn clear(&mut self) {
        self.counts.fill(0);
        let n = self.links.len();
        for (i, l) in self.links.iter_mut().enumerate() {
            *l = if i + 1 < n { (i + 1) as u32 } else { NONE };
        }
        self.free = if n > 0 { 0 } else { NONE };
        self.voxels = 0;
        self.blocks_used = 0;
        self.n_points = 0;
    }

    /// Voxel size `v`.
    pub fn voxel_size(&self) -> T {
        self.voxel_size
    }
    /// Occupied voxels.
    pub fn voxels(&self) -> usize {
        self.voxels
    }
    /// Stored points.
    pub fn points(&self) -> usize {
        self.n_points
    }
    /// Whether the map holds no voxel.
    pub fn is_empty(&self) -> bool {
        self.voxels == 0
    }
    /// Most voxels ever held.
    pub fn high_water_voxels(&self) -> usize {
        self.high_voxels
    }
    /// Most point slots (blocks * BLOCK) ever in use.
    pub fn high_water_point_slots(&self) -> usize {
        self.high_blocks * BLOCK
    }
    /// Voxel capacity.
    pub fn voxel_capacity(&self) -> usize {
        self.max_voxels
    }
    /// Point slot capacity.
    pub fn point_capacity(&self) -> usize {
        self.links.len() * BLOCK
    }

    /// The slot holding `key`, or `None`. Probing stops at an empty slot; the load cap of 3/4
    /// guarantees one, and the probe count is bounded anyway, so a broken invariant gives a
    /// wrong answer that tests catch rather than an endless loop.
    #[inline]
    fn find(&self, key: &VoxelKey) -> Option<usize> {
        let mut i = table_hash(key) as usize & self.mask;
        for _ in 0..=self.mask {
            if self.counts[i] == 0 {
                return None;
            }
            if self.keys[i] == *key {
                return Some(i);
            }
            i = (i + 1) & self.mask;
        }
        None
    }

    /// Calls `f` on each point of the voxel in `slot`, in insertion order, until it returns
    /// `false`.
    #[inline]
    fn for_each_in(&self, slot: usize, mut f: impl FnMut(Point<T>) -> bool) {
        let key = self.keys[slot];
        let mut left = self.counts[slot] as usize;
        let mut b = self.heads[slot] as usize;
        while left > 0 {
            let base = b * BLOCK;
            let n = left.min(BLOCK);
            for s in &self.points[base..base + n] {
                if !f(P::decode(s, &key, self.voxel_size)) {
                    return;
                }
            }
            left -= n;
            b = self.links[b] as usize;
        }
    }

    fn alloc_block(&mut self) -> Option<u32> {
        let b = self.free;
        if b == NONE {
            return None;
        }
        self.free = self.links[b as usize];
        self.links[b as usize] = NONE;
        self.blocks_used += 1;
        self.high_blocks = self.high_blocks.max(self.blocks_used);
        Some(b)
    }

    /// Adds world-frame points in order with the reference's admission rule.
    pub fn add_points(&mut self, points: impl Iterator<Item = Point<T>>) -> UpdateStats {
        let mut st = UpdateStats::default();
        for p in points {
            self.add_point(&p, &mut st);
        }
        st
    }

    fn add_point(&mut self, p: &Point<T>, st: &mut UpdateStats) {
        let key = point_to_voxel(p, self.voxel_size);
        let mut i = table_hash(&key) as usize & self.mask;
        let mut probes = 0;
        while self.counts[i] != 0 {
            if self.keys[i] == key {
                return self.append(i, &key, p, st);
            }
            i = (i + 1) & self.mask;
            probes += 1;
            if probes > self.mask {
                // No empty slot (cannot happen below the 3/4 load cap): drop, never spin.
                st.dropped_voxels += 1;
                return;
            }
        }
        if self.voxels >= self.max_voxels {
            st.dropped_voxels += 1;
            return;
        }
        let Some(b) = self.alloc_block() else {
            st.dropped_points += 1;
            return;
        };
        self.keys[i] = key;
        self.heads[i] = b;
        self.counts[i] = 1;
        self.points[b as usize * BLOCK] = P::encode(p, &key, self.voxel_size);
        self.voxels += 1;
        self.high_voxels = self.high_voxels.max(self.voxels);
        self.n_points += 1;
        st.added += 1;
    }

    fn append(&mut self, slot: usize, key: &VoxelKey, p: &Point<T>, st: &mut UpdateStats) {
        let count = self.counts[slot] as usize;
        if count as u32 >= self.max_points {
            return;
        }
        let mut too_close = false;
        let res = self.resolution;
        self.for_each_in(slot, |q| {
            too_close = sqrt_lt((q - p).norm_squared(), res);
            !too_close
        });
        if too_close {
            return;
        }
        // Find the last block of the chain.
        let mut b = self.heads[slot];
        for _ in 0..(count - 1) / BLOCK {
            b = self.links[b as usize];
        }
        if count % BLOCK == 0 {
            let Some(nb) = self.alloc_block() else {
                st.dropped_points += 1;
                return;
            };
            self.links[b as usize] = nb;
            b = nb;
        }
        self.points[b as usize * BLOCK + count % BLOCK] = P::encode(p, key, self.voxel_size);
        self.counts[slot] += 1;
        self.n_points += 1;
        st.added += 1;
    }

    /// Removes voxels whose first point is at least `r_max` from `origin` (squared distances
    /// compared, as the reference does).
    pub fn remove_far_from(&mut self, origin: &Point<T>) -> usize {
        let max2 = self.max_distance * self.max_distance;
        let mut removed = 0;
        let mut i = 0;
        while i <= self.mask {
            // A removal shifts a later voxel into slot i: look at slot i again.
            while self.counts[i] != 0 {
                let key = self.keys[i];
                let first = P::decode(
                    &self.points[self.heads[i] as usize * BLOCK],
                    &key,
                    self.voxel_size,
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
        let mut left = self.counts[hole] as usize;
        let mut b = self.heads[hole];
        while left > 0 {
            let next = self.links[b as usize];
            self.links[b as usize] = self.free;
            self.free = b;
            self.blocks_used -= 1;
            left = left.saturating_sub(BLOCK);
            b = next;
        }
        self.n_points -= self.counts[hole] as usize;
        self.voxels -= 1;
        self.counts[hole] = 0;
        // Backward-shift deletion: pull later members of the probe run into the hole.
        let mut j = hole;
        loop {
            j = (j + 1) & self.mask;
            if self.counts[j] == 0 {
                return;
            }
            let home = table_hash(&self.keys[j]) as usize & self.mask;
            let stays = if hole <= j {
                hole < home && home <= j
            } else {
                hole < home || home <= j
            };
            if !stays {
                self.keys[hole] = self.keys[j];
                self.heads[hole] = self.heads[j];
                self.counts[hole] = self.counts[j];
                self.counts[j] = 0;
                hole = j;
            }
        }
    }

    /// The reference's `Update`: transforms the merge cloud `local` by `pose`, adds it, then
    /// prunes voxels beyond `r_max` from the pose's position.
    pub fn update(&mut self, local: &[[T; 3]], pose: &Pose<T>) -> UpdateStats {
        let mut st = self.add_points(local.iter().map(|p| pose * Point::from(*p)));
        st.pruned_voxels = self.remove_far_from(&Point::from(pose.translation.vector));
        st
    }

    /// Every stored point, voxel by voxel in table order.
    pub fn for_each_point(&self, mut f: impl FnMut(&VoxelKey, Point<T>)) {
        for slot in 0..=self.mask {
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

#[cfg(test)]
mod tests;
