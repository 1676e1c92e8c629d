//! The spinning multi-beam LiDAR and the sweep loop that produces one scan.
//!
//! Columns fire at uniform times across the sweep, column `c` of frame `k` at
//! `start + (k C + c) / (C f)`, sweeping clockwise from the back (azimuth `pi` down to
//! `-pi`, as a Velodyne mounted KITTI-style). All beams of a column share the sensor pose at
//! that instant, so a scan carries the real motion distortion of a moving sensor. A sweep's
//! "end" is its last column's time: that is the instant deskewing moves points to (the
//! largest timestamp in the scan), so ground truth is reported there.

use crate::rng::{key, Purpose, Stream};
use crate::scene::{Scene, Surface};
use crate::trajectory::{PoseM, Trajectory};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use serde::Serialize;

/// Sensor parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Lidar {
    /// Laser beams per column (rows).
    pub beams: u32,
    /// Columns (firings) per sweep.
    pub columns: u32,
    /// Elevation of the highest beam (deg).
    pub fov_up_deg: f64,
    /// Elevation of the lowest beam (deg).
    pub fov_down_deg: f64,
    /// Sweeps per second (Hz).
    pub rate_hz: f64,
    /// Returns closer than this are dropped (m).
    pub min_range: f64,
    /// No return beyond this (m).
    pub max_range: f64,
    /// Standard deviation of the Gaussian range noise (m).
    pub noise: f64,
    /// Probability that a return is lost.
    pub dropout: f64,
}

impl Lidar {
    /// A 64 x 1024 sensor over -25..+3 deg at 10 Hz, 1-100 m, 1.5 cm noise (HDL-64-like).
    pub const DEFAULT: Self = Self {
        beams: 64,
        columns: 1024,
        fov_up_deg: 3.0,
        fov_down_deg: -25.0,
        rate_hz: 10.0,
        min_range: 1.0,
        max_range: 100.0,
        noise: 0.015,
        dropout: 0.0,
    };

    /// Checks that every parameter is finite and in a sensible range.
    pub fn validate(&self) -> Result<(), String> {
        let ok = |c: bool, what: &str| if c { Ok(()) } else { Err(what.to_string()) };
        ok((1..=512).contains(&self.beams), "beams must be in 1..=512")?;
        ok(
            (8..=16384).contains(&self.columns),
            "columns must be in 8..=16384",
        )?;
        ok(
            self.fov_down_deg.is_finite()
                && self.fov_up_deg.is_finite()
                && -89.0 <= self.fov_down_deg
                && self.fov_up_deg <= 89.0
                && (self.fov_down_deg < self.fov_up_deg
                    || (self.beams == 1 && self.fov_down_deg <= self.fov_up_deg)),
            "need -89 <= fov-down < fov-up <= 89 degrees",
        )?;
        ok(
            self.rate_hz.is_finite() && self.rate_hz >= 0.1 && self.rate_hz <= 100.0,
            "rate-hz must be in [0.1, 100]",
        )?;
        ok(
            self.min_range.is_finite()
                && self.max_range.is_finite()
                && 0.0 <= self.min_range
                && self.min_range < self.max_range
                && self.max_range <= 1000.0,
            "need 0 <= min-range < max-range <= 1000 m",
        )?;
        ok(
            self.noise.is_finite() && (0.0..=1.0).contains(&self.noise),
            "noise must be in [0, 1] m",
        )?;
        ok(
            self.dropout.is_finite() && (0.0..1.0).contains(&self.dropout),
            "dropout must be in [0, 1)",
        )
    }

    /// Sweep period (s).
    pub fn period(&self) -> f64 {
        1.0 / self.rate_hz
    }
}

/// One scan, in the order the sensor produced it (column by column, beams bottom to top).
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Frame number from 0.
    pub index: u64,
    /// x, y, z (sensor frame at capture time, m) and intensity in `[0, 1]`.
    pub points: Vec<[f32; 4]>,
    /// Capture time of each point (s, sequence time).
    pub stamps: Vec<f64>,
    /// The surface each point came from (not written; for checking ground truth).
    pub surfaces: Vec<Surface>,
    /// The sweep's end (its last column's time, s).
    pub end_time: f64,
}

/// Precomputed beam directions in the sensor frame: `cos/sin` of each elevation and azimuth.
#[derive(Clone, Debug)]
struct Beams {
    elevation: Vec<[f64; 2]>,
    azimuth: Vec<[f64; 2]>,
}

impl Beams {
    fn new(l: &Lidar) -> Self {
        let deg = core::f64::consts::PI / 180.0;
        let elevation = (0..l.beams)
            .map(|b| {
                let f = if l.beams == 1 {
                    0.5
                } else {
                    b as f64 / (l.beams - 1) as f64
                };
                let e = (l.fov_down_deg + f * (l.fov_up_deg - l.fov_down_deg)) * deg;
                [libm::cos(e), libm::sin(e)]
            })
            .collect();
        let azimuth = (0..l.columns)
            .map(|c| {
                let a =
                    core::f64::consts::PI - core::f64::consts::TAU * c as f64 / l.columns as f64;
                [libm::cos(a), libm::sin(a)]
            })
            .collect();
        Self { elevation, azimuth }
    }

    #[inline]
    fn direction(&self, column: usize, beam: usize) -> Vector3<f64> {
        let [ce, se] = self.elevation[beam];
        let [ca, sa] = self.azimuth[column];
        Vector3::new(ce * ca, ce * sa, se)
    }
}

/// A sensor riding a trajectory through a scene.
#[derive(Clone, Debug)]
pub struct Sweeper {
    lidar: Lidar,
    seed: u64,
    start_time: f64,
    beams: Beams,
}

/// One return before it is flattened into a frame.
type Return = ([f32; 4], f64, Surface);

impl Sweeper {
    /// A sweeper for a validated `lidar`; times are offset by `start_time`.
    pub fn new(lidar: Lidar, seed: u64, start_time: f64) -> Self {
        Self {
            beams: Beams::new(&lidar),
            lidar,
            seed,
            start_time,
        }
    }

    /// Trajectory time (s since the first column) of column `c` of frame `k`.
    pub fn column_offset(&self, k: u64, c: u32) -> f64 {
        // Exact (integer-valued f64 below 2^53) and overflow-free for any `k`.
        let cols = self.lidar.columns as f64;
        (k as f64 * cols + c as f64) / (cols * self.lidar.rate_hz)
    }

    /// Trajectory time of frame `k`'s end (its last column).
    pub fn end_offset(&self, k: u64) -> f64 {
        self.column_offset(k, self.lidar.columns - 1)
    }

    /// Sequence time of a trajectory time.
    pub fn sequence_time(&self, offset: f64) -> f64 {
        self.start_time + offset
    }

    /// Casts every beam of frame `k`. Columns run in parallel; the result does not depend on
    /// the thread count (each ray's randomness is keyed by its indices).
    pub fn frame(&self, k: u64, trajectory: &Trajectory, scene: &Scene) -> Frame {
        let columns: Vec<Vec<Return>> = (0..self.lidar.columns)
            .into_par_iter()
            .map(|c| self.column(k, c, trajectory, scene))
            .collect();
        let n = columns.iter().map(Vec::len).sum();
        let mut frame = Frame {
            index: k,
            points: Vec::with_capacity(n),
            stamps: Vec::with_capacity(n),
            surfaces: Vec::with_capacity(n),
            end_time: self.sequence_time(self.end_offset(k)),
        };
        for (p, t, s) in columns.into_iter().flatten() {
            frame.points.push(p);
            frame.stamps.push(t);
            frame.surfaces.push(s);
        }
        frame
    }

    fn column(&self, k: u64, c: u32, trajectory: &Trajectory, scene: &Scene) -> Vec<Return> {
        let l = &self.lidar;
        let offset = self.column_offset(k, c);
        let stamp = self.sequence_time(offset);
        let pose: PoseM = trajectory.pose(offset);
        let rot = pose.rotation.matrix();
        let origin = Point3::from(pose.translation.vector);
        let mut out = Vec::with_capacity(l.beams as usize);
        for b in 0..l.beams as usize {
            let ds = self.beams.direction(c as usize, b);
            let dw = rot * ds;
            let Some(hit) = scene.cast(&origin, &dw, l.max_range) else {
                continue;
            };
            let mut rng = Stream::from_key(key(&[
                self.seed,
                Purpose::Ray as u64,
                k,
                c as u64,
                b as u64,
            ]));
            let [n_range, n_speckle] = rng.normal_pair();
            let range = hit.t + l.noise * n_range;
            let lost = rng.chance(l.dropout);
            if lost || range < l.min_range || range > l.max_range {
                continue;
            }
            // Diffuse (Lambert-ish) falloff with incidence, a little with range, some speckle.
            let cos_inc = hit.normal.dot(&dw).abs();
            let intensity = hit.reflectivity as f64
                * (0.3 + 0.7 * cos_inc)
                * (1.0 - 0.25 * range / l.max_range)
                + 0.02 * n_speckle;
            let p = ds * range;
            out.push((
                [
                    p.x as f32,
                    p.y as f32,
                    p.z as f32,
                    intensity.clamp(0.0, 1.0) as f32,
                ],
                stamp,
                hit.surface,
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use crate::profile::Profile;
    use crate::simulation::{SimParams, Simulation};

    fn small(profile: Profile, noise: f64) -> Simulation {
        let mut p = SimParams::new(profile, 1, 20);
        p.sensor.beams = 32;
        p.sensor.columns = 512;
        p.sensor.noise = noise;
        Simulation::new(p).unwrap()
    }

    #[test]
    fn frames_do_not_depend_on_the_thread_count() {
        let sim = small(Profile::Urban, 0.015);
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| sim.frame(7))
        };
        let one = run(1);
        assert!(!one.points.is_empty());
        assert_eq!(one, run(3));
        assert_eq!(one, run(8));
    }

    #[test]
    fn stamps_are_column_times_ending_at_the_sweep_end() {
        let sim = small(Profile::Urban, 0.015);
        let l = sim.params().sensor;
        for k in [0, 5, 19] {
            let f = sim.frame(k);
            assert_eq!(f.points.len(), f.stamps.len());
            assert!(
                f.stamps.windows(2).all(|w| w[0] <= w[1]),
                "stamps must be in order"
            );
            let (lo, hi) = (f.stamps[0], f.stamps[f.stamps.len() - 1]);
            assert_eq!(hi, f.end_time, "the sweep ends with its last column");
            assert!((lo - k as f64 * l.period()).abs() < 1e-12);
            let span = (l.columns - 1) as f64 / l.columns as f64 * l.period();
            assert!((hi - lo - span).abs() < 1e-12);
            let distinct = f.stamps.windows(2).filter(|w| w[0] != w[1]).count() + 1;
            assert!(
                distinct > l.columns as usize * 9 / 10,
                "{distinct} distinct times"
            );
        }
    }

    #[test]
    fn returns_respect_the_range_limits_and_intensity_band() {
        let sim = small(Profile::Fast, 0.02);
        let l = sim.params().sensor;
        let f = sim.frame(3);
        for p in &f.points {
            let r = (p[0] as f64).hypot(p[1] as f64).hypot(p[2] as f64);
            assert!(
                r >= l.min_range - 1e-4 && r <= l.max_range + 1e-4,
                "range {r}"
            );
            assert!((0.0..=1.0).contains(&p[3]));
        }
    }

    #[test]
    fn noiseless_points_lie_exactly_on_the_surface_they_hit() {
        for profile in [
            Profile::Urban,
            Profile::Corridor,
            Profile::Fast,
            Profile::Plane,
            Profile::Tunnel,
            Profile::Field,
            Profile::Suburban,
            Profile::Forest,
            Profile::Handheld,
            Profile::Drone,
        ] {
            let sim = small(profile, 0.0);
            let f = sim.frame(4);
            let mut worst: f64 = 0.0;
            for ((p, t), s) in f.points.iter().zip(&f.stamps).zip(&f.surfaces) {
                let local = nalgebra::Point3::new(p[0] as f64, p[1] as f64, p[2] as f64);
                let w = sim.world_pose(*t) * local;
                worst = worst.max(sim.scene().distance_to(*s, &w).unwrap());
            }
            println!("{profile:?}: worst distance {worst:.2e} m (tol 1e-4, f32 rounding)");
            assert!(worst < 1e-4);
        }
    }
}
