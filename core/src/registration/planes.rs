//! Point-to-plane terms for robust mode (after GenZ-ICP, Lee et al., RA-L 2024).
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
//! read with a cyclic Jacobi eigen-decomposition, so every target gives the same bits. It
//! depends only on the voxel holding `s` (the map does not change during a registration), so
//! each source point keeps the last one it read with that voxel's key ([`Cached`]) and reads
//! again only when it moves into another voxel: the same normals as reading every time, a plane
//! fit a point and voxel instead of a point and iteration.

use super::system::SYSTEM_LEN;
use crate::eigen::jacobi_eigen;
use crate::geometry::Point;
use crate::local_map::Voxels;
use crate::scalar::Real;
use crate::voxel::{point_to_voxel, VoxelKey};
use nalgebra::Vector3;

/// A neighbourhood is planar when its smallest covariance eigenvalue is below this share of
/// their sum (GenZ-ICP's `planarity_threshold` in all its presets).
pub const PLANARITY: f64 = 0.2;

/// The Geman-McClure scale of a registration with plane terms, over `sigma`: the paper's
/// `sigma / 3` (Eq. (10); GenZ-ICP's too). With kiss-icp's `sigma` the far ground's
/// ring-to-ring matches outweigh an open field's few poles (BENCHMARKS.md section 12).
pub const PLANE_KERNEL_SCALE: f64 = 1.0 / 3.0;

/// Map points a neighbourhood needs before its shape is read (GenZ-ICP's).
pub const MIN_POINTS: usize = 5;

/// Scalars per source point of [`Cached`].
pub(super) const CACHED: usize = 6;

/// A source point's last plane: the key of the voxel it was read for (as scalars, exact within
/// 2^24 voxels of the origin in f32; infinite: none yet) and the unit normal (zero: not
/// planar).
pub(super) struct Cached;

impl Cached {
    /// Nothing read yet.
    pub(super) fn clear<T: Real>(cached: &mut [T]) {
        cached.fill(T::zero());
        if let Some(k) = cached.first_mut() {
            *k = T::one() / T::zero();
        }
    }

    /// The normal of the map around `s` (see [`normal_at`]), from `cached` when `s` is in the
    /// voxel it was read for, else read and kept in `cached` (`CACHED` scalars).
    #[inline]
    pub(super) fn normal<T: Real, M: Voxels<T>>(
        cached: &mut [T],
        map: &M,
        s: &Point<T>,
    ) -> Option<Vector3<T>> {
        let voxel = point_to_voxel(s, map.voxel_size());
        let key = voxel.map(|k| T::of(f64::from(k)));
        let (at, normal) = cached.split_first_chunk_mut::<3>()?;
        let normal = normal.first_chunk_mut::<3>()?;
        if *at != key {
            *at = key;
            *normal = normal_around(map, &voxel).map_or([T::zero(); 3], |n| [n.x, n.y, n.z]);
        }
        let n = Vector3::from(*normal);
        (n != Vector3::zeros()).then_some(n)
    }
}

/// The unit normal of the map around `s` if it is planar (see the module doc).
#[cfg(test)]
pub(super) fn normal_at<T: Real, M: Voxels<T>>(map: &M, s: &Point<T>) -> Option<Vector3<T>> {
    normal_around(map, &point_to_voxel(s, map.voxel_size()))
}

/// The unit normal of the map in the 27 voxels around `voxel` if it is planar.
fn normal_around<T: Real, M: Voxels<T>>(map: &M, voxel: &VoxelKey) -> Option<Vector3<T>> {
    let (n, cov) = map.neighbourhood_covariance(voxel)?;
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

/// Adds one weighted point-to-plane term (`J = [n, s x n]`, residual `n . r`) to `acc`, the
/// point-to-plane partial system, as `accumulate` adds a point-to-point one to its own.
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
    let mut k = 0;
    for r in 0..6 {
        for col in r..6 {
            acc[k] += w * j[r] * j[col];
            k += 1;
        }
    }
    for (r, jr) in j.iter().enumerate() {
        acc[21 + r] += w * *jr * rn;
    }
    acc[27] += T::one();
    acc[28] += rn * rn;
}

#[cfg(test)]
mod tests;
