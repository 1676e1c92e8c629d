//! The map update (Sec. III-C): points join with the reference's admission rule, voxels
//! beyond the radius are pruned.

use super::layout::MapBuffers;
use super::{MapLayout, MapState, MapView, PointCodec, UpdateStats, BLOCK, NONE};
use crate::error::ConfigError;
use crate::scalar::{sqrt_lt, Real};
use crate::voxel::{home_slot, next_slot, point_to_voxel, table_hash, VoxelKey};
use crate::{Point, Pose};

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
