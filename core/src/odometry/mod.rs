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

mod frame;

pub use frame::FrameInput;

use crate::arena::Arena;
use crate::config::{Capacities, Config, SYSTEM_LEN};
use crate::deskew::TimeSpan;
use crate::error::{ConfigError, FrameError};
use crate::lie::renormalize;
use crate::local_map::{Exact, LocalMap, MapBuffers, PointCodec};
use crate::registration::{Executor, Sequential, System};
use crate::report::{FrameReport, HighWater};
use crate::scalar::Real;
use crate::threshold::AdaptiveThreshold;
use crate::Pose;

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
    ///
    /// Timestamps that are the wrong length, not finite or all equal are ignored (the scan is
    /// registered without deskewing) and the report says why.
    pub fn register_frame_with<E: Executor>(
        &mut self,
        exec: &E,
        points: &[[T; 3]],
        stamps: Option<&[f64]>,
    ) -> Result<FrameReport<T>, FrameError> {
        let span = match stamps {
            Some(s) if self.config.deskew => Some(TimeSpan::of(s, points.len())),
            _ => None,
        };
        let stamps = stamps.filter(|s| s.len() == points.len());
        let mut frame = self.begin(span);
        frame.push(points, stamps);
        frame.finish_with(exec)
    }

    /// Starts a scan that arrives in pieces (sensor packets), for callers that cannot hold a
    /// whole sweep: push points with [`FrameInput::push`], then register with
    /// [`FrameInput::finish`]. `span` is the sweep's first and last capture time (the
    /// reference normalises per-point times by the scan's own minimum and maximum); `None`
    /// registers without deskewing. Dropping the `FrameInput` unfinished leaves the odometry as
    /// it was.
    pub fn begin_frame(&mut self, span: Option<(f64, f64)>) -> FrameInput<'_, 'a, T, P> {
        let span = span
            .filter(|_| self.config.deskew)
            .map(|(min, max)| TimeSpan::new(min, max));
        self.begin(span)
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
