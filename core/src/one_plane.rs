//! Robust mode's hold for a registration cloud of one plane: such a scan measures nothing
//! along the plane, and step 4 (Sec. III-E) is skipped for it (the frame keeps its prediction).
//!
//! Determinism: the eigen-decomposition is a cyclic Jacobi sweep in fixed order using only
//! `+ - * /` and the correctly rounded square root, so every target gives the same bits.

use crate::eigen::jacobi_eigen;
use crate::scalar::Real;
use nalgebra::{Matrix3, Vector3};

/// Whether the registration cloud `points` lies on one plane: at most one in
/// [`ONE_PLANE_OFF`] of them farther than `voxel_size` from the plane fitted
/// to them all (through their centroid, normal to their covariance's weakest direction). Such
/// a scan measures nothing along the plane: ICP's point-to-plane terms leave both of its
/// translations and the turn about its normal free, and the few terms that are left pull the
/// pose wherever the map's edges happen to be. Structure that can measure those directions
/// stands off the plane by more than a map voxel (a wall, a pole, a kerb seen across cells);
/// the plane's own roughness and a sensor's range noise stay within one. The share is small
/// because little structure already measures: a generated open field's sparsest scans have
/// 0.9-1.2 % of their registration points on its poles and trees, and registering them
/// (rather than holding them) keeps its ATE 8 % lower.
pub fn one_plane<T: Real>(points: &[[T; 3]], voxel_size: T) -> bool {
    let n = points.len();
    if n < 3 {
        return false;
    }
    let count = T::of(n as f64);
    let sum = points
        .iter()
        .fold(Vector3::zeros(), |s, p| s + Vector3::from(*p));
    let centroid = sum / count;
    let cov = points.iter().fold(Matrix3::zeros(), |c, p| {
        let d = Vector3::from(*p) - centroid;
        c + d * d.transpose()
    }) / count;
    let (values, vectors) = jacobi_eigen(cov);
    let weakest = (0..3).fold(0, |w, i| if values[i] < values[w] { i } else { w });
    let normal = vectors.column(weakest).into_owned();
    let off = points
        .iter()
        .filter(|p| (normal.dot(&(Vector3::from(**p) - centroid))).abs() > voxel_size)
        .count();
    off * ONE_PLANE_OFF <= n
}

/// A scan is one plane while at most one point in this many stands off it (see
/// [`one_plane`]): nine times below the sparsest structure measured on an open field.
const ONE_PLANE_OFF: usize = 1000;

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` points of a tilted plane (rough by 2 cm) out to 40 m, then `off` of them lifted 2 m off
    /// it (a wall's worth of structure).
    fn tilted_plane(n: usize, off: usize) -> std::vec::Vec<[f64; 3]> {
        let mut rng = crate::testutil::Rng(7);
        let normal = Vector3::new(0.1, -0.2, 1.0).normalize();
        let (u, w) = (normal.cross(&Vector3::x()).normalize(), normal);
        let v = w.cross(&u);
        (0..n)
            .map(|i| {
                let (a, b) = (80.0 * rng.next() - 40.0, 80.0 * rng.next() - 40.0);
                let lift = if i < off {
                    2.0
                } else {
                    0.04 * rng.next() - 0.02
                };
                let p = u * a + v * b + w * (lift - 1.7);
                [p.x, p.y, p.z]
            })
            .collect()
    }

    #[test]
    #[cfg_attr(
        miri,
        ignore = "18,000 points of soft-float arithmetic: the Miri lane ran out of time on it; no unsafe on this path"
    )]
    fn a_cloud_is_one_plane_until_more_than_one_point_in_a_thousand_stands_off_it() {
        assert!(one_plane(&tilted_plane(3000, 0), 0.5));
        assert!(one_plane(&tilted_plane(3000, 3), 0.5), "0.1 % off");
        assert!(
            !one_plane(&tilted_plane(3000, 4), 0.5),
            "just over 0.1 % off"
        );
        // An open field's sparsest scans: about 1 % on poles and trees.
        assert!(!one_plane(&tilted_plane(3000, 27), 0.5));
        // The plane's roughness counts against a voxel finer than it.
        assert!(!one_plane(&tilted_plane(3000, 0), 0.01));
        // Too few points to say.
        assert!(!one_plane(&tilted_plane(2, 0), 0.5));
        let f32_plane: std::vec::Vec<[f32; 3]> = tilted_plane(3000, 0)
            .iter()
            .map(|p| p.map(|x| x as f32))
            .collect();
        assert!(one_plane(&f32_plane, 0.5f32));
    }
}
