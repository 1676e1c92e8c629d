//! Voxel indices and hashes shared by the downsampling grid and the local map.

use crate::geometry::Point;
use crate::scalar::Real;

/// Integer voxel coordinates `floor(p / v)`, as the reference computes them (a division, not a
/// multiplication by `1/v`, so boundary points fall in the same voxel).
pub type VoxelKey = [i32; 3];

/// The voxel holding `p` for voxel size `v`.
#[inline]
pub fn point_to_voxel<T: Real>(p: &Point<T>, v: T) -> VoxelKey {
    [
        (p.x / v).floor_i32(),
        (p.y / v).floor_i32(),
        (p.z / v).floor_i32(),
    ]
}

/// The reference's voxel hash (`x*73856093 ^ y*19349669 ^ z*83492791` on the bit patterns as
/// `u32`). Only used to reproduce the reference's output order; our own tables use
/// [`table_hash`].
#[inline]
pub fn reference_hash(k: &VoxelKey) -> u32 {
    (k[0] as u32).wrapping_mul(73_856_093)
        ^ (k[1] as u32).wrapping_mul(19_349_669)
        ^ (k[2] as u32).wrapping_mul(83_492_791)
}

/// Hash for our open-addressing tables: a multiply-xorshift mix of the three coordinates whose
/// high bits are well spread for neighbouring voxels (the reference hash's low bits are not).
#[inline]
pub fn table_hash(k: &VoxelKey) -> u32 {
    let mut h = (k[0] as u32).wrapping_mul(0x9E37_79B1);
    h ^= (k[1] as u32).wrapping_mul(0x85EB_CA77);
    h = h.rotate_left(13);
    h ^= (k[2] as u32).wrapping_mul(0xC2B2_AE3D);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2C1B_3C6D);
    h ^= h >> 12;
    h
}

/// Slots an open-addressing table needs for `n` entries at load at most 3/4 (at least one).
pub const fn slots_for(n: usize) -> usize {
    let s = (n * 4).div_ceil(3);
    if s == 0 {
        1
    } else {
        s
    }
}

/// The home slot of `hash` in a table of `slots` slots: the high bits of the hash scaled to the
/// table (a multiply, not a modulo), so a table needs no power-of-two size.
#[inline]
pub fn home_slot(hash: u32, slots: usize) -> usize {
    ((u64::from(hash) * slots as u64) >> 32) as usize
}

/// The slot after `i` in a table of `slots` slots (wrapping at the end).
#[inline]
pub fn next_slot(i: usize, slots: usize) -> usize {
    if i + 1 == slots {
        0
    } else {
        i + 1
    }
}

/// The 27 voxels searched for a nearest neighbour, in the reference's order (the centre first,
/// then faces, edges and corners). The order decides which of two equidistant points wins.
pub const NEIGHBOUR_SHIFTS: [[i32; 3]; 27] = [
    [0, 0, 0],
    [1, 0, 0],
    [-1, 0, 0],
    [0, 1, 0],
    [0, -1, 0],
    [0, 0, 1],
    [0, 0, -1],
    [1, 1, 0],
    [1, -1, 0],
    [-1, 1, 0],
    [-1, -1, 0],
    [1, 0, 1],
    [1, 0, -1],
    [-1, 0, 1],
    [-1, 0, -1],
    [0, 1, 1],
    [0, 1, -1],
    [0, -1, 1],
    [0, -1, -1],
    [1, 1, 1],
    [1, 1, -1],
    [1, -1, 1],
    [1, -1, -1],
    [-1, 1, 1],
    [-1, 1, -1],
    [-1, -1, 1],
    [-1, -1, -1],
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn voxel_index_is_floor_of_division() {
        let v = 0.5f64;
        assert_eq!(point_to_voxel(&Point::new(0.0, -0.0, 0.49), v), [0, 0, 0]);
        assert_eq!(
            point_to_voxel(&Point::new(-0.01, 1.0, -0.5), v),
            [-1, 2, -1]
        );
    }

    #[test]
    fn reference_hash_matches_hand_computed_values() {
        // 1*73856093 ^ 2*19349669 ^ 3*83492791 computed by hand in u32 arithmetic.
        assert_eq!(
            reference_hash(&[1, 2, 3]),
            73_856_093 ^ 38_699_338 ^ 250_478_373
        );
        // -1 is 0xFFFF_FFFF: the product wraps to the two's complement of the constant.
        assert_eq!(reference_hash(&[-1, 0, 0]), 0u32.wrapping_sub(73_856_093));
    }

    #[test]
    fn neighbour_shifts_cover_the_cube_once() {
        let mut seen = [false; 27];
        for s in NEIGHBOUR_SHIFTS {
            let i = ((s[0] + 1) * 9 + (s[1] + 1) * 3 + (s[2] + 1)) as usize;
            assert!(!seen[i]);
            seen[i] = true;
        }
        assert_eq!(NEIGHBOUR_SHIFTS[0], [0, 0, 0]);
    }
}
