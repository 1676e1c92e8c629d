//! How map points are stored: exactly, or as quantised offsets inside their voxel.

use crate::geometry::Point;
use crate::scalar::Real;
use crate::voxel::VoxelKey;

/// Encoding of map points in the block pool.
pub trait PointCodec<T: Real>: Send + Sync + 'static {
    /// The stored form of one point.
    type Stored: bytemuck::Pod + Send + Sync;
    /// Encodes `p`, which lies in voxel `key` of size `v`.
    fn encode(p: &Point<T>, key: &VoxelKey, v: T) -> Self::Stored;
    /// Decodes a stored point of voxel `key`.
    fn decode(s: &Self::Stored, key: &VoxelKey, v: T) -> Point<T>;
}

/// Points stored as they are (`3 * size_of::<T>()` bytes): the f64 build then agrees with the
/// reference to rounding.
#[derive(Clone, Copy, Debug, Default)]
pub struct Exact;

impl<T: Real> PointCodec<T> for Exact {
    type Stored = [T; 3];
    #[inline]
    fn encode(p: &Point<T>, _key: &VoxelKey, _v: T) -> [T; 3] {
        [p.x, p.y, p.z]
    }
    #[inline]
    fn decode(s: &[T; 3], _key: &VoxelKey, _v: T) -> Point<T> {
        Point::from(*s)
    }
}

/// Points stored as 16-bit offsets from their voxel's corner (6 bytes a point), decoded to the
/// centre of a cell of `v / 65536` (15 um at 1 m voxels, so at most 7.6 um off per axis). The
/// idea follows the int8 inline blocks of the reference authors' `rko_lio`, with 256 times the
/// resolution; the accuracy cost against exact storage is measured in BENCHMARKS.md.
#[derive(Clone, Copy, Debug, Default)]
pub struct Quantized;

const Q: f64 = 65536.0;

impl<T: Real> PointCodec<T> for Quantized {
    type Stored = [u16; 3];
    #[inline]
    fn encode(p: &Point<T>, key: &VoxelKey, v: T) -> [u16; 3] {
        let q = |c: T, k: i32| {
            let u = (c / v - T::of(k as f64)) * T::of(Q);
            u.floor_i32().clamp(0, 65535) as u16
        };
        [q(p.x, key[0]), q(p.y, key[1]), q(p.z, key[2])]
    }
    #[inline]
    fn decode(s: &[u16; 3], key: &VoxelKey, v: T) -> Point<T> {
        let d = |q: u16, k: i32| {
            (T::of(k as f64) + (T::of(q as f64) + T::of(0.5)) * T::of(1.0 / Q)) * v
        };
        Point::new(d(s[0], key[0]), d(s[1], key[1]), d(s[2], key[2]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::voxel::point_to_voxel;

    #[test]
    fn quantised_points_decode_within_half_a_cell() {
        let v = 1.0f64;
        for p in [
            Point::new(12.3456789, -0.000001, 99.999999),
            Point::new(-7.5, 3.25, -0.75),
            Point::new(1234.5678, -4321.123, 0.5),
        ] {
            let k = point_to_voxel(&p, v);
            let back = <Quantized as PointCodec<f64>>::decode(&Quantized::encode(&p, &k, v), &k, v);
            assert!((back - p).amax() <= 0.5 / Q + 1e-12, "{p} -> {back}");
            assert_eq!(point_to_voxel(&back, v), k);
        }
    }

    #[test]
    fn exact_points_round_trip_bit_for_bit() {
        let p = Point::new(0.1f64, -2.0 / 3.0, 1e5 + 0.3);
        let k = point_to_voxel(&p, 1.0);
        assert_eq!(
            <Exact as PointCodec<f64>>::decode(&Exact::encode(&p, &k, 1.0), &k, 1.0),
            p
        );
    }
}
