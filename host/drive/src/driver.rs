//! The frame driver: the one way frames go through the core on the host.
//!
//! A [`Driver`] owns the odometry (any scalar and map storage, chosen by the settings) and its
//! worker pool, takes frames however they come, and answers each with an [`Outcome`]: the
//! frame registered (with the core's report and the time of the core's call), empty (no usable
//! point), or skipped (unreadable); after an empty or skipped frame the pose advances on the
//! constant-velocity model, as the reference does, so there is one pose per frame. `run`,
//! `bench` and `crosscheck` all use it, and so can whatever comes next:
//!
//! - a reader's items in a frame range: `kiss_odom_io::Selection` then [`Driver::feed`] (`run`);
//! - frames pushed one at a time from a callback (a ROS 2 node, a live sensor):
//!   [`Driver::register`] or [`Driver::register_points`];
//! - frames held in memory and timed (`bench`): [`Driver::preload`] then
//!   [`Driver::register_preloaded`], which times only the core's call;
//! - library and batch use: every method takes and returns plain `f64` data.
//!
//! After a frame, [`Driver::source_cloud`], [`Driver::merge_cloud`], [`Driver::map_points`] and
//! [`Driver::deskewed_scan`] give its clouds for a viewer or a published message.

use crate::engine::{self, Batch, Call, Engine};
use crate::growth::{Growth, StateMemory};
use crate::imu_check::{self, ImuCheck, Measured};
use crate::outcome::{FrameMeta, ImuUse, MapInUse, Outcome, Step};
use crate::pool::Pool;
use crate::settings::{Scalar, Settings, Storage};
use anyhow::{bail, Result};
use kiss_odom_core::{Capacities, Flag, FrameError, HighWater, ImuSample as CoreImu, Prior};
use kiss_odom_io::{Frame, Item};
use nalgebra::{Isometry3, UnitQuaternion};
use std::time::Duration;

/// Frames held in memory in one driver build's scalar (see [`Driver::preload`]).
pub struct Preloaded {
    scalar: Scalar,
    batch: Batch,
    frames: Vec<(FrameMeta, Option<Vec<f64>>)>,
}

impl Preloaded {
    /// Number of frames.
    pub fn len(&self) -> usize {
        self.frames.len()
    }
    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }
}

/// What an empty frame (no usable point) does to the state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OnEmpty {
    /// The pose advances on the constant-velocity model, one pose per frame, as the reference
    /// does with a dataset's frames.
    #[default]
    Advance,
    /// Nothing changes, as if the frame had never arrived (a live stream, where an empty
    /// message is not a sweep: the ROS 2 node).
    Ignore,
}

/// The odometry and its worker pool: see the module doc.
pub struct Driver {
    engine: Box<dyn Engine>,
    on_empty: OnEmpty,
    pool: Pool,
    build: Build,
    growth: Growth,
    imu_check: ImuCheck,
    imu_rejected: u64,
    /// Whether a scan of one plane was warned about (`Flag::OnePlane`).
    one_plane_said: bool,
    /// The IMU's axes turned into the LiDAR's (`[imu] extrinsic`), for the check's rates.
    lidar_from_imu: UnitQuaternion<f64>,
}

/// What a driver runs, fixed when it is made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Build {
    /// Worker threads of the correspondence search.
    pub threads: usize,
    /// The core's scalar.
    pub scalar: Scalar,
    /// The map point storage.
    pub storage: Storage,
    /// The core's capacities at the start (see [`Driver::memory`] for those in use).
    pub capacities: Capacities,
    /// Bytes of the core's state at the start.
    pub state_bytes: usize,
    /// Bytes of one stored map point.
    pub map_point_bytes: usize,
}

impl Driver {
    /// A driver for `settings` (already validated: the errors here are the core's); threads
    /// as [`Settings::threads`] resolves them.
    pub fn new(settings: &Settings) -> Result<Self> {
        let threads = settings.threads();
        let limit = settings.memory_limit();
        let engine = engine::build(settings, limit.is_some())?;
        let build = Build {
            threads,
            scalar: settings.runtime.scalar,
            storage: settings.runtime.map_storage,
            capacities: engine.capacities(),
            state_bytes: engine.state_bytes(),
            map_point_bytes: engine.map_point_bytes(),
        };
        Ok(Self {
            growth: Growth::new(build.capacities, build.state_bytes, limit),
            engine,
            on_empty: OnEmpty::Advance,
            pool: Pool::new(threads)?,
            build,
            imu_check: ImuCheck::default(),
            imu_rejected: 0,
            one_plane_said: false,
            lidar_from_imu: settings
                .imu
                .core::<f64>()?
                .map_or_else(UnitQuaternion::identity, |c| c.lidar_from_imu),
        })
    }

    /// Chooses what an empty frame does (default [`OnEmpty::Advance`]).
    pub fn on_empty(&mut self, policy: OnEmpty) {
        self.on_empty = policy;
    }

    /// Registers a frame read from a dataset; with the gyroscope prior on (`[imu]`), its IMU
    /// samples predict and deskew it, its sweep ending (on the IMU's clock, the sensor's) at
    /// [`Frame::sweep_end`].
    pub fn register(&mut self, frame: &Frame) -> Result<Outcome> {
        let meta = FrameMeta::of(frame);
        let stamps = frame.stamps.as_deref();
        if self.engine.imu_bias().is_none() {
            return self.register_points(meta, &frame.points, stamps);
        }
        // Only with the prior on: the sweep's end costs a pass over the stamps of a folder's
        // frame.
        let samples: Vec<CoreImu<f64>> = frame
            .imu
            .iter()
            .map(|s| CoreImu {
                time: s.seconds(),
                gyro: s.gyro,
                accel: s.accel,
            })
            .collect();
        self.register_with_imu(meta, &frame.points, stamps, frame.sweep_end(), &samples)
    }

    /// [`Self::register_points`] with the IMU samples that came with the scan, for the
    /// gyroscope prior (`[imu]`), whose sweep ends at `end` (s, on the IMU's clock; `None`:
    /// not known, and the prior does not act).
    pub fn register_with_imu(
        &mut self,
        meta: FrameMeta,
        points: &[[f64; 3]],
        stamps: Option<&[f64]>,
        end: Option<f64>,
        samples: &[CoreImu<f64>],
    ) -> Result<Outcome> {
        // A corrupt sample (beyond any gyroscope's range, standing out from the frame's others)
        // is left out, and said once: the frame goes on with the rest.
        let corrupt = imu_check::corrupt_samples(samples);
        let kept: Vec<CoreImu<f64>>;
        let samples = if corrupt {
            kept = samples
                .iter()
                .filter(|s| imu_check::plausible(&s.gyro))
                .copied()
                .collect();
            &kept[..]
        } else {
            samples
        };
        // Other rates beyond any gyroscope's range (deg/s on a fast turn) are not handed to the
        // odometry: the check counts the frame as a disagreement.
        let implausible = samples.iter().any(|s| !imu_check::plausible(&s.gyro));
        let hand_over = !self.imu_check.rejecting() && !implausible;
        let model = self.engine.last_delta();
        let prior = end.and_then(|end| self.engine.prior_before(samples, end, hand_over));
        // A registration that contradicts the gyroscope's prior is redone from the
        // constant-velocity model before the map takes it (the wrong prior leads ICP astray).
        let used = matches!(prior, Some(Prior::Used(_)));
        if let Some((gyro, _)) = self.engine.prior_measured() {
            if used && hand_over {
                let first = !self.imu_check.judging();
                self.engine.check_next(gyro, &model, first);
            }
        }
        let mut outcome = self.register_points(meta, points, stamps)?;
        let redone = self.engine.take_refused() || implausible;
        // The check, on a registered frame whose gyroscope rotation was measured.
        let measured = self
            .engine
            .prior_measured()
            .filter(|_| outcome.report().is_some());
        if corrupt {
            self.imu_check.corrupt_sample(&outcome.meta);
        }
        let verdict = measured.map(|(gyro, dt)| {
            let m = Measured {
                gyro: gyro.into(),
                icp: self.engine.last_delta().rotation.scaled_axis(),
                dt,
                rate: self.lidar_from_imu * imu_check::mean_rate(samples),
            };
            self.imu_check.judge(&outcome.meta, &m, redone)
        });
        // A frame that disagrees teaches the bias nothing.
        let residual = self.engine.prior_after(verdict.is_none_or(|(_, ok)| ok));
        let rejected = used && (!hand_over || redone);
        self.imu_rejected += u64::from(rejected);
        outcome.imu = self.engine.imu_bias().map(|bias| ImuUse {
            prior: prior.unwrap_or(Prior::NoSamples),
            samples: samples.len(),
            bias,
            residual,
            rejected,
            disagreement: verdict.map(|(off, _)| off),
        });
        Ok(outcome)
    }

    /// Frames the IMU consistency check predicted without the gyroscope prior (see
    /// `imu_check`).
    pub fn imu_rejected_frames(&self) -> u64 {
        self.imu_rejected
    }

    /// The warning that the IMU consistency check rejected the gyroscope, the first time it
    /// did, once the frames after it named the likely cause; at the `end` of a run, with what
    /// those frames tell.
    pub fn imu_check_warning(&mut self, end: bool) -> Option<String> {
        self.imu_check.warning(end)
    }

    /// Registers a scan given as points (sensor frame, m) with optional per-point capture
    /// times (one per point; any unit and offset).
    pub fn register_points(
        &mut self,
        meta: FrameMeta,
        points: &[[f64; 3]],
        stamps: Option<&[f64]>,
    ) -> Result<Outcome> {
        let sigma = self.engine.sigma();
        let moves = self.growth.memory.moves;
        self.growth.frame = meta.index;
        let call = self
            .engine
            .register(&self.pool, points, stamps, &mut self.growth);
        self.conclude(meta, sigma, call, moves)
    }

    /// A frame that could not be read (`reason` names the file): the pose advances on the
    /// constant-velocity model.
    pub fn skip(&mut self, meta: FrameMeta, reason: String) -> Outcome {
        let sigma = self.engine.sigma();
        self.engine.skip();
        Outcome {
            meta,
            step: Step::Skipped(reason),
            pose: self.engine.pose(),
            sigma,
            latency: Duration::ZERO,
            cpu: Duration::ZERO,
            input_points: 0,
            sweep: self.engine.sweep_motions(),
            imu: None,
            moves: 0,
        }
    }

    /// A reader's item: a frame is registered, an unreadable one skipped.
    pub fn feed(&mut self, item: Item) -> Result<Outcome> {
        match item {
            Item::Frame(frame) => self.register(&frame),
            Item::Skipped {
                index,
                name,
                time,
                reason,
            } => Ok(self.skip(
                FrameMeta {
                    index,
                    source: name,
                    time,
                },
                reason,
            )),
        }
    }

    /// Converts `frames` to this driver's scalar ahead of time, so that timed runs
    /// ([`Self::register_preloaded`]) neither read nor convert. Any driver of the same scalar
    /// can use the result.
    pub fn preload(&self, frames: &[Frame]) -> Preloaded {
        Preloaded {
            scalar: self.build.scalar,
            batch: self
                .engine
                .batch(&mut frames.iter().map(|f| f.points.as_slice())),
            frames: frames
                .iter()
                .map(|f| (FrameMeta::of(f), f.stamps.clone()))
                .collect(),
        }
    }

    /// Registers frame `k` of `frames`.
    pub fn register_preloaded(&mut self, frames: &Preloaded, k: usize) -> Result<Outcome> {
        let Some((meta, stamps)) = frames.frames.get(k) else {
            bail!("preloaded frame {k} of {}: no such frame", frames.len());
        };
        if frames.scalar != self.build.scalar {
            bail!(
                "frames preloaded for {:?} given to a {:?} driver",
                frames.scalar,
                self.build.scalar
            );
        }
        let sigma = self.engine.sigma();
        let moves = self.growth.memory.moves;
        self.growth.frame = meta.index;
        let call = self.engine.register_batch(
            &self.pool,
            &frames.batch,
            k,
            stamps.as_deref(),
            &mut self.growth,
        );
        let Some(call) = call else {
            bail!("preloaded frame {k}: not in this driver's scalar");
        };
        self.conclude(meta.clone(), sigma, call, moves)
    }

    /// The outcome of a core call (`moves` before it); an empty scan advances on the
    /// constant-velocity model unless [`OnEmpty::Ignore`] was chosen.
    fn conclude(&mut self, meta: FrameMeta, sigma: f64, call: Call, moves: u64) -> Result<Outcome> {
        let step = match call.result {
            Ok(report) => Step::Registered(report),
            Err(FrameError::EmptyScan) => {
                if self.on_empty == OnEmpty::Advance {
                    self.engine.skip();
                }
                Step::Empty
            }
            Err(e @ (FrameError::Storage | FrameError::Full)) => bail!("{}: {e}", meta.source),
        };
        Ok(Outcome {
            meta,
            step,
            pose: self.engine.pose(),
            sigma,
            latency: call.latency,
            cpu: call.cpu,
            input_points: call.input_points,
            sweep: self.engine.sweep_motions(),
            imu: None,
            moves: (self.growth.memory.moves - moves) as u32,
        })
    }

    /// Back to the state of a new driver (empty map, identity pose); the same frames then give
    /// the same poses.
    pub fn reset(&mut self) {
        self.engine.reset();
        self.imu_check = ImuCheck::default();
        self.imu_rejected = 0;
    }
    /// The latest motion: previous pose to latest, in the previous sensor frame.
    pub fn last_delta(&self) -> Isometry3<f64> {
        self.engine.last_delta()
    }
    /// What this driver runs: fixed at construction.
    pub fn build(&self) -> Build {
        self.build
    }
    /// What the core's state used: bytes at the start, now and at the peak, the moves into
    /// larger storage and the capacities in use.
    pub fn memory(&self) -> StateMemory {
        self.growth.memory
    }
    /// The warning that the core's state reached its memory limit, the first time it did.
    pub fn growth_warning(&mut self) -> Option<String> {
        self.growth.warning()
    }
    /// High-water marks of the core's buffers since start.
    pub fn high_water(&self) -> HighWater {
        self.engine.high_water()
    }
    /// The map in use: its voxel size and points a voxel.
    pub fn map_in_use(&self) -> MapInUse {
        self.engine.map_in_use()
    }

    /// The warning that robust mode held `outcome`'s scan to the prediction because it was
    /// one plane (`Flag::OnePlane`): on the first such frame of the run.
    pub fn one_plane_warning(&mut self, outcome: &Outcome) -> Option<String> {
        let first = outcome.status()?.contains(Flag::OnePlane) && !self.one_plane_said;
        self.one_plane_said |= first;
        first.then(|| {
            format!(
                "{}: the registration points lie on one plane, which measures nothing along \
                 it: the scan is held to the constant-velocity prediction, not registered \
                 (frames.csv one_plane counts such frames, summary.json degraded_frames)",
                outcome.meta.source
            )
        })
    }

    /// Bytes of state this build would need with capacities `caps`.
    pub fn state_bytes_for(&self, caps: &Capacities) -> usize {
        self.engine.state_bytes_for(caps)
    }
    /// Bytes of one stored map point in this build.
    pub fn map_point_bytes(&self) -> usize {
        self.engine.map_point_bytes()
    }
    /// The last registered frame's registration cloud (sensor frame, deskewed): what
    /// kiss-icp's `register_frame` returns as `source`.
    pub fn source_cloud(&self) -> Vec<[f64; 3]> {
        let mut out = Vec::new();
        self.engine.source_into(&mut out);
        out
    }
    /// [`Self::source_cloud`] into `out`, whose memory is reused.
    pub fn source_cloud_into(&self, out: &mut Vec<[f64; 3]>) {
        self.engine.source_into(out);
    }
    /// The last registered frame's merge cloud (sensor frame, deskewed).
    pub fn merge_cloud(&self) -> Vec<[f64; 3]> {
        self.engine.merge_cloud()
    }
    /// The local map's points (world frame).
    pub fn map_points(&self) -> Vec<[f64; 3]> {
        self.engine.map_points()
    }
    /// The last registered frame's points deskewed and cropped (sensor frame); give it the
    /// points and stamps that frame had.
    pub fn deskewed_scan(&mut self, points: &[[f64; 3]], stamps: Option<&[f64]>) -> Vec<[f64; 3]> {
        let mut out = Vec::new();
        self.engine.deskewed_scan_into(points, stamps, &mut out);
        out
    }
    /// [`Self::deskewed_scan`] into `out`, whose memory is reused.
    pub fn deskewed_scan_into(
        &mut self,
        points: &[[f64; 3]],
        stamps: Option<&[f64]>,
        out: &mut Vec<[f64; 3]>,
    ) {
        self.engine.deskewed_scan_into(points, stamps, out);
    }
    /// The latest pose (sensor at the end of the last sweep, in the frame of the first).
    pub fn pose(&self) -> Isometry3<f64> {
        self.engine.pose()
    }
    /// Replaces the latest pose, from which the next scan is predicted (kiss-icp's assignable
    /// `last_pose`); `false` (nothing changes) if it is not finite.
    pub fn set_last_pose(&mut self, pose: &Isometry3<f64>) -> bool {
        self.engine.set_last_pose(pose)
    }
    /// Replaces the constant-velocity model (kiss-icp's assignable `last_delta`); `false`
    /// (nothing changes) if it is not finite.
    pub fn set_last_delta(&mut self, delta: &Isometry3<f64>) -> bool {
        self.engine.set_last_delta(delta)
    }
    /// Empties the local map, keeping the poses and the threshold.
    pub fn clear_map(&mut self) {
        self.engine.clear_map();
    }
    /// Whether the local map holds no voxel.
    pub fn map_is_empty(&self) -> bool {
        self.engine.map_is_empty()
    }
    /// Frames registered or skipped so far.
    pub fn frames(&self) -> u64 {
        self.engine.frames()
    }
    /// The adaptive threshold's sigma for the next frame (m).
    pub fn sigma(&self) -> f64 {
        self.engine.sigma()
    }
    /// The gyroscope prior's bias estimate (rad/s, LiDAR axes), if it is on.
    pub fn gyro_bias(&self) -> Option<[f64; 3]> {
        self.engine.imu_bias()
    }
}

#[cfg(test)]
mod tests;
