//! A simulated sequence: a seeded scene ([`crate::city`], built from [`crate::shapes`] and
//! indexed by [`crate::scene`]) swept by a multi-beam sensor ([`crate::sensor`]) riding a smooth
//! parametric trajectory ([`crate::trajectory`]). Each column is cast from the pose at its own
//! capture time, so scans carry real motion distortion; ground truth is the same pose function
//! at each sweep's end. A [`Revisit`] drives the same scene again, changed, along another path.

use crate::city::{self, changes, changes::Changed};
use crate::profile::Profile;
use crate::revisit::{self, Revisit};
use crate::rng::{key, Purpose};
use crate::scene::Scene;
use crate::sensor::{self, Frame, Lidar};
use crate::trajectory::{PoseM, Trajectory};
use anyhow::{bail, Result};
use serde::Serialize;

/// Most frames one run may ask for (a longer route means a larger scene in memory).
pub const MAX_FRAMES: u64 = 100_000;

/// Longest lead-in (s): the scene is built along the whole route, the lead-in's included.
pub const MAX_LEAD_IN: f64 = 600.0;

/// Everything that determines a simulated sequence.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SimParams {
    /// Scene and motion.
    pub profile: Profile,
    /// Seed of scene, route, motion and noise.
    pub seed: u64,
    /// Sweeps.
    pub frames: u64,
    /// Sequence time of the first column (s).
    pub start_time: f64,
    /// Seconds of the drive before the first column, not swept: the sequence starts that far
    /// along the route, moving (0: at the route's start, where the car profiles stand still).
    pub lead_in: f64,
    /// The sensor.
    pub sensor: Lidar,
    /// Drive the scene again, changed, along another path, with ground truth in the frame of
    /// the first run (these same parameters without the revisit).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub revisit: Option<Revisit>,
}

impl SimParams {
    /// `frames` sweeps of `profile` under `seed` with the default sensor.
    pub fn new(profile: Profile, seed: u64, frames: u64) -> Self {
        Self {
            profile,
            seed,
            frames,
            start_time: 0.0,
            lead_in: 0.0,
            sensor: Lidar::DEFAULT,
            revisit: None,
        }
    }

    /// Checks every parameter; the message names the one at fault.
    pub fn validate(&self) -> Result<()> {
        if self.frames == 0 || self.frames > MAX_FRAMES {
            bail!("frames must be in 1..={MAX_FRAMES}");
        }
        if self.seed > i64::MAX as u64 {
            bail!("seed must be at most {}", i64::MAX);
        }
        if !self.start_time.is_finite() || self.start_time.abs() > 1e9 {
            bail!("start-time must be finite and within 1e9 s");
        }
        if !(0.0..=MAX_LEAD_IN).contains(&self.lead_in) {
            bail!("lead-in must be in 0..={MAX_LEAD_IN} s");
        }
        if let Some(r) = &self.revisit {
            r.validate()?;
        }
        self.sensor.validate().map_err(anyhow::Error::msg)
    }
}

/// A scene, a trajectory through it and a sensor: generates frames on demand.
#[derive(Clone, Debug)]
pub struct Simulation {
    params: SimParams,
    trajectory: Trajectory,
    scene: Scene,
    sweeper: sensor::Sweeper,
    first_end: PoseM,
    /// With a revisit: the first run's trajectory, whose frame ground truth is in.
    first_run: Option<Box<Trajectory>>,
    /// With a revisit: what changed in the scene.
    changed: Option<Box<Changed>>,
}

impl Simulation {
    /// Builds the scene and trajectory of validated `params`.
    pub fn new(params: SimParams) -> Result<Self> {
        params.validate()?;
        let l = params.sensor;
        let duration = (params.frames + 1) as f64 * l.period();
        let trajectory =
            Trajectory::generate_after(params.profile, params.seed, params.lead_in, duration);
        let layout = city::layout(params.profile, params.seed, trajectory.route());
        let sweeper = sensor::Sweeper::new(l, params.seed, params.start_time);
        let first_end = trajectory.pose(sweeper.end_offset(0));
        let Some(revisit) = params.revisit else {
            return Ok(Self {
                params,
                trajectory,
                scene: layout.scene(),
                sweeper,
                first_end,
                first_run: None,
                changed: None,
            });
        };
        // Back from where the first run's last sweep ended, never farther than it came.
        let last = sweeper.end_offset(params.frames - 1);
        let (from, to) = (trajectory.route_arc(0.0), trajectory.route_arc(last));
        let mean = (to - from) / last.max(1e-9);
        let (lo, hi) = revisit::SPEED_SHARE;
        let lateral = revisit::lateral_offset(params.profile);
        let path = trajectory.revisit(params.seed, to, lateral, (lo * mean, hi * mean));
        let lane = changes::Lane {
            lateral,
            span: (path.route_arc(last).min(to), to),
        };
        let changed = changes::apply(
            &layout,
            params.profile,
            trajectory.route(),
            params.seed,
            revisit.changes,
            lane,
        );
        let scene = Scene::new(layout.planes, changed.solids.clone());
        // Ray noise of its own: another drive, not the first one's noise again.
        let noise = key(&[params.seed, Purpose::Revisit as u64]);
        Ok(Self {
            params,
            trajectory: path,
            scene,
            sweeper: sensor::Sweeper::new(l, noise, params.start_time),
            first_end,
            first_run: Some(Box::new(trajectory)),
            changed: Some(Box::new(changed)),
        })
    }

    /// With a revisit, the first run's trajectory (ground truth is in its frame).
    pub fn first_run(&self) -> Option<&Trajectory> {
        self.first_run.as_deref()
    }

    /// With a revisit, what changed in the scene since the first run.
    pub fn changed(&self) -> Option<&Changed> {
        self.changed.as_deref()
    }

    /// The parameters.
    pub fn params(&self) -> &SimParams {
        &self.params
    }

    /// The scene (world frame).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The trajectory (trajectory time: seconds since the first column).
    pub fn trajectory(&self) -> &Trajectory {
        &self.trajectory
    }

    /// Trajectory time of frame `k`'s end (its last column).
    pub fn end_offset(&self, k: u64) -> f64 {
        self.sweeper.end_offset(k)
    }

    /// Ray casts frame `k`.
    pub fn frame(&self, k: u64) -> Frame {
        self.sweeper.frame(k, &self.trajectory, &self.scene)
    }

    /// Sequence time of frame `k`'s end (its last column).
    pub fn end_time(&self, k: u64) -> f64 {
        self.sweeper.sequence_time(self.sweeper.end_offset(k))
    }

    /// World-from-sensor pose at sequence time `t`.
    pub fn world_pose(&self, t: f64) -> PoseM {
        self.trajectory.pose(t - self.params.start_time)
    }

    /// World pose of the first sweep's end: the ground-truth frame's origin (with a revisit,
    /// the first run's first sweep's end).
    pub fn ground_truth_origin(&self) -> PoseM {
        self.first_end
    }

    /// Ground truth of frame `k`: the sensor at the end of sweep `k` in the frame of the sensor
    /// at the end of sweep 0 (so frame 0 is the identity); with a revisit, in the frame of the
    /// first run's sensor at the end of its sweep 0.
    pub fn ground_truth(&self, k: u64) -> PoseM {
        if self.first_run.is_some() {
            let end = self.trajectory.pose(self.sweeper.end_offset(k));
            return self.first_end.inverse() * end;
        }
        if k == 0 {
            // Exactly, rather than `T^-1 T` up to rounding.
            return PoseM::identity();
        }
        let end = self.trajectory.pose(self.sweeper.end_offset(k));
        self.first_end.inverse() * end
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lead_in_outside_0_to_600_s_or_not_a_number_is_refused_naming_it() {
        for bad in [-0.1, f64::NAN, MAX_LEAD_IN + 1.0, f64::INFINITY] {
            let mut p = SimParams::new(Profile::Urban, 0, 1);
            p.lead_in = bad;
            let e = p.validate().unwrap_err().to_string();
            assert!(e.contains("lead-in"), "{bad}: {e}");
        }
        let mut p = SimParams::new(Profile::Urban, 0, 1);
        p.lead_in = MAX_LEAD_IN;
        assert!(p.validate().is_ok());
    }
}
