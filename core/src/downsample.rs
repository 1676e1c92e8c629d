//! Step 2 (Sec. III-B): voxel downsampling keeping the first point of each voxel.
//!
//! The pipeline downsamples twice: the deskewed scan with voxels of `alpha v` gives the cloud
//! merged into the map, and that cloud with voxels of `beta v` gives the registration cloud.
//!
//! Which point is "first" in the second pass depends on the order of the first pass's output.
//! The reference emits its voxels in the bucket order of a `tsl::robin_map` (v1.4, power-of-two
//! buckets, `reserve(n)` so `2n` rounded up, max load 0.5, robin-hood insertion). We dedup with
//! our own table, then rebuild exactly that bucket order ([`reference_order`]) in scratch that
//! grows with the kept points only, so both passes keep the same points as the reference and
//! feed the map in the same order. That is what lets whole trajectories agree to rounding.

use crate::geometry::Point;
use crate::scalar::Real;
use crate::storage::{view, words_for};
use crate::voxel::{
    home_slot, next_slot, point_to_voxel, reference_hash, slots_for, table_hash, VoxelKey,
};

const EMPTY: u32 = u32::MAX;

/// Outcome of one downsampling pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Downsampled {
    /// Points kept (one per occupied voxel).
    pub kept: usize,
    /// Points whose voxel was new when the output was already full (rule: first-seen voxels
    /// win, later new voxels are dropped).
    pub dropped: usize,
}

/// Scratch slots of the dedup grid for an output of `capacity` points (load at most 3/4).
pub const fn grid_slots_for(capacity: usize) -> usize {
    slots_for(capacity)
}

/// Words of the grid's keys (12 bytes a slot) and of its indices (4 bytes a slot).
const fn grid_words(slots: usize) -> (usize, usize) {
    (words_for(slots * 12), words_for(slots * 4))
}

/// Scratch bytes [`reference_order`] needs for `points` points: two `u64` sort keys and a
/// `u32` permutation entry per point.
pub const fn reference_order_bytes(points: usize) -> usize {
    points * 20
}

/// Scratch `u64` words needed to downsample into an output of `capacity` points: the dedup
/// grid (12-byte key and 4-byte index per slot), then, in the same words, the reference-order
/// reconstruction.
pub const fn scratch_words_for(capacity: usize) -> usize {
    let (keys, vals) = grid_words(grid_slots_for(capacity));
    let order = words_for(reference_order_bytes(capacity));
    if keys + vals > order {
        keys + vals
    } else {
        order
    }
}

/// `u64` words of a cloud of `points` points of scalar `T`.
pub const fn cloud_words<T>(points: usize) -> usize {
    words_for(points * 3 * core::mem::size_of::<T>())
}

/// Streaming first-point-per-voxel filter writing kept points to `out` in first-seen order.
pub struct Dedup<'a, T> {
    keys: &'a mut [VoxelKey],
    vals: &'a mut [u32],
    out: &'a mut [[T; 3]],
    voxel: T,
    kept: usize,
    dropped: usize,
}

impl<'a, T: Real> Dedup<'a, T> {
    /// A filter for voxels of size `voxel` writing into `out`; `scratch` must hold
    /// [`scratch_words_for`]`(out.len())` words. Returns `None` if it does not.
    pub fn new(out: &'a mut [[T; 3]], scratch: &'a mut [u64], voxel: T) -> Option<Self> {
        let d = Self::resume(out, scratch, voxel, Downsampled::default())?;
        d.vals.fill(EMPTY);
        Some(d)
    }

    /// Continues a filter that was stopped with [`Self::finish`] after returning `so_far`, on
    /// the same `out` and `scratch` (untouched in between): a scan can arrive in pieces.
    pub fn resume(
        out: &'a mut [[T; 3]],
        scratch: &'a mut [u64],
        voxel: T,
        so_far: Downsampled,
    ) -> Option<Self> {
        let slots = grid_slots_for(out.len());
        if scratch.len() < scratch_words_for(out.len()) || so_far.kept > out.len() {
            return None;
        }
        let (kw, vw) = scratch.split_at_mut(grid_words(slots).0);
        let keys = view::<VoxelKey>(kw, slots).ok()?;
        let vals = view::<u32>(vw, slots).ok()?;
        Some(Self {
            keys,
            vals,
            out,
            voxel,
            kept: so_far.kept,
            dropped: so_far.dropped,
        })
    }

    /// Offers one point; it is kept if its voxel has not been seen yet.
    #[inline]
    pub fn push(&mut self, p: &Point<T>) {
        let key = point_to_voxel(p, self.voxel);
        let slots = self.vals.len();
        let mut i = home_slot(table_hash(&key), slots);
        loop {
            let v = self.vals[i];
            if v == EMPTY {
                if self.kept == self.out.len() {
                    self.dropped += 1;
                    return;
                }
                self.keys[i] = key;
                self.vals[i] = self.kept as u32;
                self.out[self.kept] = [p.x, p.y, p.z];
                self.kept += 1;
                return;
            }
            if self.keys[i] == key {
                return;
            }
            i = next_slot(i, slots);
        }
    }

    /// Counts so far.
    pub fn finish(self) -> Downsampled {
        Downsampled {
            kept: self.kept,
            dropped: self.dropped,
        }
    }
}

/// Bucket count of a `tsl::robin_map` after `reserve(n)`: `ceil(n / 0.5)` computed in `f32`,
/// rounded up to a power of two (0 for `n = 0`).
pub fn robin_bucket_count(n: usize) -> u64 {
    if n == 0 {
        return 0;
    }
    let count = libm::ceilf(n as f32 / 0.5f32) as u64;
    count.next_power_of_two()
}

/// Bits for the insertion index in packed sort keys (capacities stay below 2^30).
const J_BITS: u32 = 30;
const J_MASK: u64 = (1 << J_BITS) - 1;
const SLOT_EMPTY: u64 = u64::MAX;
const VISITED: u32 = 1 << 31;

/// Reorders `points` (one per voxel, in first-seen order) into the iteration order of the
/// reference's robin-hood table after inserting them in that order into a table reserved for
/// `n_input` points. `scratch` must hold [`reference_order_bytes`]`(points.len())` bytes.
///
/// Robin-hood hashing with linear probing keeps elements sorted by home bucket, cyclically;
/// the order *within* a run of equal homes depends on how elements were displaced, so each
/// cluster of consecutive buckets is replayed on its own (clusters never interact).
/// The reference's table would rehash if one probe exceeded 8192 buckets; that needs thousands
/// of colliding voxels and is not reproduced (the set of points is unaffected, only order).
pub fn reference_order<T: Real>(
    points: &mut [[T; 3]],
    voxel: T,
    n_input: usize,
    scratch: &mut [u64],
) -> bool {
    let m = points.len();
    if m < 2 {
        return true;
    }
    if scratch.len() < words_for(reference_order_bytes(m)) {
        return false;
    }
    let bc = robin_bucket_count(n_input.max(m));
    let mask = bc - 1;
    let (kw, rest) = scratch.split_at_mut(m);
    let (aw, pw) = rest.split_at_mut(m);
    let keys = kw;
    let seq = aw;
    let Ok(perm) = view::<u32>(pw, m) else {
        return false;
    };

    // Sort by (home bucket, insertion index).
    for (j, (k, p)) in keys.iter_mut().zip(points.iter()).enumerate() {
        let home = reference_hash(&point_to_voxel(&Point::from(*p), voxel)) as u64 & mask;
        *k = (home << 32) | j as u64;
    }
    keys.sort_unstable();
    let home_of = |k: u64| k >> 32;
    let j_of = |k: u64| k & 0xFFFF_FFFF;

    // Start the sequence at a cluster boundary: if the last cluster runs past the end of the
    // table it wraps into bucket 0, so begin at that cluster and lift the rest by `bc`.
    let mut start = 0;
    let mut pos = 0u64;
    let mut cluster_start = 0;
    for (i, &k) in keys.iter().enumerate() {
        let h = home_of(k);
        if i == 0 || h > pos {
            cluster_start = i;
            pos = h;
        } else {
            pos += 1;
        }
    }
    if pos >= bc {
        start = cluster_start;
    }
    for (i, slot) in seq.iter_mut().enumerate() {
        let src = (start + i) % m;
        let lift = if src < start { bc } else { 0 };
        *slot = ((home_of(keys[src]) + lift) << J_BITS) | j_of(keys[src]);
    }

    // Walk clusters along the sequence; replay each one's insertions in index order.
    let mut first_wrapped = m;
    let mut s = 0;
    while s < m {
        let mut e = s + 1;
        let mut p = seq[s] >> J_BITS;
        let p0 = p;
        while e < m && (seq[e] >> J_BITS) <= p + 1 {
            p += 1;
            e += 1;
        }
        if first_wrapped == m && p >= bc {
            first_wrapped = s + (bc.saturating_sub(p0)) as usize;
        }
        replay_cluster(&mut keys[s..e], &mut seq[s..e], &mut perm[s..e], p0);
        s = e;
    }

    // Bucket order is the sequence rotated to the first element past the table's end.
    let k0 = first_wrapped.min(m);
    let src_of = |perm: &[u32], i: usize| (perm[(k0 + i) % m] & !VISITED) as usize;
    for begin in 0..m {
        if perm[(k0 + begin) % m] & VISITED != 0 {
            continue;
        }
        let tmp = points[begin];
        let mut cur = begin;
        loop {
            let src = src_of(perm, cur);
            perm[(k0 + cur) % m] |= VISITED;
            if src == begin {
                points[cur] = tmp;
                break;
            }
            points[cur] = points[src];
            cur = src;
        }
    }
    true
}

/// Replays robin-hood insertion of one cluster whose first bucket is `p0` (in the lifted
/// coordinates of [`reference_order`]), writing insertion indices in bucket order to `out`.
fn replay_cluster(tmp: &mut [u64], seq: &mut [u64], out: &mut [u32], p0: u64) {
    let n = seq.len();
    for (t, &s) in tmp.iter_mut().zip(seq.iter()) {
        let local_home = (s >> J_BITS) - p0;
        *t = ((s & J_MASK) << 32) | local_home;
    }
    tmp.sort_unstable(); // insertion order
    let slots = seq;
    slots.fill(SLOT_EMPTY);
    let dist = |x: u64| x >> 32;
    for &t in tmp.iter() {
        let mut b = (t & 0xFFFF_FFFF) as usize;
        let mut cur = t >> 32; // j, with distance 0 in the high half
                               // Probe past elements at least as far from home as we are.
        while b < n && slots[b] != SLOT_EMPTY && dist(cur) <= dist(slots[b]) {
            b += 1;
            cur += 1 << 32;
        }
        // Place, displacing richer elements forward (robin hood).
        while b < n && slots[b] != SLOT_EMPTY {
            if dist(cur) > dist(slots[b]) {
                core::mem::swap(&mut cur, &mut slots[b]);
            }
            b += 1;
            cur += 1 << 32;
        }
        if b < n {
            slots[b] = cur;
        }
    }
    for (o, &s) in out.iter_mut().zip(slots.iter()) {
        *o = (s & 0xFFFF_FFFF) as u32;
    }
}

/// Stage API: downsamples `input` with voxels of size `voxel` into `out`, keeping the first
/// point of each voxel, in the reference's output order. `scratch` must hold
/// [`scratch_words_for`]`(out.len())` words.
pub fn voxel_downsample<T: Real>(
    input: &[[T; 3]],
    voxel: T,
    out: &mut [[T; 3]],
    scratch: &mut [u64],
) -> Option<Downsampled> {
    let res = first_per_voxel(input, voxel, out, scratch)?;
    if reference_order(&mut out[..res.kept], voxel, input.len(), scratch) {
        Some(res)
    } else {
        None
    }
}

/// The first point of `input` in each voxel of size `voxel`, into `out` in first-seen order;
/// `None` if `scratch` cannot hold the grid.
pub(crate) fn first_per_voxel<T: Real>(
    input: &[[T; 3]],
    voxel: T,
    out: &mut [[T; 3]],
    scratch: &mut [u64],
) -> Option<Downsampled> {
    let mut dedup = Dedup::new(out, scratch, voxel)?;
    for p in input {
        dedup.push(&Point::from(*p));
    }
    Some(dedup.finish())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::Rng;

    /// Full robin-hood table simulation, insertion by insertion (the slow, obvious model).
    fn brute_force(points: &[[f64; 3]], voxel: f64, n_input: usize, out: &mut [[f64; 3]]) -> usize {
        let bc = robin_bucket_count(n_input) as usize;
        let mut slots = [(0i64, usize::MAX, [0i32; 3]); 512];
        assert!(bc <= slots.len());
        for s in slots.iter_mut() {
            s.0 = -1;
        }
        for (i, p) in points.iter().enumerate() {
            let key = point_to_voxel(&Point::from(*p), voxel);
            let mut b = reference_hash(&key) as usize & (bc - 1);
            let mut d = 0i64;
            let mut found = false;
            while slots[b].0 >= 0 && d <= slots[b].0 {
                if slots[b].2 == key {
                    found = true;
                    break;
                }
                b = (b + 1) & (bc - 1);
                d += 1;
            }
            if found {
                continue;
            }
            let mut cur = (d, i, key);
            while slots[b].0 >= 0 {
                if cur.0 > slots[b].0 {
                    core::mem::swap(&mut cur, &mut slots[b]);
                }
                b = (b + 1) & (bc - 1);
                cur.0 += 1;
            }
            slots[b] = cur;
        }
        let mut n = 0;
        for s in slots[..bc].iter().filter(|s| s.0 >= 0) {
            out[n] = points[s.1];
            n += 1;
        }
        n
    }

    #[test]
    fn downsampling_matches_a_full_robin_hood_simulation() {
        // Small random sets force long clusters, equal homes and wrap-around at the table end.
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
        let mut scratch = [0u64; 4096];
        // Miri runs a slice of the trials (it is about a million times slower).
        let trials = if cfg!(miri) { 30 } else { 400 };
        for trial in 0..trials {
            let n = 1 + trial % 150;
            let mut pts = [[0.0f64; 3]; 150];
            for p in pts[..n].iter_mut() {
                *p = [
                    rng.next() * 8.0 - 4.0,
                    rng.next() * 8.0 - 4.0,
                    rng.next() * 2.0 - 1.0,
                ];
            }
            let mut ours = [[0.0f64; 3]; 150];
            let mut want = [[0.0f64; 3]; 150];
            let got = voxel_downsample(&pts[..n], 1.0, &mut ours, &mut scratch).unwrap();
            let nwant = brute_force(&pts[..n], 1.0, n, &mut want);
            assert_eq!(got.kept, nwant, "trial {trial}");
            assert_eq!(&ours[..nwant], &want[..nwant], "trial {trial}");
        }
    }

    #[test]
    fn keeps_exactly_the_first_point_of_each_voxel() {
        let pts = [
            [0.1, 0.1, 0.1],
            [0.2, 0.2, 0.2],  // same voxel as the first: dropped
            [1.5, 0.1, 0.1],  // new voxel
            [-0.1, 0.1, 0.1], // new voxel (floor(-0.1) = -1)
            [1.9, 0.9, 0.9],  // same voxel as the third: dropped
        ];
        let mut out = [[0.0f64; 3]; 8];
        let mut scratch = [0u64; 64];
        let r = voxel_downsample(&pts, 1.0, &mut out, &mut scratch).unwrap();
        assert_eq!(
            r,
            Downsampled {
                kept: 3,
                dropped: 0
            }
        );
        let mut kept = [out[0], out[1], out[2]];
        kept.sort_by(|a, b| a[0].partial_cmp(&b[0]).unwrap());
        assert_eq!(kept, [pts[3], pts[0], pts[2]]);
    }

    #[test]
    fn a_full_output_drops_later_new_voxels_and_counts_them() {
        let pts = [
            [0.5, 0.0, 0.0],
            [1.5, 0.0, 0.0],
            [2.5, 0.0, 0.0],
            [0.6, 0.0, 0.0],
        ];
        let mut out = [[0.0f64; 3]; 2];
        let mut scratch = [0u64; 64];
        let r = voxel_downsample(&pts, 1.0, &mut out, &mut scratch).unwrap();
        assert_eq!(
            r,
            Downsampled {
                kept: 2,
                dropped: 1
            }
        );
        assert!(out.contains(&pts[0]) && out.contains(&pts[1]));
    }
}
