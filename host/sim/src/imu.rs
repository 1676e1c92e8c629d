//! A strapdown IMU riding with the sensor: angular rate and specific force from the exact
//! trajectory, with white noise, a bias random walk and gravity, at a fixed rate, written as
//! `imu.csv` (the layout `kiss-odom convert` writes: `time,gyro_x,gyro_y,gyro_z,accel_x,
//! accel_y,accel_z`, seconds on the frames' clock, rad/s, m/s^2, in the IMU's axes).
//!
//! The IMU sits at a fixed pose in the LiDAR's frame, [`ImuSpec::lidar_from_imu`]. The
//! true rate is the body rate of the world-from-IMU rotation, from a central difference of the
//! trajectory's rotation over +-1 ms (its error is 1e-7 of the rate); the true specific force
//! is `R^T (a - g)` with the IMU's acceleration `a` from a central second difference of its
//! position over +-1 ms and `g = (0, 0, -9.80665)` in the world (z up). A level IMU at rest
//! reads `(0, 0, +9.80665)`. The noise model is the usual one (Kalibr's): per sample,
//! white noise of `density * sqrt(rate)` and a bias that walks by `walk * sqrt(1 / rate)`,
//! starting from a turn-on bias drawn per seed.

use crate::rng::{key, Purpose, Stream};
use crate::simulation::Simulation;
use crate::trajectory::{rotation_zyx, PoseM};
use nalgebra::{Rotation3, Translation3, Vector3};
use serde::Serialize;
use std::fmt::Write as _;

/// Standard gravity, m/s^2.
pub const GRAVITY: f64 = 9.80665;

/// The file's name beside the frames.
pub const CSV_NAME: &str = "imu.csv";

/// Its header row.
pub const CSV_HEADER: &str = "time,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z";

/// Half the step of the central differences, s.
const STEP: f64 = 1e-3;

/// What the IMU is and where it sits.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ImuSpec {
    /// Samples per second (Hz).
    pub rate_hz: f64,
    /// Gyroscope white noise, rad/s/sqrt(Hz).
    pub gyro_noise_density: f64,
    /// Accelerometer white noise, m/s^2/sqrt(Hz).
    pub accel_noise_density: f64,
    /// Gyroscope bias random walk, rad/s^2/sqrt(Hz).
    pub gyro_bias_walk: f64,
    /// Accelerometer bias random walk, m/s^3/sqrt(Hz).
    pub accel_bias_walk: f64,
    /// Largest turn-on gyroscope bias per axis, rad/s (drawn uniformly per seed).
    pub gyro_bias_max: f64,
    /// Largest turn-on accelerometer bias per axis, m/s^2.
    pub accel_bias_max: f64,
    /// The IMU's pose in the LiDAR's frame: x y z (m), then roll pitch yaw (deg, applied as
    /// Rz Ry Rx).
    pub lidar_from_imu: [f64; 6],
    /// The IMU's clock minus the frames' clock, s.
    pub time_offset: f64,
}

impl ImuSpec {
    /// A MEMS IMU as LiDARs carry one (noise of the ICM-20948 class an Ouster has), at
    /// `rate_hz`, placed as the Livox Mid-360's (11, 23, -44 mm, axes aligned), clocks in sync.
    pub fn mems(rate_hz: f64) -> Self {
        Self {
            rate_hz,
            gyro_noise_density: 2.6e-4,
            accel_noise_density: 2.3e-3,
            gyro_bias_walk: 2.0e-5,
            accel_bias_walk: 3.0e-4,
            gyro_bias_max: 0.01,
            accel_bias_max: 0.05,
            lidar_from_imu: [0.011, 0.02329, -0.04412, 0.0, 0.0, 0.0],
            time_offset: 0.0,
        }
    }

    /// The same IMU without noise or bias: the exact rates and forces.
    pub fn exact(self) -> Self {
        Self {
            gyro_noise_density: 0.0,
            accel_noise_density: 0.0,
            gyro_bias_walk: 0.0,
            accel_bias_walk: 0.0,
            gyro_bias_max: 0.0,
            accel_bias_max: 0.0,
            ..self
        }
    }

    /// Checks every parameter; the message names the one at fault.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.rate_hz.is_finite() && (1.0..=4000.0).contains(&self.rate_hz)) {
            return Err("imu-rate must be in 1..=4000 Hz".into());
        }
        let noise = [
            self.gyro_noise_density,
            self.accel_noise_density,
            self.gyro_bias_walk,
            self.accel_bias_walk,
            self.gyro_bias_max,
            self.accel_bias_max,
        ];
        if !noise.iter().all(|v| v.is_finite() && *v >= 0.0) {
            return Err("IMU noise parameters must be finite and not negative".into());
        }
        if !self.lidar_from_imu.iter().all(|v| v.is_finite()) || !self.time_offset.is_finite() {
            return Err("the IMU's extrinsic and time offset must be finite".into());
        }
        Ok(())
    }

    /// The IMU's pose in the LiDAR's frame.
    pub fn extrinsic(&self) -> PoseM {
        let [x, y, z, roll, pitch, yaw] = self.lidar_from_imu;
        let r = rotation_zyx(roll.to_radians(), pitch.to_radians(), yaw.to_radians());
        PoseM::from_parts(Translation3::new(x, y, z), r)
    }
}

/// One IMU sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuSample {
    /// Time on the IMU's clock, s.
    pub time: f64,
    /// Angular rate, rad/s, IMU axes.
    pub gyro: [f64; 3],
    /// Specific force, m/s^2, IMU axes.
    pub accel: [f64; 3],
}

impl ImuSample {
    /// Its `imu.csv` row, with a line end (times to the nanosecond, the rest exact).
    pub fn push_csv_row(&self, out: &mut String) {
        let [gx, gy, gz] = self.gyro;
        let [ax, ay, az] = self.accel;
        let _ = writeln!(out, "{:.9},{gx},{gy},{gz},{ax},{ay},{az}", self.time);
    }
}

/// The turn-on biases a seed draws: gyroscope, accelerometer.
pub fn turn_on_bias(spec: &ImuSpec, seed: u64) -> ([f64; 3], [f64; 3]) {
    let mut rng = Stream::new(seed, Purpose::Imu);
    let mut draw = |max: f64| [0; 3].map(|_| rng.range(-max, max));
    let gyro = draw(spec.gyro_bias_max);
    (gyro, draw(spec.accel_bias_max))
}

/// The exact rate and specific force of the IMU at trajectory time `t`.
pub fn exact(sim: &Simulation, extrinsic: &PoseM, t: f64) -> ([f64; 3], [f64; 3]) {
    let imu = |t: f64| sim.trajectory().pose(t) * extrinsic;
    let (before, now, after) = (imu(t - STEP), imu(t), imu(t + STEP));
    let rate = rotation_log(&(before.rotation.inverse() * after.rotation)) / (2.0 * STEP);
    let a = (after.translation.vector - 2.0 * now.translation.vector + before.translation.vector)
        / (STEP * STEP);
    let force = now.rotation.inverse() * (a + Vector3::new(0.0, 0.0, GRAVITY));
    (rate.into(), force.into())
}

/// The rotation vector of `r` (axis times angle), on `libm` so the bits are the same
/// everywhere.
fn rotation_log(r: &Rotation3<f64>) -> Vector3<f64> {
    let m = r.matrix();
    let w = 0.5
        * Vector3::new(
            m[(2, 1)] - m[(1, 2)],
            m[(0, 2)] - m[(2, 0)],
            m[(1, 0)] - m[(0, 1)],
        );
    let s = libm::sqrt(w.dot(&w));
    let c = 0.5 * (m.trace() - 1.0);
    let angle = libm::atan2(s, c);
    if s > 0.0 {
        w * (angle / s)
    } else {
        w
    }
}

/// The samples from trajectory time 0 to `until` (s), on the frames' clock plus the IMU's
/// offset: sample `k` at `start_time + k / rate`.
pub fn samples(sim: &Simulation, spec: &ImuSpec, until: f64) -> Vec<ImuSample> {
    let extrinsic = spec.extrinsic();
    let dt = 1.0 / spec.rate_hz;
    let n = (until.max(0.0) * spec.rate_hz).floor() as u64 + 1;
    let (mut gyro_bias, mut accel_bias) = turn_on_bias(spec, sim.params().seed);
    let white = |d: f64| d * libm::sqrt(spec.rate_hz);
    let walk = |w: f64| w * libm::sqrt(dt);
    let start = sim.params().start_time;
    (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            let (rate, force) = exact(sim, &extrinsic, t);
            let mut rng = Stream::from_key(key(&[sim.params().seed, Purpose::Imu as u64, k]));
            let mut normal3 = || [rng.normal(), rng.normal(), rng.normal()];
            let (ng, na, wg, wa) = (normal3(), normal3(), normal3(), normal3());
            let mut gyro = [0.0; 3];
            let mut accel = [0.0; 3];
            for i in 0..3 {
                gyro[i] = rate[i] + gyro_bias[i] + white(spec.gyro_noise_density) * ng[i];
                accel[i] = force[i] + accel_bias[i] + white(spec.accel_noise_density) * na[i];
                gyro_bias[i] += walk(spec.gyro_bias_walk) * wg[i];
                accel_bias[i] += walk(spec.accel_bias_walk) * wa[i];
            }
            ImuSample {
                time: start + t + spec.time_offset,
                gyro,
                accel,
            }
        })
        .collect()
}

/// `imu.csv`'s text for `samples`.
pub fn csv(samples: &[ImuSample]) -> String {
    let mut out = String::with_capacity(samples.len() * 120 + CSV_HEADER.len() + 1);
    out.push_str(CSV_HEADER);
    out.push('\n');
    for s in samples {
        s.push_csv_row(&mut out);
    }
    out
}

#[cfg(test)]
mod tests;
