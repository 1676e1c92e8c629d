//! The four builds of the core behind one object-safe trait: `Odometry<T, P>` for `T` in
//! f32/f64 and `P` in `Exact`/`Quantized`, owning its words (`Odometry::boxed`). The generic
//! code is written once ([`Core`]); [`build`] is the only place that picks a build.
//!
//! Everything crosses the trait in `f64`: points are converted into a buffer the core reads
//! (outside the timed call), reports and poses are widened.

use crate::growth::{trim_buffer, Growth};
use crate::outcome::{MapInUse, SweepMotions};
use crate::pool::Pool;
use crate::settings::{Scalar, Settings, Storage};
use crate::widen::{widen, widen_report};
use anyhow::Result;
use cpu_time::ThreadTime;
use kiss_odom_core::{
    Capacities, Exact, FrameError, FrameReport, GyroPrior, HighWater, ImuSample as CoreImu,
    Odometry, PointCodec, Prior, Quantized, Real, WhenFull,
};
use nalgebra::{Isometry3, Translation3};
use std::time::{Duration, Instant};

/// What one frame call of the core gave, and how long the call took.
pub(crate) struct Call {
    pub result: Result<FrameReport<f64>, FrameError>,
    pub latency: Duration,
    /// The calling thread's CPU time in the call (all of it with one thread).
    pub cpu: Duration,
    pub input_points: usize,
}

/// Wall-clock and calling-thread CPU time of a stretch of work.
struct Stopwatch(Instant, ThreadTime);

impl Stopwatch {
    fn start() -> Self {
        Self(Instant::now(), ThreadTime::now())
    }

    /// (wall, cpu) since the start.
    fn stop(self) -> (Duration, Duration) {
        (self.0.elapsed(), self.1.elapsed())
    }
}

/// Frames converted to the core's scalar ahead of time.
pub(crate) enum Batch {
    F64(Vec<Vec<[f64; 3]>>),
    F32(Vec<Vec<[f32; 3]>>),
}

/// The scalars the host runs the core in, and where their preloaded frames live in a
/// [`Batch`].
pub(crate) trait HostScalar: Real {
    fn batch(frames: Vec<Vec<[Self; 3]>>) -> Batch;
    fn frames(batch: &Batch) -> Option<&[Vec<[Self; 3]>]>;
}

macro_rules! host_scalar {
    ($t:ty, $variant:ident) => {
        impl HostScalar for $t {
            fn batch(frames: Vec<Vec<[$t; 3]>>) -> Batch {
                Batch::$variant(frames)
            }
            fn frames(batch: &Batch) -> Option<&[Vec<[$t; 3]>]> {
                match batch {
                    Batch::$variant(f) => Some(f),
                    _ => None,
                }
            }
        }
    };
}

host_scalar!(f64, F64);
host_scalar!(f32, F32);

/// One build of the core, whatever its scalar and map storage.
pub(crate) trait Engine: Send + Sync {
    /// Registers a whole scan, growing the storage as `growth` allows.
    fn register(
        &mut self,
        pool: &Pool,
        points: &[[f64; 3]],
        stamps: Option<&[f64]>,
        growth: &mut Growth,
    ) -> Call;
    /// Registers frame `k` of a batch this engine made; `None` if it is not one.
    fn register_batch(
        &mut self,
        pool: &Pool,
        batch: &Batch,
        k: usize,
        stamps: Option<&[f64]>,
        growth: &mut Growth,
    ) -> Option<Call>;
    /// Converts frames to this engine's scalar.
    fn batch(&self, frames: &mut dyn Iterator<Item = &[[f64; 3]]>) -> Batch;
    /// Advances one frame on the constant-velocity model.
    fn skip(&mut self);
    /// Back to the state of a new odometry.
    fn reset(&mut self);
    /// The latest pose.
    fn pose(&self) -> Isometry3<f64>;
    /// The latest motion: from the previous pose to the latest, in the previous sensor frame.
    fn last_delta(&self) -> Isometry3<f64>;
    /// Where deskewing put the sensor within the latest frame's sweep.
    fn sweep_motions(&self) -> SweepMotions;
    /// The threshold's current sigma.
    fn sigma(&self) -> f64;
    /// High-water marks since start.
    fn high_water(&self) -> HighWater;
    /// The map in use and how the run registers on it.
    fn map_in_use(&self) -> MapInUse;
    /// Capacities in use.
    fn capacities(&self) -> Capacities;
    /// Bytes of state in use.
    fn state_bytes(&self) -> usize;
    /// Bytes of state this build would need with capacities `caps`.
    fn state_bytes_for(&self, caps: &Capacities) -> usize;
    /// Bytes of one stored map point.
    fn map_point_bytes(&self) -> usize;
    /// The last frame's registration cloud (sensor frame), into `out`.
    fn source_into(&self, out: &mut Vec<[f64; 3]>);
    /// The last frame's merge cloud (sensor frame).
    fn merge_cloud(&self) -> Vec<[f64; 3]>;
    /// The local map's points (world frame).
    fn map_points(&self) -> Vec<[f64; 3]>;
    /// `points` deskewed and cropped as the last frame was, into `out`.
    fn deskewed_scan_into(
        &mut self,
        points: &[[f64; 3]],
        stamps: Option<&[f64]>,
        out: &mut Vec<[f64; 3]>,
    );
    /// Replaces the latest pose; `false` (nothing changes) if it is not finite.
    fn set_last_pose(&mut self, pose: &Isometry3<f64>) -> bool;
    /// Replaces the constant-velocity model; `false` (nothing changes) if it is not finite.
    fn set_last_delta(&mut self, delta: &Isometry3<f64>) -> bool;
    /// Empties the local map, keeping poses and threshold.
    fn clear_map(&mut self);
    /// Whether the local map holds no voxel.
    fn map_is_empty(&self) -> bool;
    /// Frames registered or skipped so far.
    fn frames(&self) -> u64;
    /// The gyroscope prior, if on, before a frame whose sweep ends at `end` (s): what it did.
    /// Without `hand_over` the gyroscope's rotation is only measured and the frame is
    /// predicted as without the prior.
    fn prior_before(
        &mut self,
        samples: &[CoreImu<f64>],
        end: f64,
        hand_over: bool,
    ) -> Option<Prior>;
    /// The rotation vector the gyroscope measured over the frame (rad, LiDAR axes, less the
    /// bias) and the frame's interval (s), before [`Self::prior_after`].
    fn prior_measured(&self) -> Option<([f64; 3], f64)>;
    /// The gyroscope prior after the frame (its bias learns from the registered rotation
    /// when `learn`): how far ICP's rotation rate was from the gyroscope's, rad/s, if the
    /// frame used it.
    fn prior_after(&mut self, learn: bool) -> Option<f64>;
    /// The gyroscope prior's bias estimate, if it is on.
    fn imu_bias(&self) -> Option<[f64; 3]>;
    /// Puts the next registration to the IMU consistency check before the map takes it: one
    /// that disagrees with the gyroscope's rotation `gyro` (rad, LiDAR axes) is redone from
    /// `fallback` (see `imu_check`).
    fn check_next(&mut self, gyro: [f64; 3], fallback: &Isometry3<f64>, first: bool);
    /// Whether the last registration was refused by the check and redone (and clears it).
    fn take_refused(&mut self) -> bool;
}

/// The build `settings.runtime` asks for.
/// The build `settings.runtime` asks for, refusing full frames if its storage is to grow.
pub(crate) fn build(settings: &Settings, grows: bool) -> Result<Box<dyn Engine>> {
    Ok(
        match (settings.runtime.scalar, settings.runtime.map_storage) {
            (Scalar::F64, Storage::Exact) => Box::new(Core::<f64, Exact>::new(settings, grows)?),
            (Scalar::F64, Storage::Quantized) => {
                Box::new(Core::<f64, Quantized>::new(settings, grows)?)
            }
            (Scalar::F32, Storage::Exact) => Box::new(Core::<f32, Exact>::new(settings, grows)?),
            (Scalar::F32, Storage::Quantized) => {
                Box::new(Core::<f32, Quantized>::new(settings, grows)?)
            }
        },
    )
}

/// The odometry owning its words, a buffer for points converted to its scalar, and the
/// gyroscope prior with its samples in that scalar.
struct Core<T: Real, P: PointCodec<T>> {
    odom: Odometry<T, P, Box<[u64]>>,
    /// The last frame's points in `T`, and its deskewed copy: kept from frame to frame, so
    /// their memory is already mapped.
    points: Vec<[T; 3]>,
    deskewed: Vec<[T; 3]>,
    /// Points those buffers keep room for: the scan capacity the run started with.
    keep: usize,
    prior: Option<GyroPrior<T>>,
    imu: Vec<kiss_odom_core::ImuSample<T>>,
    /// The check the next registration is put to, and whether the last one was refused.
    check: Option<Check>,
    refused: bool,
}

/// The IMU consistency check for one registration: the gyroscope's rotation over the frame
/// and the motion to register from if the registration disagrees with it.
#[derive(Clone, Copy, Debug)]
struct Check {
    gyro: nalgebra::Vector3<f64>,
    fallback: Isometry3<f64>,
    /// The first frame the gyroscope measured (see `imu_check::tolerance`).
    first: bool,
}

impl<T: HostScalar, P: PointCodec<T>> Core<T, P> {
    fn new(settings: &Settings, grows: bool) -> Result<Self> {
        let mut odom = Odometry::boxed(settings.core_config::<T>()?, settings.capacities()?)
            .map_err(|e| anyhow::anyhow!("cannot build the odometry: {e}"))?;
        if grows {
            odom.set_when_full(WhenFull::Refuse);
        }
        Ok(Self {
            keep: odom.capacities().scan_points,
            odom,
            points: Vec::new(),
            deskewed: Vec::new(),
            prior: settings.imu.core::<T>()?.map(GyroPrior::new),
            imu: Vec::new(),
            check: None,
            refused: false,
        })
    }
}

fn narrow<T: Real>(points: &[[f64; 3]], out: &mut Vec<[T; 3]>) {
    out.clear();
    out.extend(
        points
            .iter()
            .map(|p| [T::of(p[0]), T::of(p[1]), T::of(p[2])]),
    );
}

/// An `f64` pose in `T`, entry by entry (the core renormalises what it is given).
fn narrow_pose<T: Real>(p: &Isometry3<f64>) -> kiss_odom_core::Pose<T> {
    let (q, t) = (p.rotation.coords, p.translation.vector);
    kiss_odom_core::Pose::from_parts(
        nalgebra::Translation3::new(T::of(t.x), T::of(t.y), T::of(t.z)),
        nalgebra::UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(
            T::of(q.w),
            T::of(q.x),
            T::of(q.y),
            T::of(q.z),
        )),
    )
}

fn wide<T: Real>(points: &[[T; 3]]) -> Vec<[f64; 3]> {
    let mut out = Vec::with_capacity(points.len());
    wide_into(points, &mut out);
    out
}

/// `points` in f64, into `out` (its memory reused).
fn wide_into<T: Real>(points: &[[T; 3]], out: &mut Vec<[f64; 3]>) {
    out.clear();
    out.extend(
        points
            .iter()
            .map(|p| [p[0].wide(), p[1].wide(), p[2].wide()]),
    );
}

/// Bytes of state of a `T`, `P` odometry with capacities `caps`.
pub(crate) fn state_bytes_for<T: Real, P: PointCodec<T>>(caps: &Capacities) -> usize {
    caps.arena_words::<T, P>() * 8 + core::mem::size_of::<Odometry<T, P>>()
}

/// Zeroed words for capacities `caps`, or `None` if the allocator has not that much.
fn words_for<T: Real, P: PointCodec<T>>(caps: &Capacities) -> Option<Box<[u64]>> {
    let n = caps.arena_words::<T, P>();
    let mut v = Vec::new();
    v.try_reserve_exact(n).ok()?;
    v.resize(n, 0u64);
    Some(v.into_boxed_slice())
}

/// Registers `pts`; a frame the core refuses as too large for its storage moves the odometry
/// into larger storage, as `growth` allows, and is registered again. Where growth stops (its
/// limit, or an allocator that has no more), the core's fixed-storage rule takes over.
fn register_growing<T: Real, P: PointCodec<T>>(
    odom: &mut Odometry<T, P, Box<[u64]>>,
    pool: &Pool,
    pts: &[[T; 3]],
    stamps: Option<&[f64]>,
    growth: &mut Growth,
    check: Option<Check>,
    refused: &mut bool,
) -> Result<FrameReport<T>, FrameError> {
    loop {
        let registered = match check {
            None => odom.register_frame_with(pool, pts, stamps),
            Some(c) => {
                // The first measured frame is judged by the registration the prior did not
                // lead: on a map of one undeskewed scan, ICP follows any prior.
                let agrees =
                    |m: &kiss_odom_core::Pose<T>, judge: Option<&kiss_odom_core::Pose<T>>| {
                        let icp = widen(judge.unwrap_or(m)).rotation.scaled_axis();
                        crate::imu_check::agrees(&c.gyro, &icp, c.first)
                    };
                let fallback = narrow_pose(&c.fallback);
                odom.register_frame_checked(pool, pts, stamps, fallback, c.first, agrees)
                    .map(|(report, accepted)| {
                        *refused = !accepted;
                        report
                    })
            }
        };
        match registered {
            Err(FrameError::Full) => {
                let caps = *odom.capacities();
                let next = growth.next(&caps, &odom.room_needed(), state_bytes_for::<T, P>);
                let moved = next.and_then(|next| {
                    let words = words_for::<T, P>(&next)?;
                    odom.rehome(next, words).ok()
                });
                match moved {
                    Some(o) => {
                        *odom = o;
                        growth.moved(*odom.capacities(), odom.state_bytes());
                    }
                    None => {
                        growth.cap();
                        odom.set_when_full(WhenFull::Drop);
                    }
                }
            }
            other => return other,
        }
    }
}

/// Times the core's call on already converted points.
fn timed<T: Real>(call: impl FnOnce() -> Result<FrameReport<T>, FrameError>, n: usize) -> Call {
    let watch = Stopwatch::start();
    let result = call();
    let (latency, cpu) = watch.stop();
    Call {
        result: result.map(|r| widen_report(&r)),
        latency,
        cpu,
        input_points: n,
    }
}

impl<T: HostScalar, P: PointCodec<T>> Engine for Core<T, P> {
    fn register(
        &mut self,
        pool: &Pool,
        points: &[[f64; 3]],
        stamps: Option<&[f64]>,
        growth: &mut Growth,
    ) -> Call {
        narrow(points, &mut self.points);
        let (odom, pts, refused) = (&mut self.odom, &self.points, &mut self.refused);
        let check = self.check.take();
        let call = timed(
            || register_growing(odom, pool, pts, stamps, growth, check, refused),
            pts.len(),
        );
        trim_buffer(&mut self.points, self.keep);
        call
    }

    fn register_batch(
        &mut self,
        pool: &Pool,
        batch: &Batch,
        k: usize,
        stamps: Option<&[f64]>,
        growth: &mut Growth,
    ) -> Option<Call> {
        let pts = T::frames(batch)?.get(k)?;
        let (odom, refused) = (&mut self.odom, &mut self.refused);
        let check = self.check.take();
        Some(timed(
            || register_growing(odom, pool, pts, stamps, growth, check, refused),
            pts.len(),
        ))
    }

    fn batch(&self, frames: &mut dyn Iterator<Item = &[[f64; 3]]>) -> Batch {
        T::batch(
            frames
                .map(|f| {
                    let mut v = Vec::with_capacity(f.len());
                    narrow(f, &mut v);
                    v
                })
                .collect(),
        )
    }

    fn skip(&mut self) {
        self.odom.skip_frame();
    }
    fn reset(&mut self) {
        self.odom.reset();
        if let Some(p) = &mut self.prior {
            p.reset();
        }
    }
    fn pose(&self) -> Isometry3<f64> {
        widen(self.odom.pose())
    }
    fn last_delta(&self) -> Isometry3<f64> {
        widen(self.odom.last_delta())
    }
    fn sweep_motions(&self) -> SweepMotions {
        SweepMotions {
            start: widen(&self.odom.scan_motion_at(0.0)),
            middle: widen(&self.odom.scan_motion_at(0.5)),
        }
    }
    fn sigma(&self) -> f64 {
        self.odom.sigma().wide()
    }
    fn high_water(&self) -> HighWater {
        self.odom.high_water()
    }
    fn map_in_use(&self) -> MapInUse {
        let c = self.odom.config();
        MapInUse {
            voxel_size: c.voxel_size.wide(),
            max_points_per_voxel: c.max_points_per_voxel,
        }
    }
    fn capacities(&self) -> Capacities {
        *self.odom.capacities()
    }
    fn state_bytes(&self) -> usize {
        self.odom.state_bytes()
    }
    fn state_bytes_for(&self, caps: &Capacities) -> usize {
        state_bytes_for::<T, P>(caps)
    }
    fn map_point_bytes(&self) -> usize {
        core::mem::size_of::<P::Stored>()
    }
    fn source_into(&self, out: &mut Vec<[f64; 3]>) {
        wide_into(self.odom.source(), out);
    }
    fn merge_cloud(&self) -> Vec<[f64; 3]> {
        wide(self.odom.merge_cloud())
    }
    fn map_points(&self) -> Vec<[f64; 3]> {
        let mut out = Vec::new();
        self.odom
            .map()
            .for_each_point(|_, p| out.push([p.x.wide(), p.y.wide(), p.z.wide()]));
        out
    }
    fn deskewed_scan_into(
        &mut self,
        points: &[[f64; 3]],
        stamps: Option<&[f64]>,
        out: &mut Vec<[f64; 3]>,
    ) {
        narrow(points, &mut self.points);
        let buf = &mut self.deskewed;
        buf.clear();
        buf.resize(self.points.len(), [T::zero(); 3]);
        let kept = self.odom.deskewed_scan(&self.points, stamps, buf).kept;
        wide_into(&buf[..kept], out);
        trim_buffer(&mut self.points, self.keep);
        trim_buffer(&mut self.deskewed, self.keep);
    }
    fn set_last_pose(&mut self, pose: &Isometry3<f64>) -> bool {
        self.odom.set_last_pose(narrow_pose(pose))
    }
    fn set_last_delta(&mut self, delta: &Isometry3<f64>) -> bool {
        self.odom.set_last_delta(narrow_pose(delta))
    }
    fn clear_map(&mut self) {
        self.odom.clear_map();
    }
    fn map_is_empty(&self) -> bool {
        self.odom.map().is_empty()
    }
    fn frames(&self) -> u64 {
        self.odom.frames()
    }
    fn prior_before(
        &mut self,
        samples: &[CoreImu<f64>],
        end: f64,
        hand_over: bool,
    ) -> Option<Prior> {
        let prior = self.prior.as_mut()?;
        self.imu.clear();
        self.imu.extend(samples.iter().map(|s| CoreImu {
            time: s.time,
            gyro: s.gyro.map(T::of),
            accel: s.accel.map(T::of),
        }));
        Some(if hand_over {
            prior.before_frame(&mut self.odom, &self.imu, end)
        } else {
            prior.measure_frame(&mut self.odom, &self.imu, end)
        })
    }
    fn prior_measured(&self) -> Option<([f64; 3], f64)> {
        let (q, dt) = self.prior.as_ref()?.measured()?;
        let turn = widen(&Isometry3::from_parts(Translation3::identity(), q)).rotation;
        Some((turn.scaled_axis().into(), dt))
    }
    fn prior_after(&mut self, learn: bool) -> Option<f64> {
        let prior = self.prior.as_mut()?;
        if !learn {
            prior.discard();
            return None;
        }
        prior.after_frame(&self.odom).map(|r| r.wide())
    }
    fn imu_bias(&self) -> Option<[f64; 3]> {
        self.prior.as_ref().map(|p| p.bias().map(|b| b.wide()))
    }
    fn check_next(&mut self, gyro: [f64; 3], fallback: &Isometry3<f64>, first: bool) {
        self.check = Some(Check {
            gyro: gyro.into(),
            fallback: *fallback,
            first,
        });
    }
    fn take_refused(&mut self) -> bool {
        core::mem::take(&mut self.refused)
    }
}
