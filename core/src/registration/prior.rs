//! Robust mode's motion prior: what the scene leaves free, the sensor's motion decides
//!.
//!
//! In a bare corridor no scan says how far the sensor went along the axis, and plane terms
//! (see `planes`) leave that direction without any information: Gauss-Newton then steps along
//! it by whatever rounding and noise give. Two soft terms, added to the summed normal
//! equations of a registration with plane terms, decide such directions:
//!
//! - **hold**: `|t - t_pred|^2`, the position at the constant-velocity prediction (Eq. (1)), so
//!   a direction no correspondence constrains stays where the prediction put it (what the
//!   issue's "kept at the constant-velocity prediction" asks, softly);
//! - **lateral**: `(l . (t - t_{t-1}))^2`, no motion along the sensor's `y` axis `l` (taken
//!   halfway between the last pose and the prediction): a car-like vehicle (wheels, tracks)
//!   carrying the sensor with `x` forward does not slide sideways. While it turns in a
//!   corridor, the observed motion across the corridor then fixes the motion along it.
//!
//! Each term is a residual of the position `t` of the current iterate, linearized for ICP's
//! left-multiplied twist (`dt = rho + phi x t`): the hold is a point-to-point term of the point
//! `t` against `t_pred`, the lateral one a point-to-plane term of `t` against the plane through
//! `t_{t-1}` with normal `l`. Their weights are per correspondence of the iteration
//! (`Robust::prediction_prior`, `Robust::lateral_prior`), so they keep their share whatever the
//! scan's size; neither counts as a correspondence.

use super::planes::accumulate_plane;
use super::system::{accumulate, SYSTEM_LEN};
use crate::geometry::Pose;
use crate::scalar::Real;
use nalgebra::Vector3;

/// The motion prior of one frame's registration with plane terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionPrior<T: Real> {
    /// `t_pred`: the constant-velocity prediction's position.
    predicted: Vector3<T>,
    /// `t_{t-1}`: the last pose's position.
    last: Vector3<T>,
    /// `l`: the unit lateral direction.
    lateral: Vector3<T>,
    /// Weight of the hold term per correspondence.
    hold: T,
    /// Weight of the lateral term per correspondence.
    sideways: T,
}

impl<T: Real> MotionPrior<T> {
    /// The prior from the last pose and the prediction, with the hold and lateral weights per
    /// correspondence (0: that term is left out).
    pub fn new(last: &Pose<T>, prediction: &Pose<T>, hold: T, sideways: T) -> Self {
        let y = Vector3::y();
        let both = last.rotation * y + prediction.rotation * y;
        let norm = both.norm();
        // Two y axes a third of a turn or more apart (not one frame's turn) have no halfway
        // direction to trust: no lateral term then.
        let (lateral, sideways) = if norm > T::one() {
            (both / norm, sideways)
        } else {
            (Vector3::zeros(), T::zero())
        };
        Self {
            predicted: prediction.translation.vector,
            last: last.translation.vector,
            lateral,
            hold,
            sideways,
        }
    }

    /// Adds the prior's terms at the iterate's position `t` to the summed system `sum`, each
    /// weighted by the system's correspondence count.
    pub(super) fn add(&self, sum: &mut [T; SYSTEM_LEN], t: &Vector3<T>) {
        // The accumulations count a correspondence and its squared residual: these are not.
        let (correspondences, squares) = (sum[27], sum[28]);
        if self.hold > T::zero() {
            accumulate(sum, t, &(t - self.predicted), self.hold * correspondences);
        }
        if self.sideways > T::zero() {
            let across = self.lateral.dot(&(t - self.last));
            let weight = self.sideways * correspondences;
            accumulate_plane(sum, t, &self.lateral, across, weight);
        }
        sum[27] = correspondences;
        sum[28] = squares;
    }
}

#[cfg(test)]
mod tests;
