//! Nearest-neighbour search over the 27 voxels around a query (Sec. III-C).
//!
//! Result-identical to the reference's `GetClosestNeighbor`: voxels are visited in its order,
//! points in insertion order, and a candidate replaces the best only if its *norm* is strictly
//! smaller, so equidistant points resolve the same way. Two exact shortcuts make it fast: a
//! voxel is skipped when the distance from the query to the voxel's box (shrunk by a rounding
//! margin) already rules out every point in it, either against the best so far or against the
//! correspondence threshold, which the reference applies after the search anyway.

use super::{MapView, PointCodec};
use crate::scalar::{norm_lt, sqrt_lt, Real};
use crate::voxel::{point_to_voxel, NEIGHBOUR_SHIFTS};
use crate::Point;

impl<T: Real, P: PointCodec<T>> MapView<'_, T, P> {
    /// The closest map point to `query` among the 27 surrounding voxels if its distance is
    /// below `max_distance`, with its squared distance.
    #[inline]
    pub fn closest_neighbor(&self, query: &Point<T>, max_distance: T) -> Option<(Point<T>, T)> {
        if self.st.voxels == 0 {
            return None;
        }
        let v = self.st.voxel_size;
        let key = point_to_voxel(query, v);
        let margin = v * T::of(1e-3);
        // Squared distance from the query to the slab of neighbour offsets -1, 0, +1, per axis.
        let mut slab = [[T::zero(); 3]; 3];
        for a in 0..3 {
            let lo = T::of(key[a] as f64) * v;
            let below = (query[a] - lo - margin).max(T::zero());
            let above = (lo + v - query[a] - margin).max(T::zero());
            slab[a] = [below * below, T::zero(), above * above];
        }
        let limit2 = max_distance * max_distance * (T::one() + T::of(8.0) * T::EPS);
        let mut best2 = T::max_value().unwrap_or(T::one() / T::zero());
        let mut best = Point::origin();
        for s in NEIGHBOUR_SHIFTS.iter() {
            let lb2 = slab[0][(s[0] + 1) as usize]
                + slab[1][(s[1] + 1) as usize]
                + slab[2][(s[2] + 1) as usize];
            if lb2 > best2 || lb2 >= limit2 {
                continue;
            }
            let nk = [key[0] + s[0], key[1] + s[1], key[2] + s[2]];
            let Some(slot) = self.find(&nk) else {
                continue;
            };
            self.for_each_in(slot, |p| {
                let d2 = (p - query).norm_squared();
                if norm_lt(d2, best2) {
                    best2 = d2;
                    best = p;
                }
                true
            });
        }
        if sqrt_lt(best2, max_distance) {
            Some((best, best2))
        } else {
            None
        }
    }
}

impl<T: Real, P: PointCodec<T>> MapView<'_, T, P> {
    /// Number of points and their covariance in the voxel holding `p`, if it exists.
    pub fn voxel_covariance(&self, p: &Point<T>) -> Option<(usize, nalgebra::Matrix3<T>)> {
        let slot = self.find(&point_to_voxel(p, self.st.voxel_size))?;
        let n = self.counts[slot] as usize;
        let mut mean = nalgebra::Vector3::zeros();
        self.for_each_in(slot, |q| {
            mean += q.coords;
            true
        });
        mean /= T::of(n as f64);
        let mut cov = nalgebra::Matrix3::zeros();
        self.for_each_in(slot, |q| {
            let d = q.coords - mean;
            cov += d * d.transpose();
            true
        });
        Some((n, cov / T::of(n as f64)))
    }
}
