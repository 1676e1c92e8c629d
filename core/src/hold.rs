//! Hold mode ([`crate::Degeneracy::Hold`], kept for comparison with robust mode): directions the
//! scene does not constrain are held at the constant-velocity prediction. Robust mode itself,
//! [`crate::Degeneracy::Robust`], is point-to-plane terms (see `registration::planes`).
//!
//! Step 4 (Sec. III-E) moves the pose along every direction its point-to-point normal
//! equations allow, and those equations cannot tell a corridor from a street (see
//! `observability`): in a tunnel or over a lone ground plane ICP slides along the directions the
//! scene does not constrain. In hold mode, before ICP, the point-to-plane information of the
//! registration points at the constant-velocity prediction is measured from the shapes of
//! well-filled map voxels (`observability::information`) and taken in the predicted sensor frame.
//! Translation directions weaker than [`TRANSLATION_RATIO`] of the strongest translation, and
//! rotation directions weaker than [`ROTATION_RATIO`] of the strongest rotation, are *held*:
//! every Gauss-Newton step is projected off them (Zhang, Kaess & Singh, ICRA 2016, "solution
//! remapping"), and the final correction's twist, in the predicted sensor frame, loses its
//! component along them. Along a held direction the pose is the prediction; along the others
//! ICP runs as in the reference, and a frame with no weak direction is registered exactly as
//! in [`crate::Degeneracy::Reference`].
//!
//! Memory: nothing is kept between frames and nothing is added to the arena; a [`Hold`] is two
//! 6x6 matrices (288 B in f32, 576 B in f64) on the stack and in the ICP parameters.
//! Determinism: the eigen-decompositions are cyclic Jacobi sweeps in fixed order using only
//! `+ - * /` and the correctly rounded square root, so every target gives the same bits.

use crate::eigen::jacobi_eigen;
use crate::geometry::{Point, Pose};
use crate::lie::{hat, se3_exp, se3_log};
use crate::local_map::{MapView, PointCodec};
use crate::observability::{information, Information, Volumes};
use crate::scalar::Real;
use nalgebra::{Matrix3, Matrix6, Vector6};

/// Names of the predicted sensor frame's axes in twist order, as [`Held`] and `frames.csv`
/// give them: translations along x, y, z, then rotations about x (roll), y (pitch), z (yaw).
pub const AXES: [&str; 6] = ["tx", "ty", "tz", "roll", "pitch", "yaw"];

/// What hold mode held in a frame: how many eigen-directions, and which sensor axes lie
/// mostly (at least half their squared length) in the held subspace.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Held {
    axes: u8,
    directions: u8,
}

impl Held {
    /// Nothing held.
    pub const NONE: Held = Held {
        axes: 0,
        directions: 0,
    };

    /// Eigen-directions held at the prediction (0 to 6).
    pub const fn directions(self) -> u8 {
        self.directions
    }
    /// The held axes as bits, bit `i` for [`AXES`]`[i]`.
    pub const fn axes(self) -> u8 {
        self.axes
    }
    /// Whether axis `i` of [`AXES`] is held.
    pub const fn holds_axis(self, i: usize) -> bool {
        i < 6 && self.axes & (1 << i) != 0
    }
    /// The held axes' names, in [`AXES`] order.
    pub fn names(self) -> impl Iterator<Item = &'static str> {
        AXES.into_iter()
            .enumerate()
            .filter(move |(i, _)| self.holds_axis(*i))
            .map(|(_, n)| n)
    }
}

impl core::fmt::Display for Held {
    /// The held axes joined by `|` (e.g. `tx|ty|yaw`); empty when none is.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        for (i, name) in self.names().enumerate() {
            if i > 0 {
                f.write_str("|")?;
            }
            f.write_str(name)?;
        }
        Ok(())
    }
}

/// The projection hold mode applies in one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hold<T: Real> {
    /// Projector on ICP's steps (twists about the world origin, left-multiplied).
    world: Matrix6<T>,
    /// Projector on the correction's twist in the predicted sensor frame.
    body: Matrix6<T>,
    held: Held,
}

impl<T: Real> Hold<T> {
    /// ICP's step `dx` with no component along the held directions.
    #[inline]
    pub fn step(&self, dx: &Vector6<T>) -> Vector6<T> {
        self.world * dx
    }

    /// `pose` brought back to `prediction` along the held directions: the correction
    /// `prediction^-1 pose` loses the held part of its twist.
    pub fn apply(&self, prediction: &Pose<T>, pose: &Pose<T>) -> Pose<T> {
        let xi = se3_log(&(prediction.inverse() * pose));
        prediction * se3_exp(&(self.body * xi))
    }

    /// What is held.
    pub fn held(&self) -> Held {
        self.held
    }
}

/// Hold mode's finding for a frame: the hold (if any direction is weak) and, for translation
/// and rotation, the weakest over the strongest eigenvalue of the information.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weakness<T: Real> {
    /// The projection, `None` when no direction is weak.
    pub hold: Option<Hold<T>>,
    /// Smallest over largest eigenvalue of the translation and the rotation information,
    /// `None` when nothing was measured.
    pub ratio: Option<[T; 2]>,
    /// The translation information's middle eigenvalue over its largest: a corridor leaves
    /// one translation weak (this is large), an open plane two (this is small too).
    pub middle: Option<T>,
}

impl<T: Real> Weakness<T> {
    /// Nothing measured, nothing held (the reference mode, the first frame).
    pub const NONE: Weakness<T> = Weakness {
        hold: None,
        ratio: None,
        middle: None,
    };

    /// What is held (nothing without a hold).
    pub fn held(&self) -> Held {
        self.hold.map_or(Held::NONE, |h| h.held)
    }

    /// `pose` held along the weak directions, or `pose` itself when nothing is held.
    pub fn apply(&self, prediction: &Pose<T>, pose: Pose<T>) -> Pose<T> {
        match &self.hold {
            Some(h) => h.apply(prediction, &pose),
            None => pose,
        }
    }
}

/// A translation direction is held when its information is below this fraction of the
/// strongest translation's. Read from `frames.csv` (`weak_t`) of generated runs: the
/// corridor's axis reads 0.01-0.09 (scan-pattern artefacts in sparsely filled voxels leak a little),
/// a lone plane's 1e-4, urban streets' weakest 0.25-0.6.
pub const TRANSLATION_RATIO: f64 = 0.1;

/// A rotation direction is held when its information is below this fraction of the strongest
/// rotation's. Rotations spread more than translations because their lever arms differ by
/// axis (the corridor's roll has its 4 m width, its yaw the 100 m length: 0.003-0.02); a lone
/// plane's yaw reads 1e-4, urban streets' weakest rotation 0.03-0.1.
pub const ROTATION_RATIO: f64 = 0.002;

/// Measures the `source` points (sensor frame) at `prediction` against `map` and decides what
/// to hold, reading only voxels with at least `min_points` map points (see [`min_points`]).
/// While no voxel near the points is that full (the first frames) nothing is measured and
/// nothing held: ICP runs as the reference's and gives the constant-velocity model its first
/// velocity.
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
    info.map_or(Weakness::NONE, |info| decide(&info, prediction))
}

/// Map points a voxel needs before hold mode reads its shape: more than one sweep can put
/// there. A sweep adds at most `(1 / alpha)^2` points to a voxel's worth of surface (one per
/// `alpha v` merge voxel), and what a single sweep leaves, sparse at range, is one ring arc or
/// scan column whose shape is the scan pattern's, not the scene's (a column on a wall seen at
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

/// The hold for `info` (about the sensor, world axes) at `prediction`.
fn decide<T: Real>(info: &Information<T>, prediction: &Pose<T>) -> Weakness<T> {
    // Into the predicted sensor frame: both halves of a twist rotate by R^T.
    let r = prediction.rotation.to_rotation_matrix().into_inner();
    let rt = r.transpose();
    let (t, [t_ratio, middle], t_weak) = weak_block(&(rt * info.t * r), T::of(TRANSLATION_RATIO));
    let (w, [w_ratio, _], w_weak) = weak_block(&(rt * info.r * r), T::of(ROTATION_RATIO));
    let ratio = Some([t_ratio, w_ratio]);
    let middle = Some(middle);
    let directions = t_weak + w_weak;
    if directions == 0 {
        return Weakness {
            hold: None,
            ratio,
            middle,
        };
    }
    let mut body = Matrix6::identity();
    body.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(Matrix3::identity() - t));
    body.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(Matrix3::identity() - w));
    let mut axes = 0u8;
    for i in 0..3 {
        // The share of axis i in the held subspace.
        axes |= u8::from(t[(i, i)] >= T::of(0.5)) << i;
        axes |= u8::from(w[(i, i)] >= T::of(0.5)) << (i + 3);
    }
    let held = Held { axes, directions };
    Weakness {
        hold: Some(hold_of(body, held, prediction)),
        ratio,
        middle,
    }
}

/// The projector onto the directions of the symmetric `m` weaker than `threshold` of its
/// strongest, the weakest and the middle eigenvalue over the strongest, and how many are weak.
fn weak_block<T: Real>(m: &Matrix3<T>, threshold: T) -> (Matrix3<T>, [T; 2], u8) {
    let (values, vectors) = jacobi_eigen(*m);
    let max = values.max();
    if !(max > T::zero() && max.is_finite()) {
        return (Matrix3::identity(), [T::zero(); 2], 3);
    }
    let mut weak = Matrix3::zeros();
    let mut count = 0;
    for k in 0..3 {
        if values[k] < threshold * max {
            let v = vectors.column(k);
            weak += v * v.transpose();
            count += 1;
        }
    }
    let min = values.min();
    let middle = values.iter().fold(T::zero(), |a, &v| a + v) - min - max;
    let ratios = [min / max, middle / max].map(|x| x.max(T::zero()));
    (weak, ratios, count)
}

/// The hold of the sensor-frame projector `body`, with its world-frame twin for ICP's steps.
fn hold_of<T: Real>(body: Matrix6<T>, held: Held, prediction: &Pose<T>) -> Hold<T> {
    // A sensor-frame twist xi moves the pose to `prediction exp(xi) = exp(Ad xi) prediction`,
    // Ad = [[R, [p]x R], [0, R]]; ICP's steps are the world twists Ad xi.
    let r = prediction.rotation.to_rotation_matrix().into_inner();
    let pr = hat(&prediction.translation.vector) * r;
    let rt = r.transpose();
    let mut ad = Matrix6::zeros();
    let mut ad_inv = Matrix6::zeros();
    ad.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    ad.fixed_view_mut::<3, 3>(0, 3).copy_from(&pr);
    ad.fixed_view_mut::<3, 3>(3, 3).copy_from(&r);
    ad_inv.fixed_view_mut::<3, 3>(0, 0).copy_from(&rt);
    ad_inv
        .fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&(-(rt * pr * rt)));
    ad_inv.fixed_view_mut::<3, 3>(3, 3).copy_from(&rt);
    Hold {
        world: ad * body * ad_inv,
        body,
        held,
    }
}

#[cfg(test)]
mod tests;
