//! Point-to-plane terms for robust mode (issue 17; after GenZ-ICP, Lee et al., RA-L 2024).
//!
//! Step 4's point-to-point residual `s - q` is as stiff along a wall as across it, so in a
//! tunnel the thousands of wall and floor points pin the pose where the prediction put it and
//! the few pillars cannot pull it along the free axis; over open ground the same residual
//! matches each scan ring to the last sweep's ring, which moves whenever the sensor pitches.
//! Where the map around the registration point `s` is a plane, robust mode uses the residual
//! `n . (s - q)` along the plane's normal `n` instead (`q` the closest map point, as in the
//! reference): it has no stiffness along the plane, so the scene's sparse structure decides the
//! free directions. Every other correspondence keeps the point-to-point term. The two kinds are
//! summed in separate partial systems and combined as `(1 - a) H_point + a H_plane`, with `a`
//! the share of planar correspondences in the iteration (GenZ-ICP's adaptive weight: the more
//! structured the scene, the more the planes count).
//!
//! The plane is read from the map points of the 27 voxels around `s` (GenZ-ICP's
//! neighbourhood; one voxel far out holds one ring's arc): at least [`MIN_POINTS`] of them,
//! covariance eigenvalues `l0 <= l1 <= l2` with `l0 < PLANARITY (l0 + l1 + l2)` (GenZ-ICP's test
//! and threshold; a ring's arc passes it, and its normal is then the arc's flatter side). It is
//! computed per query (no memory kept; a cyclic Jacobi eigen-decomposition, so every target
//! gives the same bits).

use super::{SYSTEM_LEN, TERMS};
use crate::local_map::{MapView, PointCodec};
use crate::robust::jacobi_eigen;
use crate::scalar::Real;
use crate::Point;
use nalgebra::Vector3;

/// A neighbourhood is planar when its smallest covariance eigenvalue is below this share of
/// their sum (GenZ-ICP's `planarity_threshold` in all its presets).
pub const PLANARITY: f64 = 0.2;

/// Map points a neighbourhood needs before its shape is read (GenZ-ICP's).
pub const MIN_POINTS: usize = 5;

/// Offset of the planar partial system in a chunk's system: after the point-to-point one.
pub(super) const PLANAR: usize = TERMS;

/// The unit normal of the map around `s` if it is planar (see the module doc).
pub(super) fn normal_at<T: Real, P: PointCodec<T>>(
    map: &MapView<'_, T, P>,
    s: &Point<T>,
) -> Option<Vector3<T>> {
    let (n, cov) = map.neighbourhood_covariance(s)?;
    if n < MIN_POINTS {
        return None;
    }
    let (values, vectors) = jacobi_eigen(cov);
    let mut idx = [0usize, 1, 2];
    idx.sort_unstable_by(|&a, &b| {
        values[a]
            .partial_cmp(&values[b])
            .unwrap_or(core::cmp::Ordering::Equal)
    });
    let l = idx.map(|i| values[i].max(T::zero()));
    let sum = l[0] + l[1] + l[2];
    let planar = sum > T::zero() && sum.is_finite() && l[0] < T::of(PLANARITY) * sum;
    planar.then(|| vectors.column(idx[0]).into_owned())
}

/// Adds one weighted point-to-plane term (`J = [n, s x n]`, residual `n . r`) to the planar
/// half of `acc`, as `accumulate` adds a point-to-point one to the other half.
#[inline]
pub(super) fn accumulate_plane<T: Real>(
    acc: &mut [T; SYSTEM_LEN],
    s: &Vector3<T>,
    n: &Vector3<T>,
    rn: T,
    w: T,
) {
    let c = s.cross(n);
    let j = [n.x, n.y, n.z, c.x, c.y, c.z];
    let mut k = PLANAR;
    for r in 0..6 {
        for col in r..6 {
            acc[k] += w * j[r] * j[col];
            k += 1;
        }
    }
    for (r, jr) in j.iter().enumerate() {
        acc[PLANAR + 21 + r] += w * *jr * rn;
    }
    acc[PLANAR + 27] += T::one();
    acc[PLANAR + 28] += rn * rn;
}

#[cfg(test)]
mod tests;
