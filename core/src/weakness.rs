//! How weakly the scene constrains each direction at the prediction, for robust mode's motion
//! prior gate ([`crate::Robust::prior_gate`]).
//!
//! Step 4 (Sec. III-E) moves the pose along every direction its point-to-point normal
//! equations allow, and those equations cannot tell a corridor from a street (see
//! `observability`): in a tunnel or over a lone ground plane ICP slides along the directions
//! the scene does not constrain. Before ICP, the point-to-plane information of the
//! registration points at the constant-velocity prediction is measured from the shapes of
//! well-filled map voxels (`observability::information`): its weakest and middle translation
//! eigenvalues over the strongest, and its weakest rotation over the strongest. Robust mode's
//! gated motion prior acts where the weakest translation is below the gate, and holds the
//! position at the prediction only where the middle one is not (a corridor's lone free axis);
//! `frames.csv` reports the two weakest ratios (`weak_t`, `weak_r`).
//!
//! Memory: nothing is kept between frames and nothing is added to the arena.
//! Determinism: the eigen-decompositions are cyclic Jacobi sweeps in fixed order using only
//! `+ - * /` and the correctly rounded square root, so every target gives the same bits.

use crate::eigen::jacobi_eigen;
use crate::geometry::{Point, Pose};
use crate::local_map::{MapView, PointCodec};
use crate::observability::{information, Information, Volumes};
use crate::scalar::Real;
use nalgebra::{Matrix3, Vector3};

/// The measurement of a frame: for translation and rotation, the weakest over the strongest
/// eigenvalue of the information, and the middle translation over the strongest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weakness<T: Real> {
    /// Smallest over largest eigenvalue of the translation and the rotation information,
    /// `None` when nothing was measured.
    pub ratio: Option<[T; 2]>,
    /// The translation information's middle eigenvalue over its largest: a corridor leaves
    /// one translation weak (this is large), an open plane two (this is small too).
    pub middle: Option<T>,
}

impl<T: Real> Weakness<T> {
    /// Nothing measured (the reference mode, an ungated prior, the first frames).
    pub const NONE: Weakness<T> = Weakness {
        ratio: None,
        middle: None,
    };
}

/// Measures the `source` points (sensor frame) at `prediction` against `map`, reading only
/// voxels with at least `min_points` map points (see [`min_points`]). While no voxel near the
/// points is that full (the first frames) nothing is measured.
pub fn weakness<T: Real, P: PointCodec<T>>(
    map: &MapView<'_, T, P>,
    source: &[[T; 3]],
    prediction: &Pose<T>,
    max_distance: T,
    min_points: usize,
) -> Weakness<T> {
    let origin = Point::from(prediction.translation.vector);
    let points = source.iter().map(|p| prediction * Point::from(*p));
    let info = information(
        map,
        points,
        source.len(),
        &origin,
        max_distance,
        Volumes::Flattest,
        min_points,
    );
    info.map_or(Weakness::NONE, |info| measure(&info, prediction))
}

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

/// Map points a voxel needs before its shape is read: more than one sweep can put there. A
/// sweep adds at most `(1 / alpha)^2` points to a voxel's worth of surface (one per `alpha v`
/// merge voxel), and what a single sweep leaves, sparse at range, is one ring arc or scan
/// column whose shape is the scan pattern's, not the scene's (a column on a wall seen at
/// grazing incidence looks like a plane across the corridor).
pub fn min_points<T: Real>(alpha: T) -> usize {
    // A product, not `powi`: `powi` is not correctly rounded (nor the same on every target;
    // Miri perturbs it), and `(1 / 0.5)^2` must be 4 exactly.
    let inv = T::one() / alpha;
    let per_sweep = (inv * inv).wide();
    if per_sweep.is_finite() && per_sweep < 1e6 {
        per_sweep as usize + 1
    } else {
        usize::MAX
    }
}

/// The ratios of `info` (about the sensor, world axes) at `prediction`.
fn measure<T: Real>(info: &Information<T>, prediction: &Pose<T>) -> Weakness<T> {
    // Into the predicted sensor frame (both halves of a twist rotate by R^T). The eigenvalues
    // do not depend on the axes but their rounding does, and the preset's gate was read from
    // ratios taken there.
    let r = prediction.rotation.to_rotation_matrix().into_inner();
    let rt = r.transpose();
    let [t_ratio, middle] = ratios(&(rt * info.t * r));
    let [w_ratio, _] = ratios(&(rt * info.r * r));
    Weakness {
        ratio: Some([t_ratio, w_ratio]),
        middle: Some(middle),
    }
}

/// The weakest and the middle eigenvalue of the symmetric `m` over its strongest (both 0
/// when the strongest is not positive and finite).
fn ratios<T: Real>(m: &Matrix3<T>) -> [T; 2] {
    let (values, _) = jacobi_eigen(*m);
    let max = values.max();
    if !(max > T::zero() && max.is_finite()) {
        return [T::zero(); 2];
    }
    let min = values.min();
    let middle = values.iter().fold(T::zero(), |a, &v| a + v) - min - max;
    [min / max, middle / max].map(|x| x.max(T::zero()))
}

#[cfg(test)]
mod tests;
