//! The pipeline: one call per scan runs the paper's steps in order.
//!
//! ```text
//! scan --crop/deskew--> P* --alpha v--> P*_merge --beta v--> P^* --ICP vs map--> T_t
//!                                         |                                       |
//!                                         +----------- map update at T_t <--------+
//! ```
//!
//! Bookkeeping follows the reference: the prediction is `T_{t-1} dT_{t-1}` (constant velocity,
//! Eq. (1)), the first frame returns the identity and seeds the map, the second starts from an
//! identity prediction, and the model deviation `(T_{t-1} T_pred)^-1 T_t` (Eq. (13)) feeds the
//! adaptive threshold.

use crate::arena::Arena;
use crate::config::{Capacities, Config, SYSTEM_LEN};
use crate::degeneracy::observability;
use crate::deskew::StampProblem;
use crate::downsample::{reference_order, Dedup};
use crate::error::{ConfigError, FrameError};
use crate::lie::renormalize;
use crate::local_map::{Exact, LocalMap, MapBuffers, PointCodec};
use crate::preprocess::{Drop, Preprocessor};
use crate::registration::{align_points_to_map, Executor, IcpParams, Sequential, System};
use crate::report::{Dropped, FrameReport, HighWater, Status};
use crate::scalar::Real;
use crate::threshold::AdaptiveThreshold;
use crate::{Point, Pose};

/// KISS-ICP odometry over a caller-owned arena.
///
/// ```
/// use kiss_odom_core::{Capacities, Config, Exact, Odometry};
/// let caps = Capacities { scan_points: 1000, merge_points: 512, source_points: 128,
///                         map_voxels: 1024, map_points: 4096 };
/// let mut arena = [0u64; 1 << 16];
/// assert!(caps.arena_words::<f64, Exact>() <= arena.len());
/// let mut odom = Odometry::<f64, Exact>::new(Config::new(50.0), caps, &mut arena).unwrap();
/// let scan = [[5.0, 1.0, 0.5], [6.0, -2.0, 0.1], [9.0, 3.0, -1.0]];
/// let report = odom.register_frame(&scan, None).unwrap();
/// assert_eq!(report.index, 0); // the first frame is the origin
/// ```
pub struct Odometry<'a, T: Real, P: PointCodec<T> = Exact> {
    config: Config<T>,
    caps: Capacities,
    merge: &'a mut [[T; 3]],
    source: &'a mut [[T; 3]],
    scratch: &'a mut [u64],
    systems: &'a mut [System<T>],
    map: LocalMap<'a, T, P>,
    threshold: AdaptiveThreshold<T>,
    last_pose: Pose<T>,
    last_delta: Pose<T>,
    frames: u64,
    merge_len: usize,
    high: HighWater,
    arena_words: usize,
}

impl<'a, T: Real, P: PointCodec<T>> Odometry<'a, T, P> {
    /// Builds the pipeline in `arena`, which must hold `caps.arena_words::<T, P>()` words.
    pub fn new(
        config: Config<T>,
        caps: Capacities,
        arena: &'a mut [u64],
    ) -> Result<Self, ConfigError> {
        config.validate()?;
        caps.validate()?;
        let layout = caps.layout(core::mem::size_of::<T>(), core::mem::size_of::<P::Stored>());
        let w = layout.words;
        let mut a = Arena::new(arena);
        let merge = a.slice(w[0], caps.merge_points)?;
        let source = a.slice(w[1], caps.source_points)?;
        let scratch = a.words(w[2])?;
        let systems = a.slice::<[T; SYSTEM_LEN]>(w[3], layout.chunks)?;
        let buf = MapBuffers {
            keys: a.slice(w[4], layout.map_slots)?,
            heads: a.slice(w[5], layout.map_slots)?,
            counts: a.slice(w[6], layout.map_slots)?,
            points: a.slice(w[7], layout.map_blocks * crate::config::BLOCK)?,
            links: a.slice(w[8], layout.map_blocks)?,
        };
        let map = LocalMap::new(
            config.voxel_size,
            config.max_range,
            config.max_points_per_voxel,
            caps.map_voxels,
            buf,
        )
        .ok_or(ConfigError::Capacity)?;
        Ok(Self {
            threshold: AdaptiveThreshold::new(
                config.initial_threshold,
                config.min_motion_threshold,
                config.max_range,
            ),
            config,
            caps,
            merge,
            source,
            scratch,
            systems,
            map,
            last_pose: Pose::identity(),
            last_delta: Pose::identity(),
            frames: 0,
            merge_len: 0,
            high: HighWater::default(),
            arena_words: a.used_words(),
        })
    }

    /// Registers one scan on the calling thread. See [`Self::register_frame_with`].
    pub fn register_frame(
        &mut self,
        points: &[[T; 3]],
        stamps: Option<&[f64]>,
    ) -> Result<FrameReport<T>, FrameError> {
        self.register_frame_with(&Sequential, points, stamps)
    }

    /// Registers one scan (sensor frame, any number of points) with optional per-point
    /// timestamps (seconds or any unit, any offset; one per point), running the
    /// correspondence search on `exec`. Returns the end-of-sweep pose and a report, or
    /// [`FrameError::EmptyScan`] with the state untouched when no point is usable.
    pub fn register_frame_with<E: Executor>(
        &mut self,
        exec: &E,
        points: &[[T; 3]],
        stamps: Option<&[f64]>,
    ) -> Result<FrameReport<T>, FrameError> {
        let cfg = self.config;
        let mut dropped = Dropped::default();
        let mut status = Status::default();

        // Step 1: crop, deskew and (streaming) the first downsampling pass.
        let used = points.len().min(self.caps.scan_points);
        dropped.truncated = (points.len() - used) as u32;
        // Stamps of the wrong length are ignored (and reported) rather than guessed at.
        let (stamps, wrong_length) = match stamps {
            Some(s) if s.len() == points.len() => (Some(&s[..used]), false),
            Some(_) => (None, cfg.deskew),
            None => (None, false),
        };
        let mut pre = Preprocessor::new(
            cfg.min_range,
            cfg.max_range,
            cfg.deskew,
            stamps,
            used,
            &self.last_delta,
        );
        let deskewed = pre.deskews();
        let alpha_v = cfg.voxel_size * cfg.alpha;
        let beta_v = cfg.voxel_size * cfg.beta;
        let mut kept = 0usize;
        let mut out_of_range = 0u32;
        let merged = {
            // The layout sizes scratch for the merge capacity, so `new` cannot fail here.
            let mut dedup =
                Dedup::new(self.merge, self.scratch, alpha_v).ok_or(FrameError::EmptyScan)?;
            for (i, raw) in points[..used].iter().enumerate() {
                let t = stamps.and_then(|s| s.get(i).copied()).unwrap_or(0.0);
                match pre.point(raw, t) {
                    Ok(p) => {
                        kept += 1;
                        dedup.push(&p);
                    }
                    Err(Drop::NonFinite) => dropped.non_finite += 1,
                    Err(Drop::OutOfRange) => out_of_range += 1,
                }
            }
            dedup.finish()
        };
        if kept == 0 {
            self.merge_len = 0;
            return Err(FrameError::EmptyScan);
        }
        // Step 2: downsampling in the reference's order (see `downsample`).
        dropped.merge_full = merged.dropped as u32;
        let m = merged.kept;
        reference_order(&mut self.merge[..m], alpha_v, kept, self.scratch);
        let sourced = {
            let mut dedup =
                Dedup::new(self.source, self.scratch, beta_v).ok_or(FrameError::EmptyScan)?;
            for p in self.merge[..m].iter() {
                dedup.push(&Point::from(*p));
            }
            dedup.finish()
        };
        dropped.source_full = sourced.dropped as u32;
        let s = sourced.kept;
        reference_order(&mut self.source[..s], beta_v, m, self.scratch);
        self.merge_len = m;

        // Steps 3 and 4: register against the map with the adaptive threshold.
        let sigma = self.threshold.sigma();
        let max_distance = cfg.max_correspondence_factor * sigma;
        let initial_guess = self.last_pose * self.last_delta;
        let params = IcpParams {
            convergence_criterion: cfg.convergence_criterion,
            max_iterations: cfg.max_iterations,
        };
        let first_frame = self.map.is_empty();
        let al = align_points_to_map(
            exec,
            &mut self.source[..s],
            self.systems,
            &self.map,
            &initial_guess,
            max_distance,
            cfg.kernel_scale * sigma,
            &params,
        );
        let finite = al.pose.translation.vector.iter().all(|v| v.is_finite())
            && al.pose.rotation.coords.iter().all(|v| v.is_finite());
        let new_pose = if finite { al.pose } else { initial_guess };
        let observability = if first_frame {
            None
        } else {
            observability(
                &self.map,
                &self.source[..s],
                &Point::from(new_pose.translation.vector),
                max_distance,
            )
        };

        // Update: threshold, map, velocity and pose.
        let deviation = initial_guess.inverse() * new_pose;
        let model_error = self.threshold.model_error(&deviation);
        self.threshold.update(&deviation);
        let st = self.map.update(&self.merge[..m], &new_pose);
        dropped.map_voxels_full = st.dropped_voxels as u32;
        dropped.map_points_full = st.dropped_points as u32;
        self.last_delta = self.last_pose.inverse() * new_pose;
        self.last_pose = new_pose;
        renormalize(&mut self.last_pose);

        self.high.merge_points = self.high.merge_points.max(m);
        self.high.source_points = self.high.source_points.max(s);
        self.high.map_voxels = self.map.high_water_voxels();
        self.high.map_point_slots = self.map.high_water_point_slots();

        let stamp_problem = if wrong_length {
            Some(StampProblem::Length)
        } else {
            pre.stamp_problem()
        };
        status.set(Status::TIMESTAMPS_IGNORED, stamp_problem.is_some());
        status.set(Status::ITERATION_CAP, !al.converged && !al.singular);
        status.set(
            Status::NO_CORRESPONDENCES,
            !first_frame && al.correspondences == 0,
        );
        status.set(Status::SINGULAR, !first_frame && (al.singular || !finite));
        status.set(
            Status::DEGENERATE,
            observability.is_some_and(|o| o < cfg.degeneracy_ratio),
        );
        status.set(Status::INVALID_POINTS, dropped.non_finite > 0);
        status.set(Status::SCAN_TRUNCATED, dropped.truncated > 0);
        status.set(Status::CAPACITY, dropped.capacity());

        let report = FrameReport {
            index: self.frames,
            pose: self.last_pose,
            status,
            iterations: al.iterations,
            correspondences: al.correspondences,
            sigma,
            rms: al.rms,
            model_error,
            observability,
            input_points: points.len() as u32,
            out_of_range,
            merge_points: m as u32,
            source_points: s as u32,
            map_voxels: self.map.voxels() as u32,
            map_points: self.map.points() as u32,
            pruned_voxels: st.pruned_voxels as u32,
            dropped,
            deskewed,
            stamp_problem,
        };
        self.frames += 1;
        Ok(report)
    }

    /// Advances one frame on the constant-velocity model alone, as the reference does when a
    /// scan is empty: the pose becomes the prediction and the velocity is kept.
    pub fn skip_frame(&mut self) -> Pose<T> {
        self.last_pose *= self.last_delta;
        renormalize(&mut self.last_pose);
        self.frames += 1;
        self.last_pose
    }

    /// The latest pose.
    pub fn pose(&self) -> &Pose<T> {
        &self.last_pose
    }
    /// The latest relative motion (the constant-velocity model).
    pub fn last_delta(&self) -> &Pose<T> {
        &self.last_delta
    }
    /// The threshold's current `sigma`.
    pub fn sigma(&self) -> T {
        self.threshold.sigma()
    }
    /// The local map.
    pub fn map(&self) -> &LocalMap<'a, T, P> {
        &self.map
    }
    /// The last frame's merge cloud (sensor frame, deskewed, in the reference's order).
    pub fn merge_cloud(&self) -> &[[T; 3]] {
        &self.merge[..self.merge_len]
    }
    /// Parameters in use.
    pub fn config(&self) -> &Config<T> {
        &self.config
    }
    /// Capacities in use.
    pub fn capacities(&self) -> &Capacities {
        &self.caps
    }
    /// Frames registered or skipped so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }
    /// High-water marks since start.
    pub fn high_water(&self) -> HighWater {
        self.high
    }
    /// Bytes of state: the arena in use plus this struct. Fixed at construction.
    pub fn state_bytes(&self) -> usize {
        self.arena_words * 8 + core::mem::size_of::<Self>()
    }
}
