//! The map update (Sec. III-C): points join with the reference's admission rule, voxels
//! beyond the radius are pruned.

use super::codec::PointCodec;
use super::layout::MapBuffers;
use super::layout::MapLayout;
use super::layout::BLOCK;
use super::state::{MapCapacity, MapState, UpdateStats, NONE};
use super::view::MapView;
use crate::error::ConfigError;
use crate::geometry::{Point, Pose};
use crate::scalar::{sqrt_lt, Real};
use crate::voxel::{home_slot, next_slot, point_to_voxel, table_hash, VoxelKey};

/// Below this share of both capacities a shrunk radius grows back by [`GROW_STEP`] a scan.
pub const GROW_BELOW: (usize, usize) = (8, 10);

/// What a shrunk radius grows by a scan, as a share of `r_max`: 1/20 (BENCHMARKS.md compares
/// it with one voxel a scan, with no growth and with starting each scan at `r_max`).
pub const GROW_STEP: (usize, usize) = (1, 20);

/// Write access to a local map (the pipeline's update).
pub(crate) struct MapMut<'a, T: Real, P: PointCodec<T>> {
    pub(super) st: &'a mut MapState<T>,
    pub(super) buf: MapBuffers<'a, P::Stored>,
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
        self.st.limit2 = self.st.max_distance * self.st.max_distance;
    }

    pub(super) fn alloc_block(&mut self) -> Option<u32> {
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

    /// Adds world-frame points in order with the reference's admission rule; what does not fit
    /// is dropped and counted (this map has no pose to evict around: see [`Self::update`]).
    pub(crate) fn add_points(&mut self, points: impl Iterator<Item = Point<T>>) -> UpdateStats {
        let mut st = UpdateStats::default();
        for p in points {
            if let Err(full) = self.add_point(&p, &mut st) {
                st.count_drop(full);
            }
        }
        st
    }

    /// Adds `p` with the admission rule, or says which capacity refused it.
    fn add_point(&mut self, p: &Point<T>, st: &mut UpdateStats) -> Result<(), MapCapacity> {
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
                // No empty slot (cannot happen below the 3/4 load cap): refuse, never spin.
                return Err(MapCapacity::Voxels);
            }
        }
        if self.st.voxels >= self.st.max_voxels {
            return Err(MapCapacity::Voxels);
        }
        let b = self.alloc_block().ok_or(MapCapacity::Points)?;
        self.buf.keys[i] = key;
        self.buf.heads[i] = b;
        self.buf.counts[i] = 1;
        self.buf.points[b as usize * BLOCK] = P::encode(p, &key, self.st.voxel_size);
        self.st.voxels += 1;
        self.st.high_voxels = self.st.high_voxels.max(self.st.voxels);
        self.st.n_points += 1;
        st.added += 1;
        Ok(())
    }

    fn append(
        &mut self,
        slot: usize,
        key: &VoxelKey,
        p: &Point<T>,
        st: &mut UpdateStats,
    ) -> Result<(), MapCapacity> {
        let count = self.buf.counts[slot] as usize;
        if count as u32 >= self.st.max_points {
            return Ok(());
        }
        let mut too_close = false;
        let res = self.st.resolution;
        self.view().for_each_in(slot, |q| {
            too_close = sqrt_lt((q - p).norm_squared(), res);
            !too_close
        });
        if too_close {
            return Ok(());
        }
        // Find the last block of the chain.
        let mut b = self.buf.heads[slot];
        for _ in 0..(count - 1) / BLOCK {
            b = self.buf.links[b as usize];
        }
        if count % BLOCK == 0 {
            let nb = self.alloc_block().ok_or(MapCapacity::Points)?;
            self.buf.links[b as usize] = nb;
            b = nb;
        }
        self.buf.points[b as usize * BLOCK + count % BLOCK] = P::encode(p, key, self.st.voxel_size);
        self.buf.counts[slot] += 1;
        self.st.n_points += 1;
        st.added += 1;
        Ok(())
    }

    /// Removes voxels whose first point is at least `r_max` from `origin` (squared distances
    /// compared, as the reference does).
    pub(crate) fn remove_far_from(&mut self, origin: &Point<T>) -> usize {
        self.remove_beyond(origin, self.st.max_distance * self.st.max_distance)
    }

    /// The squared distance from `origin` of the first point of the voxel in `slot`, by which
    /// the map decides what is far.
    pub(super) fn first_distance2(&self, slot: usize, origin: &Point<T>) -> T {
        let first = P::decode(
            &self.buf.points[self.buf.heads[slot] as usize * BLOCK],
            &self.buf.keys[slot],
            self.st.voxel_size,
        );
        (first - origin).norm_squared()
    }

    /// Removes voxels whose first point's squared distance from `origin` is `limit2` or more.
    pub(super) fn remove_beyond(&mut self, origin: &Point<T>, limit2: T) -> usize {
        let mut removed = 0;
        let mut from = 0;
        while let Some(i) = next_occupied(self.buf.counts, from) {
            // A removal shifts a later voxel into slot i: look at slot i again.
            while self.buf.counts[i] != 0 {
                if self.first_distance2(i, origin) >= limit2 {
                    self.remove_slot(i);
                    removed += 1;
                } else {
                    break;
                }
            }
            from = i + 1;
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
    /// prunes voxels beyond the map's radius from the pose's position.
    ///
    /// The radius is `r_max` until the map fills. An insertion that finds the voxel table or
    /// the point pool full first evicts the farthest voxels around the pose, making room for
    /// the rest of the scan inside a smaller radius (`evict`, at most once per update, with
    /// `scratch` to tally the scan); the points of this and later scans beyond the radius are
    /// not added, as a smaller `r_max` would have cropped them. Only when the sensor's near
    /// field alone overfills the map does an insertion still fail: its point is dropped and
    /// counted. While the map stays below [`GROW_BELOW`] of both capacities, the radius grows
    /// back by [`GROW_STEP`] of `r_max` a scan.
    pub(crate) fn update(
        &mut self,
        local: &[[T; 3]],
        pose: &Pose<T>,
        scratch: &mut [u64],
    ) -> UpdateStats {
        let origin = Point::from(pose.translation.vector);
        let max2 = self.st.max_distance * self.st.max_distance;
        let mut st = UpdateStats::default();
        for (i, p) in local.iter().enumerate() {
            let p = pose * Point::from(*p);
            if self.st.limit2 < max2 && (p - origin).norm_squared() >= self.st.limit2 {
                st.beyond_radius += 1;
                continue;
            }
            let Err(full) = self.add_point(&p, &mut st) else {
                continue;
            };
            st.filled = st.filled.or(Some(full));
            if st.evicted {
                st.count_drop(full);
                continue;
            }
            st.evicted = true;
            st.evicted_voxels = self.evict(&local[i..], pose, scratch);
            if (p - origin).norm_squared() >= self.st.limit2 {
                st.beyond_radius += 1;
            } else if let Err(full) = self.add_point(&p, &mut st) {
                st.count_drop(full);
            }
        }
        st.pruned_voxels = self.remove_beyond(&origin, self.st.limit2);
        if !st.evicted && self.st.limit2 < max2 && self.below(GROW_BELOW) {
            let (num, den) = GROW_STEP;
            let step = self.st.max_distance * T::of(num as f64) / T::of(den as f64);
            let r = self.st.limit2.sqrt_l() + step;
            self.st.limit2 = (r * r).min(max2);
        }
        st
    }

    /// Whether both the voxels and the point blocks in use are below `share` of capacity.
    fn below(&self, (num, den): (usize, usize)) -> bool {
        self.st.voxels * den < self.st.max_voxels * num
            && self.st.blocks_used * den < self.st.blocks * num
    }
}

/// The first slot at or after `from` that holds a voxel. The table is sized for the map's
/// capacity and mostly empty, so empty slots are skipped eight at a time.
pub(super) fn next_occupied(counts: &[u8], from: usize) -> Option<usize> {
    let rest = counts.get(from..)?;
    let mut words = rest.chunks_exact(8);
    let mut at = from;
    for word in &mut words {
        let word = u64::from_le_bytes(word.try_into().ok()?);
        if word != 0 {
            return Some(at + (word.trailing_zeros() / 8) as usize);
        }
        at += 8;
    }
    let tail = words.remainder();
    tail.iter().position(|&c| c != 0).map(|k| at + k)
}
