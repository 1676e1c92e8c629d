//! `[imu]`: the opt-in gyroscope prior (`kiss_odom_core::GyroPrior`). Off, the settings file
//! leaves the section out and every pose is the reference's.

use anyhow::{bail, Result};
use kiss_odom_core::{ImuConfig, Real};
use nalgebra::{Quaternion, UnitQuaternion};
use serde::{Deserialize, Serialize};

/// The gyroscope prior's settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Imu {
    /// Predict and deskew each frame with the rotation the IMU samples that come with it
    /// measured (a recording's `imu.csv` or its sensor's IMU packets).
    pub enabled: bool,
    /// The IMU's pose in the LiDAR's frame: x y z (m), then roll pitch yaw (deg, applied as
    /// Rz Ry Rx); the rotation is what the prior uses.
    pub extrinsic: [f64; 6],
    /// The IMU's clock minus the LiDAR's, s.
    pub time_offset: f64,
    /// Fraction of ICP's disagreement with the gyroscope taken into the bias each frame.
    pub bias_gain: f64,
    /// Longest gap in the samples the prior bridges, s.
    pub max_gap: f64,
    /// Deskew each point with the rotation the gyroscope measured up to its time (or, `false`,
    /// the whole sweep at the mean rate of the rotation measured over it).
    pub point_deskew: bool,
}

impl Default for Imu {
    fn default() -> Self {
        let core = ImuConfig::<f64>::new();
        Self {
            enabled: false,
            extrinsic: [0.0; 6],
            time_offset: core.time_offset,
            bias_gain: core.bias_gain,
            max_gap: core.max_gap,
            point_deskew: core.point_deskew,
        }
    }
}

impl Imu {
    /// Whether it is off with the defaults (then `config.toml` leaves it out).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// The core's configuration, if enabled; an error names the value at fault.
    pub fn core<T: Real>(&self) -> Result<Option<ImuConfig<T>>> {
        if !self.extrinsic.iter().all(|v| v.is_finite()) {
            bail!("imu.extrinsic = {:?}: not finite", self.extrinsic);
        }
        if !(0.0..=1.0).contains(&self.bias_gain) {
            bail!("imu.bias_gain = {}: not in [0, 1]", self.bias_gain);
        }
        if !(self.max_gap > 0.0 && self.max_gap <= 1.0) {
            bail!("imu.max_gap = {}: not in (0, 1] s", self.max_gap);
        }
        if !(self.time_offset.is_finite() && self.time_offset.abs() <= 1e9) {
            bail!(
                "imu.time_offset = {}: not a finite time within 1e9 s",
                self.time_offset
            );
        }
        if !self.enabled {
            return Ok(None);
        }
        let [.., roll, pitch, yaw] = self.extrinsic;
        let q = UnitQuaternion::from_euler_angles(
            roll.to_radians(),
            pitch.to_radians(),
            yaw.to_radians(),
        );
        let q = UnitQuaternion::new_unchecked(Quaternion::new(
            T::of(q.w),
            T::of(q.i),
            T::of(q.j),
            T::of(q.k),
        ));
        Ok(Some(ImuConfig {
            lidar_from_imu: q,
            time_offset: self.time_offset,
            bias_gain: T::of(self.bias_gain),
            max_gap: self.max_gap,
            point_deskew: self.point_deskew,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn off_by_default_and_bad_values_are_named() {
        assert!(Imu::default().core::<f64>().unwrap().is_none());
        let on = Imu {
            enabled: true,
            extrinsic: [0.0, 0.0, 0.0, 0.0, 0.0, 90.0],
            ..Imu::default()
        };
        let c = on.core::<f32>().unwrap().unwrap();
        let x = c.lidar_from_imu * nalgebra::Vector3::x();
        assert!((x.y - 1.0).abs() < 1e-6, "yaw 90 turns x onto y: {x:?}");
        for (bad, name) in [
            (
                Imu {
                    bias_gain: 2.0,
                    ..on
                },
                "imu.bias_gain",
            ),
            (Imu { max_gap: 0.0, ..on }, "imu.max_gap"),
            (
                Imu {
                    extrinsic: [f64::NAN; 6],
                    ..on
                },
                "imu.extrinsic",
            ),
            (
                Imu {
                    time_offset: f64::INFINITY,
                    ..on
                },
                "imu.time_offset",
            ),
        ] {
            let e = bad.core::<f64>().unwrap_err().to_string();
            assert!(e.starts_with(name), "{e}");
        }
    }
}
