//! Adaptive threshold for data association (Sec. III-D).
//!
//! Each frame's model deviation `dT` (Eq. (13): how far ICP moved the constant-velocity
//! prediction) bounds the displacement of any point within `r_max` by
//! `delta(dT) = delta_rot + delta_trans` (Eq. (5)), with
//! `delta_rot = 2 r_max sin(theta / 2)` and `delta_trans = |dt|` (Eq. (6)). Deviations larger
//! than `delta_min` are samples of a zero-mean Gaussian whose standard deviation (Eq. (7))
//! `sigma = sqrt(sum delta^2 / |M|)` gives the correspondence threshold `tau = 3 sigma`.
//!
//! As in the reference, the running sum starts with `tau_0^2` counted as one sample, so the
//! first frames use `sigma = tau_0` and the seed's weight fades as real samples arrive.
//!
//! `sigma` models the error of the prediction. A prediction measured by another sensor (a
//! gyroscope's rotation, see `imu`) errs far less than the constant-velocity model on the same
//! motion, so [`Thresholds`] keeps one estimate per kind of prediction: a frame is gated by, and
//! adds its deviation to, the estimate of the prediction it was made with. An odometry never
//! given a measured prediction uses the constant-velocity one alone, as the reference does.

use crate::geometry::Pose;
use crate::lie::rotation_angle;
use crate::scalar::Real;

/// Running estimate of Eq. (7).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AdaptiveThreshold<T> {
    min_motion: T,
    max_range: T,
    model_sse: T,
    samples: u64,
}

impl<T: Real> AdaptiveThreshold<T> {
    /// A threshold seeded with `initial_threshold` (`tau_0`).
    pub fn new(initial_threshold: T, min_motion: T, max_range: T) -> Self {
        Self {
            min_motion,
            max_range,
            model_sse: initial_threshold * initial_threshold,
            samples: 1,
        }
    }

    /// `delta(dT)` of Eq. (5)-(6).
    pub fn model_error(&self, deviation: &Pose<T>) -> T {
        let theta = rotation_angle(&deviation.rotation);
        let delta_rot = T::of(2.0) * self.max_range * (theta / T::of(2.0)).sin_l();
        let delta_trans = deviation.translation.vector.norm();
        delta_trans + delta_rot
    }

    /// Adds a frame's model deviation if it exceeds `delta_min` (the index set of Eq. (8)).
    pub fn update(&mut self, deviation: &Pose<T>) {
        let e = self.model_error(deviation);
        if e > self.min_motion {
            self.model_sse += e * e;
            self.samples += 1;
        }
    }

    /// `sigma_t` of Eq. (7).
    pub fn sigma(&self) -> T {
        (self.model_sse / T::of(self.samples as f64)).sqrt_l()
    }

    /// Samples counted so far, including the seed.
    pub fn samples(&self) -> u64 {
        self.samples
    }
}

/// Eq. (7) per kind of prediction: the constant-velocity model's (Eq. (1)) and that of
/// predictions measured elsewhere.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) struct Thresholds<T> {
    constant_velocity: AdaptiveThreshold<T>,
    measured: AdaptiveThreshold<T>,
    /// The next frame's prediction is a measured one.
    next_measured: bool,
}

impl<T: Real> Thresholds<T> {
    /// Both seeded with `tau_0`; the next prediction is the constant-velocity model's.
    pub(crate) fn new(initial_threshold: T, min_motion: T, max_range: T) -> Self {
        let seed = AdaptiveThreshold::new(initial_threshold, min_motion, max_range);
        Self {
            constant_velocity: seed,
            measured: seed,
            next_measured: false,
        }
    }

    /// Says which kind of prediction the next frame is made with.
    pub(crate) fn predict_with(&mut self, measured: bool) {
        self.next_measured = measured;
    }

    /// The estimate of the next frame's kind of prediction.
    pub(crate) fn in_use(&self) -> &AdaptiveThreshold<T> {
        if self.next_measured {
            &self.measured
        } else {
            &self.constant_velocity
        }
    }

    /// Adds a frame's model deviation to the estimate it was gated by; the frame after it is
    /// the constant-velocity model's unless a measured prediction is given again.
    pub(crate) fn update(&mut self, deviation: &Pose<T>) {
        if self.next_measured {
            self.measured.update(deviation);
        } else {
            self.constant_velocity.update(deviation);
        }
        self.next_measured = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion, Vector3};

    #[test]
    fn sigma_follows_the_formula_on_hand_computed_deviations() {
        let mut th = AdaptiveThreshold::new(2.0f64, 0.1, 100.0);
        assert_eq!(th.sigma(), 2.0);
        // Pure translation of 0.3 m: delta = 0.3 > 0.1, counted.
        th.update(&Pose::translation(0.3, 0.0, 0.0));
        assert!((th.sigma() - ((4.0 + 0.09) / 2.0f64).sqrt()).abs() < 1e-15);
        // 0.05 m: below delta_min, ignored.
        th.update(&Pose::translation(0.0, 0.05, 0.0));
        assert_eq!(th.samples(), 2);
        // Rotation of 0.002 rad about z plus 0.1 m: delta = 0.1 + 2*100*sin(0.001).
        let dev = Pose::from_parts(
            Translation3::new(0.0, 0.0, 0.1),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.002),
        );
        let delta = 0.1 + 200.0 * 0.001f64.sin();
        assert!((th.model_error(&dev) - delta).abs() < 1e-12);
        th.update(&dev);
        let want = ((4.0 + 0.09 + delta * delta) / 3.0f64).sqrt();
        assert!((th.sigma() - want).abs() < 1e-12);
    }

    #[test]
    fn each_kind_of_prediction_keeps_its_own_estimate() {
        let mut th = Thresholds::new(2.0f64, 0.1, 100.0);
        // Measured predictions err by 0.2 m for a while.
        for _ in 0..50 {
            th.predict_with(true);
            assert!(th.in_use().sigma() < 2.0 + 1e-12);
            th.update(&Pose::translation(0.2, 0.0, 0.0));
        }
        let measured = th.measured.sigma();
        assert!(measured < 0.35, "measured sigma {measured}");
        // Then the constant-velocity model predicts: its estimate is still the seed, and the
        // measured predictions' small errors do not gate it.
        assert_eq!(th.in_use().sigma(), 2.0);
        th.update(&Pose::translation(3.0, 0.0, 0.0));
        assert!((th.in_use().sigma() - ((4.0 + 9.0) / 2.0f64).sqrt()).abs() < 1e-12);
        assert_eq!(th.measured.sigma(), measured);
        // A measured prediction again: its estimate is where it was left.
        th.predict_with(true);
        assert_eq!(th.in_use().sigma(), measured);
    }
}
