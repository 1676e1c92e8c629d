//! The node's contact with the core: the host's frame driver ([`kiss_odom_drive::Driver`]), built
//! from [`Settings`] so that an empty cloud leaves the state untouched ([`OnEmpty::Ignore`]),
//! and what the node publishes from one registered cloud.

use anyhow::Result;
use kiss_odom_core::localize::Located;
use kiss_odom_core::Status;
use kiss_odom_drive::localize::MapLocalizer;
use kiss_odom_drive::settings::Settings;
use kiss_odom_drive::{Driver, OnEmpty, Step};
use kiss_odom_io::Frame;
use nalgebra::Isometry3;

/// What registering one cloud gave.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Registered {
    /// Sensor pose in the odometry frame (the first cloud's sensor frame), widened to f64 as
    /// `kiss-odom run` writes it.
    pub(crate) pose: Isometry3<f64>,
    /// Motion from the previous registered cloud to this one, in the previous sensor frame.
    pub(crate) delta: Isometry3<f64>,
    /// The core's flags for the frame.
    pub(crate) status: Status,
    /// Points given.
    pub(crate) input_points: u32,
    /// NaN/inf points the core skipped.
    pub(crate) non_finite: u32,
    /// Whether per-point times were used to deskew.
    pub(crate) deskewed: bool,
    /// Seconds in the core's frame call.
    pub(crate) core_s: f64,
    /// With a prior map: the cloud localized in it (the sensor's pose in the map frame).
    pub(crate) located: Option<Located<f64>>,
}

/// The node's driver for `settings`.
pub(crate) fn driver(settings: &Settings) -> Result<Driver> {
    let mut d = Driver::new(settings)?;
    d.on_empty(OnEmpty::Ignore);
    Ok(d)
}

/// Registers a cloud's frame (sensor frame, optional per-point times, and with the gyroscope
/// prior on the IMU samples up to its sweep's end), then localizes it in `map` if one is given.
/// `None` when no point was usable: the odometry and the localizer are untouched, as if the
/// cloud had never arrived.
pub(crate) fn register(
    driver: &mut Driver,
    frame: &Frame,
    map: Option<&mut MapLocalizer>,
) -> Result<Option<Registered>> {
    let outcome = driver.register(frame)?;
    let Step::Registered(r) = &outcome.step else {
        return Ok(None);
    };
    let located = map.map(|m| m.locate(driver, &outcome));
    Ok(Some(Registered {
        pose: outcome.pose,
        delta: driver.last_delta(),
        status: r.status,
        input_points: r.input_points,
        non_finite: r.dropped.non_finite,
        deskewed: r.deskewed,
        core_s: outcome.latency.as_secs_f64(),
        located,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use kiss_odom_drive::settings::{Scalar, Storage};

    /// An irregular room seen from a sensor at `x`: scattered points on five planes (a
    /// regular grid would let ICP slide by one grid step).
    fn room(x: f64) -> Vec<[f64; 3]> {
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut pts = Vec::new();
        for _ in 0..800 {
            let (u, v, w) = (rnd() * 20.0 - 10.0, rnd() * 4.0 - 2.0, rnd());
            pts.push(match (w * 5.0) as u32 {
                0 => [12.0 - x, u, v],
                1 => [-12.0 - x, u * 0.7, v + u * 0.1],
                2 => [u - x, 11.0, v],
                3 => [u * 0.8 - x, -9.0 + 0.2 * v, v],
                _ => [u - x, v * 4.0, -2.5],
            });
        }
        pts
    }

    #[test]
    fn every_configuration_registers_and_an_empty_cloud_leaves_no_trace() {
        for (scalar, storage) in [
            (Scalar::F64, Storage::Exact),
            (Scalar::F32, Storage::Quantized),
        ] {
            let mut s = Settings::default();
            s.data.max_range = 30.0;
            s.runtime.scalar = scalar;
            s.runtime.map_storage = storage;
            s.runtime.threads = 1;
            s.capacities = kiss_odom_core::Capacities::SMALL.into();
            let mut d = driver(&s).unwrap();
            let mut reg = |pts: &[[f64; 3]]| {
                let frame = Frame {
                    points: pts.to_vec(),
                    ..Frame::default()
                };
                register(&mut d, &frame, None).unwrap()
            };
            {
                let first = reg(&room(0.0)).unwrap();
                assert_eq!(first.pose, Isometry3::identity());
                assert!(reg(&[]).is_none());
                assert!(reg(&[[f64::NAN; 3]]).is_none());
                let second = reg(&room(0.3)).unwrap();
                assert!(
                    (second.pose.translation.x - 0.3).abs() < 0.05,
                    "{scalar:?}: x = {}",
                    second.pose.translation.x
                );
                let gap = (second.delta.inverse() * second.pose)
                    .translation
                    .vector
                    .norm();
                assert!(gap < 1e-12, "delta from the identity is the pose ({gap})");
            }
            assert!(!d.map_points().is_empty());
            assert!(d.build().state_bytes > 0);
        }
    }
}
