//! Registration diagnostics: is the scene constraining every direction of the pose?
//!
//! Point-to-point ICP cannot see its own degeneracy: the translation block of its normal
//! equations is `sum(w) I` whatever the geometry, so a featureless corridor looks as well
//! conditioned as a city street. We look at the map instead. For a fixed subsample of the
//! registered points, the voxel of each point's nearest map point is classified by the
//! eigenvalues of its covariance as a plane (it constrains motion along its normal `n`), a line
//! (constrains the two directions across it) or a volume (constrains all three). The summed
//! information `sum M_i` (translation) and `sum [s_i]x^T M_i [s_i]x` (rotation about the
//! sensor) then shows weak directions; the frame's observability is the smaller of the two
//! blocks' smallest-to-largest eigenvalue ratios.
//!
//! A line can also be an artefact of the scan pattern: where rings are sparse (the ground
//! beyond a few metres, anything far away) a voxel holds the arc of a single ring, a line
//! lying in that beam's cone around the spin axis. Its position across the cone is set by the
//! sensor's height and attitude, not by the scene, so it would report information that a flat
//! ground does not have (the plane profile read 0.03-0.05 on its first frames, unflagged, while
//! ICP slid metres). Lines within 30 degrees of the cone's surface therefore give no
//! information; steeper lines (poles, trunks, vertical edges) keep theirs. The spin axis is
//! taken as the map's z (the first scan's up), which is right for ground vehicles.

use crate::geometry::Point;
use crate::lie::hat;
use crate::local_map::Voxels;
use crate::scalar::Real;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// Most points sampled per frame; the sample is every k-th point, so it is deterministic.
pub const SAMPLES: usize = 256;

/// A line voxel counts only if its direction leaves the local beam cone by more than this
/// sine (30 degrees); flatter lines may be single scan rings (see the module doc).
pub const RING_SINE: f64 = 0.5;

/// Observability ratio in `[0, 1]` of the `n` registered `points` (world frame) seen from
/// `origin`, or `None` if no sample had a structured voxel nearby.
pub fn observability<T: Real, M: Voxels<T>>(
    map: &M,
    points: impl Iterator<Item = Point<T>>,
    n: usize,
    origin: &Point<T>,
    max_distance: T,
) -> Option<T> {
    let info = information(map, points, n, origin, max_distance)?;
    Some(ratio(&info.t).min(ratio(&info.r)))
}

/// The summed information `sum J^T M_i J` of the sampled points for a motion about `origin`
/// (world axes), `J = [I, -[s_i - origin]x]`: its translation and rotation blocks.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Information<T: Real> {
    /// Translation block `sum M_i`.
    t: Matrix3<T>,
    /// Rotation block `sum [s_i - origin]x^T M_i [s_i - origin]x`.
    r: Matrix3<T>,
}

/// The information of the `n` `points` (world frame) seen from `origin`, sampled every
/// `n / SAMPLES`-th point, from voxels holding at least 3 map points; `None` if no sample had
/// such a voxel nearby.
fn information<T: Real, M: Voxels<T>>(
    map: &M,
    points: impl Iterator<Item = Point<T>>,
    n: usize,
    origin: &Point<T>,
    max_distance: T,
) -> Option<Information<T>> {
    let step = n.div_ceil(SAMPLES).max(1);
    let mut info = Information {
        t: Matrix3::zeros(),
        r: Matrix3::zeros(),
    };
    let mut used = 0;
    for s in points.step_by(step) {
        let Some((q, _)) = map.closest_neighbor(&s, max_distance) else {
            continue;
        };
        let Some((n, cov)) = map.voxel_covariance(&q) else {
            continue;
        };
        if n < 3 {
            continue;
        }
        let ray = s - origin;
        let Some(m) = shape_information(&cov, &ray) else {
            continue;
        };
        let arm = hat(&ray);
        info.t += m;
        info.r += arm.transpose() * m * arm;
        used += 1;
    }
    (used > 0).then_some(info)
}

/// Information `M` (trace 1) a voxel of covariance `cov` gives a point matched in it, seen
/// along `ray` from the sensor; `None` for no information.
fn shape_information<T: Real>(cov: &Matrix3<T>, ray: &Vector3<T>) -> Option<Matrix3<T>> {
    let eig = SymmetricEigen::new(*cov);
    let mut idx = [0usize, 1, 2];
    idx.sort_unstable_by(|&a, &b| {
        eig.eigenvalues[a]
            .partial_cmp(&eig.eigenvalues[b])
            .unwrap_or(core::cmp::Ordering::Equal)
    });
    let l = [
        eig.eigenvalues[idx[0]].max(T::zero()),
        eig.eigenvalues[idx[1]].max(T::zero()),
        eig.eigenvalues[idx[2]].max(T::zero()),
    ];
    if l[2] <= T::zero() || !l[2].is_finite() {
        return None;
    }
    let tenth = T::of(0.1);
    let col = |i: usize| -> Vector3<T> { eig.eigenvectors.column(idx[i]).into_owned() };
    let m = if l[1] < tenth * l[2] {
        let d = col(2);
        if along_beam_cone(&d, ray) {
            return None;
        }
        (Matrix3::identity() - d * d.transpose()) * T::of(0.5)
    } else if l[0] < tenth * l[1] {
        let n = col(0);
        n * n.transpose()
    } else {
        Matrix3::identity() * T::of(1.0 / 3.0)
    };
    Some(m)
}

/// Whether direction `d` (unit) at the end of `ray` lies within [`RING_SINE`] of the cone that
/// the beam along `ray` sweeps around z. The cone's normal there is z projected off the ray.
fn along_beam_cone<T: Real>(d: &Vector3<T>, ray: &Vector3<T>) -> bool {
    let len = ray.norm();
    if len <= T::zero() || !len.is_finite() {
        return false;
    }
    let u = ray / len;
    let normal = Vector3::z() - u * u.z;
    let n = normal.norm();
    // A vertical ray has no cone; keep the line.
    n > T::of(1e-6) && d.dot(&normal).abs() < T::of(RING_SINE) * n
}

/// Smallest over largest eigenvalue of a symmetric positive semi-definite matrix.
fn ratio<T: Real>(m: &Matrix3<T>) -> T {
    let ev = m.symmetric_eigenvalues();
    let (mut lo, mut hi) = (ev[0], ev[0]);
    for &e in ev.iter() {
        lo = lo.min(e);
        hi = hi.max(e);
    }
    if hi > T::zero() {
        (lo / hi).max(T::zero())
    } else {
        T::zero()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_are_classified_by_their_covariance() {
        // A plane z = 0: information only along z.
        let plane = Matrix3::from_diagonal(&Vector3::new(0.1f64, 0.08, 1e-6));
        let m = shape_information(&plane, &Vector3::x()).unwrap();
        assert!((m[(2, 2)] - 1.0).abs() < 1e-9 && m[(0, 0)].abs() < 1e-9);
        // A vertical line (a pole) seen side-on: information across it only.
        let pole = Matrix3::from_diagonal(&Vector3::new(1e-6f64, 1e-6, 0.1));
        let m = shape_information(&pole, &Vector3::x()).unwrap();
        assert!(m[(2, 2)].abs() < 1e-9 && (m[(0, 0)] - 0.5).abs() < 1e-9);
        // A blob: isotropic.
        let blob = Matrix3::from_diagonal(&Vector3::new(0.1f64, 0.09, 0.08));
        let m = shape_information(&blob, &Vector3::x()).unwrap();
        assert!((m - Matrix3::identity() / 3.0).amax() < 1e-12);
    }

    #[test]
    fn single_ring_arcs_give_no_information() {
        // A ring on the ground 20 m ahead of a sensor 1.8 m up: an arc along y, across the ray.
        let ray = Vector3::new(20.0f64, 0.0, -1.8);
        let arc = Matrix3::from_diagonal(&Vector3::new(1e-6f64, 0.1, 1e-6));
        assert_eq!(shape_information(&arc, &ray), None);
        // The same arc on a side wall, seen at 45 degrees: along the wall, slightly tilted.
        let ray = Vector3::new(10.0f64, 10.0, -1.0);
        let d = Vector3::new(1.0f64, 0.0, -0.07).normalize();
        let wall_arc = d * d.transpose() * 0.1 + Matrix3::identity() * 1e-6;
        assert_eq!(shape_information(&wall_arc, &ray), None);
        // A line leaving the cone steeply (a pole, 20 degrees off vertical) still counts.
        let d = Vector3::new(0.34f64, 0.0, 0.94).normalize();
        let leaning = d * d.transpose() * 0.1 + Matrix3::identity() * 1e-6;
        assert!(shape_information(&leaning, &Vector3::new(15.0, 0.0, 0.5)).is_some());
    }

    #[test]
    fn ratio_is_zero_for_a_missing_direction() {
        assert_eq!(
            ratio(&Matrix3::from_diagonal(&Vector3::new(1.0f64, 2.0, 0.0))),
            0.0
        );
        assert!(
            (ratio(&Matrix3::from_diagonal(&Vector3::new(1.0f64, 4.0, 2.0))) - 0.25).abs() < 1e-12
        );
    }
}
