//! The node's only contact with the core: build the odometry from [`Settings`], register a
//! cloud, read the pose, the last motion and the local map.
//!
//! It stands in for the shared host frame driver (`host/src/drive.rs`, not written yet): when
//! that lands, [`with_engine`] and [`Engine::register`] become calls into it and nothing else in
//! `ros2/` changes. Until then this is the fourth copy of the scalar/storage dispatch that
//! `run`, `bench` and `crosscheck` each have.

use crate::exec::Pool;
use crate::run::widen;
use crate::settings::{Scalar, Settings, Storage};
use anyhow::{anyhow, Result};
use kiss_odom_core::{Exact, FrameError, Odometry, PointCodec, Quantized, Real, Status};
use nalgebra::Isometry3;
use std::time::Instant;

/// What registering one cloud gave.
#[derive(Clone, Debug, PartialEq)]
pub struct Registered {
    /// Sensor pose in the odometry frame (the first cloud's sensor frame), widened to f64 as
    /// `kiss-odom run` writes it.
    pub pose: Isometry3<f64>,
    /// Motion from the previous registered cloud to this one, in the previous sensor frame.
    pub delta: Isometry3<f64>,
    /// The core's flags for the frame.
    pub status: Status,
    /// Points given.
    pub input_points: u32,
    /// NaN/inf points the core skipped.
    pub non_finite: u32,
    /// Whether per-point times were used to deskew.
    pub deskewed: bool,
    /// Seconds in the core's frame call.
    pub core_s: f64,
}

/// A running odometry, whatever scalar and map storage it was built with.
pub trait Engine {
    /// Registers one cloud (sensor frame) with optional per-point times. `None` when no point
    /// was usable: the state is untouched, as if the cloud had never arrived.
    fn register(&mut self, points: &[[f64; 3]], stamps: Option<&[f64]>) -> Option<Registered>;
    /// Every local-map point, in the odometry frame.
    fn local_map(&self) -> Vec<[f64; 3]>;
    /// Bytes of the core's state (fixed at start).
    fn state_bytes(&self) -> usize;
}

struct Core<T: Real, P: PointCodec<T>> {
    odom: Odometry<T, P, Box<[u64]>>,
    pool: Pool,
    scratch: Vec<[T; 3]>,
}

impl<T: Real, P: PointCodec<T>> Engine for Core<T, P> {
    fn register(&mut self, points: &[[f64; 3]], stamps: Option<&[f64]>) -> Option<Registered> {
        self.scratch.clear();
        self.scratch.extend(
            points
                .iter()
                .map(|p| [T::of(p[0]), T::of(p[1]), T::of(p[2])]),
        );
        let t0 = Instant::now();
        let result = self
            .odom
            .register_frame_with(&self.pool, &self.scratch, stamps);
        let core_s = t0.elapsed().as_secs_f64();
        match result {
            Ok(r) => Some(Registered {
                pose: widen(self.odom.pose()),
                delta: widen(self.odom.last_delta()),
                status: r.status,
                input_points: r.input_points,
                non_finite: r.dropped.non_finite,
                deskewed: r.deskewed,
                core_s,
            }),
            Err(FrameError::EmptyScan | FrameError::Storage) => None,
        }
    }

    fn local_map(&self) -> Vec<[f64; 3]> {
        let mut out = Vec::with_capacity(self.odom.map().points());
        self.odom
            .map()
            .for_each_point(|_, p| out.push([p.x.wide(), p.y.wide(), p.z.wide()]));
        out
    }

    fn state_bytes(&self) -> usize {
        self.odom.state_bytes()
    }
}

/// Builds the odometry `settings` describe and lends it to `f`; the core's storage lives for
/// the duration of the call.
pub fn with_engine<R>(
    settings: &Settings,
    f: impl FnOnce(&mut dyn Engine) -> Result<R>,
) -> Result<R> {
    match (settings.runtime.scalar, settings.runtime.map_storage) {
        (Scalar::F64, Storage::Exact) => build::<f64, Exact, R>(settings, f),
        (Scalar::F64, Storage::Quantized) => build::<f64, Quantized, R>(settings, f),
        (Scalar::F32, Storage::Exact) => build::<f32, Exact, R>(settings, f),
        (Scalar::F32, Storage::Quantized) => build::<f32, Quantized, R>(settings, f),
    }
}

fn build<T: Real, P: PointCodec<T>, R>(
    settings: &Settings,
    f: impl FnOnce(&mut dyn Engine) -> Result<R>,
) -> Result<R> {
    let config = settings.core_config::<T>()?;
    let caps = settings.capacities()?;
    let odom = Odometry::<T, P, _>::boxed(config, caps)
        .map_err(|e| anyhow!("cannot build the odometry: {e}"))?;
    let mut core = Core {
        odom,
        pool: Pool::new(settings.threads())?,
        scratch: Vec::new(),
    };
    f(&mut core)
}

#[cfg(test)]
mod tests {
    use super::*;

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
            with_engine(&s, |e| {
                let first = e.register(&room(0.0), None).unwrap();
                assert_eq!(first.pose, Isometry3::identity());
                assert!(e.register(&[], None).is_none());
                assert!(e.register(&[[f64::NAN; 3]], None).is_none());
                let second = e.register(&room(0.3), None).unwrap();
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
                assert!(!e.local_map().is_empty());
                assert!(e.state_bytes() > 0);
                Ok(())
            })
            .unwrap();
        }
    }
}
