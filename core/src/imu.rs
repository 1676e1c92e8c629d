//! A gyroscope as the motion prior (opt-in): Sec. III-A predicts each scan and deskews it with
//! the constant-velocity model `dT_{t-1}` (Eq. (1)); a sensor that turns fast breaks that model
//! before ICP starts. [`GyroPrior`] replaces the model's rotation by the rotation the gyroscope
//! measured over the sweep (end of the last sweep to the end of this one), keeps its
//! translation, and hands it to the odometry as the motion to predict with
//! ([`Odometry::set_measured_delta`]: kiss-icp's assignable `last_delta`, gated by the adaptive
//! threshold of measured predictions, see `threshold`). Each point is deskewed
//! with the rotation the gyroscope measured up to its own time ([`Odometry::set_sweep_rotation`],
//! unless [`ImuConfig::point_deskew`] is off: then at the sweep's mean rate). After the scan is
//! registered, the rotation ICP found is compared with the gyroscope's and the difference, as a
//! rate, corrects the gyroscope's bias estimate by a fraction ([`ImuConfig::bias_gain`]).
//!
//! Without a prior (no samples, or a gap in them) the frame is predicted as the reference
//! predicts it; an odometry never given a prior is the reference, bit for bit. The samples are
//! the caller's slice (those since the last frame): nothing is stored but the bias and a time.

use crate::deskew::{SweepRotation, SWEEP_KNOTS};
use crate::lie::{so3_exp, so3_log};
use crate::local_map::PointCodec;
use crate::odometry::Odometry;
use crate::scalar::Real;
use crate::storage::Storage;
use nalgebra::{UnitQuaternion, Vector3};

/// One IMU sample.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ImuSample<T> {
    /// Time on the IMU's clock, s.
    pub time: f64,
    /// Angular rate, rad/s, IMU axes.
    pub gyro: [T; 3],
    /// Specific force, m/s^2, IMU axes (not used by the rotation prior).
    pub accel: [T; 3],
}

/// Where the IMU sits and how the prior learns its bias.
#[derive(Clone, Copy, Debug)]
pub struct ImuConfig<T> {
    /// The IMU's axes in the LiDAR's frame (its rotation; a lever arm does not change a rate).
    pub lidar_from_imu: UnitQuaternion<T>,
    /// The IMU's clock minus the LiDAR's, s.
    pub time_offset: f64,
    /// Fraction of the disagreement between ICP's rotation and the gyroscope's taken into the
    /// bias estimate after each frame (0 keeps the bias at zero).
    pub bias_gain: T,
    /// Longest gap between samples (and between the sweep's ends and the nearest sample)
    /// that the prior bridges, s; a longer one and the frame gets no prior.
    pub max_gap: f64,
    /// Deskew each point with the rotation measured up to its time (`true`), or the whole
    /// sweep at the rate of the rotation measured over it.
    pub point_deskew: bool,
}

impl<T: Real> ImuConfig<T> {
    /// An IMU with the LiDAR's axes and clock, learning its bias at 0.1 a frame, bridging
    /// gaps up to 50 ms.
    pub fn new() -> Self {
        Self {
            lidar_from_imu: UnitQuaternion::identity(),
            time_offset: 0.0,
            bias_gain: T::of(0.1),
            max_gap: 0.05,
            point_deskew: true,
        }
    }
}

impl<T: Real> Default for ImuConfig<T> {
    fn default() -> Self {
        Self::new()
    }
}

/// What the prior did for a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Prior {
    /// The frame was predicted and deskewed with the gyroscope's rotation over this many
    /// samples.
    Used(u32),
    /// The first frame: no sweep before it to measure from.
    First,
    /// No sample in the frame's interval.
    NoSamples,
    /// A gap longer than [`ImuConfig::max_gap`] in the samples or at the sweep's ends.
    Gap,
    /// Samples out of time order or not finite.
    BadSamples,
}

impl Prior {
    /// Its name in reports: `used`, `first`, `no_samples`, `gap`, `bad_samples`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Used(_) => "used",
            Self::First => "first",
            Self::NoSamples => "no_samples",
            Self::Gap => "gap",
            Self::BadSamples => "bad_samples",
        }
    }
}

/// The gyroscope prior's state: the bias estimate and the last sweep's end.
#[derive(Clone, Copy, Debug)]
pub struct GyroPrior<T: Real> {
    config: ImuConfig<T>,
    /// Gyroscope bias, LiDAR axes, rad/s.
    bias: Vector3<T>,
    /// The last sweep's end, LiDAR clock, s.
    last_end: Option<f64>,
    /// The rotation measured for the frame being registered, its interval (s), and whether
    /// it was handed over to predict and deskew the frame.
    pending: Option<(UnitQuaternion<T>, f64, bool)>,
}

impl<T: Real> GyroPrior<T> {
    /// A prior with zero bias that has seen no frame.
    pub fn new(config: ImuConfig<T>) -> Self {
        Self {
            config,
            bias: Vector3::zeros(),
            last_end: None,
            pending: None,
        }
    }

    /// Back to the state [`Self::new`] left, for an odometry that was reset.
    pub fn reset(&mut self) {
        *self = Self::new(self.config);
    }

    /// The bias estimate, LiDAR axes, rad/s.
    pub fn bias(&self) -> [T; 3] {
        self.bias.into()
    }

    /// Before a frame whose sweep ends at `end` (LiDAR clock, s): the rotation `samples` (the
    /// IMU's, those since the last frame, in time order) measured since the last sweep's end
    /// replaces the rotation of `odom`'s motion model, and deskews the frame (see
    /// [`ImuConfig::point_deskew`]). Call [`Self::after_frame`] once the frame is registered (or
    /// skipped).
    pub fn before_frame<P: PointCodec<T>, S: Storage>(
        &mut self,
        odom: &mut Odometry<T, P, S>,
        samples: &[ImuSample<T>],
        end: f64,
    ) -> Prior {
        self.begin(odom, samples, end, true)
    }

    /// [`Self::before_frame`] that only measures: the rotation is kept for
    /// [`Self::measured`], `odom` predicts and deskews the frame as the reference does, and
    /// [`Self::after_frame`] learns nothing from it. For a gyroscope the caller does not trust
    /// (it disagreed with ICP), so that it can tell when it agrees again. Returns what
    /// [`Self::before_frame`] would have.
    pub fn measure_frame<P: PointCodec<T>, S: Storage>(
        &mut self,
        odom: &mut Odometry<T, P, S>,
        samples: &[ImuSample<T>],
        end: f64,
    ) -> Prior {
        self.begin(odom, samples, end, false)
    }

    fn begin<P: PointCodec<T>, S: Storage>(
        &mut self,
        odom: &mut Odometry<T, P, S>,
        samples: &[ImuSample<T>],
        end: f64,
        hand_over: bool,
    ) -> Prior {
        let start = self.last_end.replace(end);
        self.pending = None;
        odom.set_sweep_rotation(None);
        let Some(start) = start else {
            return Prior::First;
        };
        let (rotation, sweep) = match self.rotation(samples, start, end) {
            Ok(r) => r,
            Err(why) => return why,
        };
        if hand_over {
            let mut delta = *odom.last_delta();
            delta.rotation = rotation;
            if !odom.set_measured_delta(delta) {
                return Prior::BadSamples;
            }
            if self.config.point_deskew {
                odom.set_sweep_rotation(Some(sweep));
            }
        }
        self.pending = Some((rotation, end - start, hand_over));
        Prior::Used(samples.len() as u32)
    }

    /// The rotation the gyroscope measured over the frame being registered (less the bias,
    /// LiDAR axes) and its interval (s), until [`Self::after_frame`] or [`Self::discard`].
    pub fn measured(&self) -> Option<(UnitQuaternion<T>, f64)> {
        self.pending.map(|(q, dt, _)| (q, dt))
    }

    /// Forgets the frame's measured rotation without learning from it: the bias stays as it
    /// was (for a frame whose gyroscope the caller found wrong).
    pub fn discard(&mut self) {
        self.pending = None;
    }

    /// After the frame: the rotation ICP registered (`odom`'s new motion model) against the
    /// gyroscope's, as a rate, corrects the bias by [`ImuConfig::bias_gain`] of it. Returns
    /// that disagreement (rad/s) when the frame used the prior: a few hundredths is the bias
    /// and ICP's noise; a wrong extrinsic or clock shows as much more on fast turns.
    pub fn after_frame<P: PointCodec<T>, S: Storage>(
        &mut self,
        odom: &Odometry<T, P, S>,
    ) -> Option<T> {
        // `dt` is positive: `rotation` refused an empty interval.
        let (gyro, dt, handed) = self.pending.take()?;
        if !handed {
            return None;
        }
        let (err, _) = so3_log(&(gyro.inverse() * odom.last_delta().rotation));
        // The gyroscope turned by (rate - bias_est) where the sensor turned by (rate - bias):
        // the registered rotation is short by (bias - bias_est) dt.
        let rate = err / T::of(dt);
        let step = rate * self.config.bias_gain;
        if step.iter().all(|v| v.is_finite()) {
            self.bias -= step;
        }
        Some(rate.norm())
    }

    /// The rotation from `start` to `end` (LiDAR clock, s) of the body, LiDAR axes: each
    /// sample's rate, less the bias, over the part of the interval nearest to it; and the same
    /// rotation through the interval, at its knots.
    fn rotation(
        &self,
        samples: &[ImuSample<T>],
        start: f64,
        end: f64,
    ) -> Result<(UnitQuaternion<T>, SweepRotation<T>), Prior> {
        let (Some(first), Some(last)) = (samples.first(), samples.last()) else {
            return Err(Prior::NoSamples);
        };
        let lidar_time = |s: &ImuSample<T>| s.time - self.config.time_offset;
        let ordered = samples.windows(2).all(|w| w[0].time <= w[1].time);
        let finite = samples
            .iter()
            .all(|s| s.time.is_finite() && s.gyro.iter().all(|g| g.is_finite()));
        if !(ordered && finite && end.is_finite() && start.is_finite() && end > start) {
            return Err(Prior::BadSamples);
        }
        let gap = self.config.max_gap;
        let gaps = samples
            .windows(2)
            .any(|w| lidar_time(&w[1]) - lidar_time(&w[0]) > gap);
        if gaps || lidar_time(first) - start > gap || end - lidar_time(last) > gap {
            return Err(Prior::Gap);
        }
        let r_li = self.config.lidar_from_imu;
        let knot = |k: usize| start + (end - start) * (k as f64 / SWEEP_KNOTS as f64);
        let mut turned = [UnitQuaternion::identity(); SWEEP_KNOTS + 1];
        let mut next = 1;
        let mut q = UnitQuaternion::identity();
        let mut from = start;
        for (i, s) in samples.iter().enumerate() {
            // Each sample's rate holds from half way after the one before to half way before
            // the next: the nearest sample, no half-period lag.
            let until = samples.get(i + 1).map_or(end, |n| {
                (0.5 * (lidar_time(s) + lidar_time(n))).clamp(start, end)
            });
            if until > from {
                let rate = r_li * Vector3::from(s.gyro) - self.bias;
                while next < SWEEP_KNOTS && knot(next) <= until {
                    turned[next] = q * so3_exp(&(rate * T::of(knot(next) - from))).0;
                    next += 1;
                }
                q *= so3_exp(&(rate * T::of(until - from))).0;
                from = until;
            }
        }
        // The last interval ends at `end`: every knot is filled, the last with the whole turn.
        turned[next..].fill(q);
        Ok((q, SweepRotation::from_start(&turned)))
    }
}

#[cfg(test)]
mod tests;
