//! Step 1 (Sec. III-A): motion compensation ("deskewing") with the constant velocity model.
//!
//! The paper writes Eq. (4) as `p* = Exp(s w) p + s v` with `s` the time since the sweep began.
//! The reference moves every point to the *end* of the sweep instead: with the last frame's
//! relative motion `dT` (Eq. (1)) and timestamps normalised per scan to
//! `s = (t - t_min) / (t_max - t_min)`, each point becomes `Exp((s - 1) Log(dT)) p`. Poses
//! are therefore end-of-sweep poses. We follow the reference.

use crate::geometry::{Point, Pose};
use crate::lie::{se3_exp, se3_log, so3_exp, so3_log};
use crate::scalar::Real;
use nalgebra::{UnitQuaternion, Vector3, Vector6};

/// Why a scan's timestamps were not used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StampProblem {
    /// Fewer or more timestamps than points.
    Length,
    /// A NaN or infinite timestamp (the reference would deskew with NaN).
    NonFinite,
    /// All timestamps equal: the reference divides 0 by 0 and produces NaN points.
    Constant,
}

/// Per-scan timestamp normalisation `s = (t - min) / (max - min)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeSpan {
    min: f64,
    max: f64,
}

impl TimeSpan {
    /// Checks a scan's timestamps (any offset and unit) and finds their span.
    pub fn of(stamps: &[f64], points: usize) -> Result<Self, StampProblem> {
        if stamps.len() != points {
            return Err(StampProblem::Length);
        }
        let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
        for &t in stamps {
            if !t.is_finite() {
                return Err(StampProblem::NonFinite);
            }
            min = min.min(t);
            max = max.max(t);
        }
        Self::new(min, max)
    }

    /// The span of a sweep from its first and last capture times, for scans that arrive in
    /// pieces (the sensor driver knows the sweep's span before the last packet).
    pub fn new(min: f64, max: f64) -> Result<Self, StampProblem> {
        if !(min.is_finite() && max.is_finite()) {
            return Err(StampProblem::NonFinite);
        }
        if max - min <= 0.0 || !(max - min).is_finite() {
            return Err(StampProblem::Constant);
        }
        Ok(Self { min, max })
    }

    /// The normalised time of `t`, in `[0, 1]`.
    #[inline]
    pub fn normalise(&self, t: f64) -> f64 {
        (t - self.min) / (self.max - self.min)
    }
}

/// Intervals of a sweep at whose ends [`SweepRotation`] keeps the rotation.
pub const SWEEP_KNOTS: usize = 16;

/// How the sensor turned through one sweep when its rate was not constant (measured, e.g. by a
/// gyroscope): the rotation from the sensor's axes at normalised time `s` to its axes at the
/// sweep's end, kept at `s = k / SWEEP_KNOTS` and at a constant rate between those knots.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweepRotation<T: Real> {
    /// `knots[k]`: the rotation from the axes at `s = k / SWEEP_KNOTS` to the end's.
    knots: [UnitQuaternion<T>; SWEEP_KNOTS],
    /// `steps[k]`: the rotation vector from knot `k` to knot `k + 1`, worked out once here
    /// rather than for every point time.
    steps: [Vector3<T>; SWEEP_KNOTS],
}

impl<T: Real> SweepRotation<T> {
    /// From the body's rotation since the sweep's start at each knot (`turned[0]` the
    /// identity, `turned[SWEEP_KNOTS]` the whole sweep's).
    pub fn from_start(turned: &[UnitQuaternion<T>; SWEEP_KNOTS + 1]) -> Self {
        let to_end = turned[SWEEP_KNOTS].inverse();
        let all = turned.map(|q| to_end * q);
        Self {
            knots: core::array::from_fn(|k| all[k]),
            steps: core::array::from_fn(|k| so3_log(&(all[k].inverse() * all[k + 1])).0),
        }
    }

    /// The rotation from the axes at normalised time `s` to the end's; outside `[0, 1]` the
    /// first or last interval's rate goes on.
    pub fn at(&self, s: f64) -> UnitQuaternion<T> {
        let x = s * SWEEP_KNOTS as f64;
        // In range, and 0 for NaN: `as` saturates.
        let k = (libm::floor(x) as usize).min(SWEEP_KNOTS - 1);
        self.knots[k] * so3_exp(&(self.steps[k] * T::of(x - k as f64))).0
    }
}

/// The motion of one sweep as deskewing applies it: Eq. (4) in the reference's end-of-sweep
/// form, the sensor at normalised time `s` moved by `Exp((s - 1) Log(dT))` to the end, its
/// rotation replaced by a measured [`SweepRotation`] when there is one.
#[derive(Clone, Copy, Debug)]
pub struct SweepMotion<T: Real> {
    xi: Vector6<T>,
    rotation: Option<SweepRotation<T>>,
}

impl<T: Real> SweepMotion<T> {
    /// The motion of a sweep that moved by `relative_motion` (the last frame's delta), turning
    /// as `rotation` measured if given (the translation stays `relative_motion`'s).
    pub fn new(relative_motion: &Pose<T>, rotation: Option<SweepRotation<T>>) -> Self {
        Self {
            xi: se3_log(relative_motion),
            rotation,
        }
    }

    /// The motion from the sensor at normalised time `s` to the sweep's end.
    pub fn at(&self, s: f64) -> Pose<T> {
        let mut m = se3_exp(&(self.xi * T::of(s - 1.0)));
        if let Some(r) = &self.rotation {
            m.rotation = r.at(s);
        }
        m
    }
}

/// Applies a [`SweepMotion`] to the points of one scan.
pub struct Deskewer<T: Real> {
    motion: SweepMotion<T>,
    span: TimeSpan,
    cached_s: f64,
    cached: Pose<T>,
}

impl<T: Real> Deskewer<T> {
    /// A deskewer for a scan whose sweep moved by `relative_motion` (the last frame's delta).
    pub fn new(relative_motion: &Pose<T>, span: TimeSpan) -> Self {
        Self::turning(relative_motion, None, span)
    }

    /// The same, with the sensor's rotation through the sweep measured (`Some`) instead of
    /// the constant rate of `relative_motion`'s; the translation stays `relative_motion`'s.
    pub fn turning(
        relative_motion: &Pose<T>,
        rotation: Option<SweepRotation<T>>,
        span: TimeSpan,
    ) -> Self {
        Self {
            motion: SweepMotion::new(relative_motion, rotation),
            span,
            cached_s: f64::NAN,
            cached: Pose::identity(),
        }
    }

    /// The deskewed position of `p` captured at raw time `t`.
    #[inline]
    pub fn apply(&mut self, p: &Point<T>, t: f64) -> Point<T> {
        let s = self.span.normalise(t);
        // Sensors fire many points at one instant: reuse the pose while the time repeats.
        if s.to_bits() != self.cached_s.to_bits() {
            self.cached = self.motion.at(s);
            self.cached_s = s;
        }
        self.cached * p
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion, Vector3};

    #[test]
    fn timestamps_are_checked_for_length_finiteness_and_spread() {
        assert_eq!(TimeSpan::of(&[1.0, 2.0], 3), Err(StampProblem::Length));
        assert_eq!(
            TimeSpan::of(&[1.0, f64::NAN], 2),
            Err(StampProblem::NonFinite)
        );
        assert_eq!(TimeSpan::of(&[5.0, 5.0], 2), Err(StampProblem::Constant));
        let span = TimeSpan::of(&[1e9 + 0.05, 1e9, 1e9 + 0.1], 3).unwrap();
        assert_eq!(span.normalise(1e9), 0.0);
        assert_eq!(span.normalise(1e9 + 0.1), 1.0);
    }

    /// Sensor pose at time `tau` of a vehicle driving at speed `u` with yaw rate `w` while
    /// climbing at `c`: the closed-form kinematics of a constant velocity, written without
    /// any Lie-group code.
    fn screw_pose(tau: f64, u: f64, w: f64, c: f64) -> Pose<f64> {
        let x = u / w * (w * tau).sin();
        let y = u / w * (1.0 - (w * tau).cos());
        Pose::from_parts(
            Translation3::new(x, y, c * tau),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), w * tau),
        )
    }

    #[test]
    fn deskew_restores_a_scan_recorded_under_constant_velocity() {
        let (u, w, c, sweep) = (15.0, 0.8, 0.4, 0.1);
        let end = screw_pose(sweep, u, w, c);
        // The relative motion the odometry would have estimated over one sweep.
        let motion = screw_pose(0.0, u, w, c).inverse() * end;
        let world = [
            Point::new(10.0, 2.0, -1.0),
            Point::new(-4.0, 7.5, 0.3),
            Point::new(0.5, -20.0, 2.0),
            Point::new(30.0, 30.0, -1.7),
            Point::new(-60.0, 1.0, 4.0),
        ];
        let stamps = [0.0, 0.021, 0.05, 0.077, 0.1];
        let mut d = Deskewer::new(&motion, TimeSpan::of(&stamps, 5).unwrap());
        for (w_pt, &t) in world.iter().zip(stamps.iter()) {
            let recorded = screw_pose(t, u, w, c).inverse() * w_pt;
            let undistorted = end.inverse() * w_pt;
            let restored = d.apply(&recorded, t);
            assert!(
                (restored - undistorted).norm() < 1e-12,
                "{restored} vs {undistorted}"
            );
        }
    }

    #[test]
    fn with_identity_motion_points_are_unchanged_bit_for_bit() {
        let span = TimeSpan::of(&[0.0, 1.0], 2).unwrap();
        let mut d = Deskewer::<f64>::new(&Pose::identity(), span);
        let p = Point::new(3.25, -1.0 / 3.0, 7.0);
        assert_eq!(d.apply(&p, 0.4), p);
    }
}
