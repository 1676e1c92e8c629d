//! Room in a full map: the paper bounds the map by `r_max` (Sec. III-C), and a fixed arena adds a
//! second bound, so a full map gives up what a smaller `r_max` would: its farthest voxels.
//!
//! When an insertion finds the voxel table or the point pool full, [`MapMut::evict`] bins the
//! map's voxels (by their first point, as pruning measures them) and what the rest of the scan
//! still needs into shells around the sensor, picks the largest radius whose content fits in
//! [`EVICT_TO`] of both capacities, removes every voxel beyond it and shrinks the radius there:
//! the scan's points inside the new radius then fit, the ones beyond it are left out. One
//! eviction per update, two passes over the table and one over the rest of the scan.

use super::codec::PointCodec;
use super::layout::BLOCK;
use super::update::MapMut;
use crate::geometry::{Point, Pose};
use crate::scalar::Real;
use crate::storage::{view, words_for};
use crate::voxel::{home_slot, next_slot, point_to_voxel, table_hash, VoxelKey};

/// Shells of equal squared width inside the radius (so they are thinnest at the rim, where the
/// cut falls): at `r_max` 100 m the outermost is 0.8 m thick.
pub const RADIUS_BINS: usize = 64;

/// What eviction leaves of each capacity, the scan's own points included: 9/10, so the next
/// scans find room.
pub const EVICT_TO: (usize, usize) = (9, 10);

/// Which shell a squared distance falls in: `RADIUS_BINS` for the radius and beyond.
#[derive(Clone, Copy)]
struct Shelling<T> {
    limit2: T,
    per_bin: T,
}

impl<T: Real> Shelling<T> {
    fn new(limit2: T) -> Self {
        Self {
            limit2,
            per_bin: T::of(RADIUS_BINS as f64) / limit2,
        }
    }

    fn of(&self, d2: T) -> usize {
        if d2 >= self.limit2 {
            RADIUS_BINS
        } else {
            ((d2 * self.per_bin).floor_i32().max(0) as usize).min(RADIUS_BINS - 1)
        }
    }
}

/// Voxels and point blocks per shell.
struct Shells {
    voxels: [usize; RADIUS_BINS + 1],
    blocks: [usize; RADIUS_BINS + 1],
}

impl Shells {
    fn add(&mut self, shell: usize, voxels: usize, blocks: usize) {
        self.voxels[shell] += voxels;
        self.blocks[shell] += blocks;
    }

    /// The first shell to remove (shells `keep..` go) so that the rest holds at most `voxels`
    /// voxels and `blocks` blocks; the innermost shell always stays.
    fn keep(&self, voxels: usize, blocks: usize) -> usize {
        let mut kept_voxels: usize = self.voxels.iter().sum();
        let mut kept_blocks: usize = self.blocks.iter().sum();
        let mut keep = RADIUS_BINS + 1;
        while keep > 1 && (kept_voxels > voxels || kept_blocks > blocks) {
            keep -= 1;
            kept_voxels -= self.voxels[keep];
            kept_blocks -= self.blocks[keep];
        }
        keep
    }
}

/// Per scan voxel in the tally: the points that fall in it (saturating) and the innermost
/// shell among them. 0 marks an empty slot.
const COUNT_BITS: u32 = 8;
const COUNT_MASK: u32 = (1 << COUNT_BITS) - 1;

impl<T: Real, P: PointCodec<T>> MapMut<'_, T, P> {
    /// Makes room around the pose for `rest` (the scan's points not added yet, sensor frame),
    /// using `scratch` to tally their voxels (with too little scratch, every point counts as a
    /// voxel of its own: more is evicted, never less). Shrinks the radius and returns the
    /// voxels removed.
    pub(super) fn evict(&mut self, rest: &[[T; 3]], pose: &Pose<T>, scratch: &mut [u64]) -> usize {
        let origin = Point::from(pose.translation.vector);
        let shelling = Shelling::new(self.st.limit2);
        let mut shells = Shells {
            voxels: [0; RADIUS_BINS + 1],
            blocks: [0; RADIUS_BINS + 1],
        };
        for slot in 0..self.st.slots {
            let count = self.buf.counts[slot] as usize;
            if count != 0 {
                let shell = shelling.of(self.first_distance2(slot, &origin));
                shells.add(shell, 1, count.div_ceil(BLOCK));
            }
        }
        self.tally(rest, pose, &shelling, scratch, &mut shells);
        let (num, den) = EVICT_TO;
        let keep = shells.keep(self.st.max_voxels * num / den, self.st.blocks * num / den);
        if keep <= RADIUS_BINS {
            self.st.limit2 = shelling.limit2 * T::of(keep as f64) / T::of(RADIUS_BINS as f64);
        }
        self.remove_beyond(&origin, self.st.limit2)
    }

    /// Adds to `shells` what the points of `rest` inside the radius would need: for a voxel the
    /// map lacks (or holds farther out than the scan's nearest point in it, since eviction
    /// may remove it) a voxel and its blocks, otherwise the blocks its chain would grow by;
    /// both at the shell of the scan's nearest point in it.
    fn tally(
        &self,
        rest: &[[T; 3]],
        pose: &Pose<T>,
        shelling: &Shelling<T>,
        scratch: &mut [u64],
        shells: &mut Shells,
    ) {
        let origin = Point::from(pose.translation.vector);
        let v = self.st.voxel_size;
        let n_max = self.st.max_points as usize;
        // 12 bytes of key and 4 of tally a slot.
        let mut slots = scratch.len() * 8 / 16;
        while slots > 0 && words_for(slots * 12) + words_for(slots * 4) > scratch.len() {
            slots -= 1;
        }
        let (kw, vw) = scratch.split_at_mut(words_for(slots * 12));
        let (Ok(keys), Ok(tallies)) = (view::<VoxelKey>(kw, slots), view::<u32>(vw, slots)) else {
            return;
        };
        tallies.fill(0);
        for p in rest {
            let p = pose * Point::from(*p);
            let d2 = (p - origin).norm_squared();
            if d2 >= shelling.limit2 {
                continue; // beyond the radius already: never added
            }
            let shell = shelling.of(d2) as u32;
            let key = point_to_voxel(&p, v);
            let Some(i) = slot_of(keys, tallies, &key) else {
                shells.add(shell as usize, 1, 1); // no room to tally: its own voxel
                continue;
            };
            let t = tallies[i];
            tallies[i] = if t == 0 {
                keys[i] = key;
                (shell << COUNT_BITS) | 1
            } else {
                let count = ((t & COUNT_MASK) + 1).min(COUNT_MASK);
                ((t >> COUNT_BITS).min(shell) << COUNT_BITS) | count
            };
        }
        for (key, &t) in keys.iter().zip(tallies.iter()) {
            if t == 0 {
                continue;
            }
            let (new, shell) = (
                ((t & COUNT_MASK) as usize).min(n_max),
                (t >> COUNT_BITS) as usize,
            );
            let map = self.view();
            match map.find(key) {
                Some(slot) if shelling.of(self.first_distance2(slot, &origin)) <= shell => {
                    let old = self.buf.counts[slot] as usize;
                    let grow = (old + new).min(n_max).div_ceil(BLOCK) - old.div_ceil(BLOCK);
                    shells.add(shell, 0, grow);
                }
                _ => shells.add(shell, 1, new.div_ceil(BLOCK)),
            }
        }
    }
}

/// The slot of `key` in the tally table, or an empty one for it; `None` if the table has
/// neither.
fn slot_of(keys: &[VoxelKey], tallies: &[u32], key: &VoxelKey) -> Option<usize> {
    let slots = tallies.len();
    if slots == 0 {
        return None;
    }
    let mut i = home_slot(table_hash(key), slots);
    for _ in 0..slots {
        if tallies[i] == 0 || keys[i] == *key {
            return Some(i);
        }
        i = next_slot(i, slots);
    }
    None
}
