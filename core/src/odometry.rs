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
//!
//! [`frame`](self) holds the per-scan steps in paper order, `input` the streaming entry
//! ([`FrameInput`]), `layout` where each buffer lives in the storage.

mod frame;
mod icp;
mod input;
mod layout;
mod rehome;

pub use input::FrameInput;
pub use layout::Layout;
pub use rehome::WhenFull;

use crate::config::Degeneracy;
use crate::config::{Capacities, Config};
use crate::deskew::{SweepMotion, SweepRotation};
use crate::error::{ConfigError, FrameError};
use crate::geometry::Pose;
use crate::lie::renormalize;
use crate::local_map::{Exact, MapMut, MapState, MapView, PointCodec};
use crate::preprocess::{Preprocessed, Preprocessor};
use crate::registration::{Executor, Sequential};
use crate::report::{FrameReport, HighWater};
use crate::scalar::Real;
use crate::storage::Storage;
use crate::threshold::Thresholds;
use core::marker::PhantomData;

/// KISS-ICP odometry over storage it owns or borrows (see [`crate::storage`]).
///
/// ```
/// use kiss_odom_core::{Capacities, Config, Exact, Odometry};
/// let caps = Capacities { scan_points: 1000, merge_points: 512, source_points: 128,
///                         map_voxels: 1024, map_points: 4096, plane_terms: false };
/// let mut words = [0u64; 1 << 16];
/// assert!(caps.arena_words::<f64, Exact>() <= words.len());
/// let mut odom = Odometry::<f64, Exact, _>::new(Config::new(50.0), caps, &mut words[..]).unwrap();
/// let scan = [[5.0, 1.0, 0.5], [6.0, -2.0, 0.1], [9.0, 3.0, -1.0]];
/// let report = odom.register_frame(&scan, None).unwrap();
/// assert_eq!(report.index, 0); // the first frame is the origin
/// ```
pub struct Odometry<T: Real, P: PointCodec<T> = Exact, S: Storage = &'static mut [u64]> {
    storage: S,
    layout: Layout,
    /// The configuration in use: `asked`, or its sparse-scan form from the first scan on.
    config: Config<T>,
    /// The configuration the odometry was built with.
    asked: Config<T>,
    caps: Capacities,
    map: MapState<T>,
    threshold: Thresholds<T>,
    last_pose: Pose<T>,
    last_delta: Pose<T>,
    /// The motion the last registered scan was deskewed with (see [`Self::scan_motion`]).
    scan_motion: Pose<T>,
    /// The motion the scan being received is deskewed with.
    deskew_motion: Pose<T>,
    /// The measured rotation through the next scan's sweep, if one was given.
    sweep_rotation: Option<SweepRotation<T>>,
    /// The one the last registered scan was deskewed with.
    scan_rotation: Option<SweepRotation<T>>,
    frames: u64,
    /// The last registration measured every direction (it was not the first frame's, and its
    /// observability was not below `degeneracy_ratio`), as the second deskew asks too.
    constrained: bool,
    merge_len: usize,
    source_len: usize,
    high: HighWater,
    /// What a frame that would overfill a buffer does, and what the last refused one needed.
    when_full: WhenFull,
    needed: Capacities,
    _codec: PhantomData<P>,
}

impl<T: Real, P: PointCodec<T>, S: Storage> Odometry<T, P, S> {
    /// Builds the pipeline in `storage`, which must hold `caps.arena_words::<T, P>()` words
    /// (more is fine). The words are cleared here.
    pub fn new(config: Config<T>, caps: Capacities, mut storage: S) -> Result<Self, ConfigError> {
        config.validate()?;
        caps.validate()?;
        if config.degeneracy == Degeneracy::Robust && !caps.plane_terms {
            return Err(ConfigError::PlaneTerms);
        }
        let layout = Layout::new::<T, P>(&caps);
        let words = storage.as_mut();
        if words.len() < layout.words {
            return Err(ConfigError::ArenaTooSmall);
        }
        words[..layout.words].fill(0);
        let map = MapState::new(
            config.voxel_size,
            config.max_range,
            config.max_points_per_voxel,
            caps.map_voxels,
            &layout.map,
        )
        .ok_or(ConfigError::PointsPerVoxel)?;
        let mut odom = Self {
            storage,
            layout,
            threshold: Self::fresh_threshold(&config),
            config,
            asked: config,
            caps,
            map,
            last_pose: Pose::identity(),
            last_delta: Pose::identity(),
            scan_motion: Pose::identity(),
            deskew_motion: Pose::identity(),
            sweep_rotation: None,
            scan_rotation: None,
            frames: 0,
            constrained: false,
            merge_len: 0,
            source_len: 0,
            high: HighWater::default(),
            when_full: WhenFull::Drop,
            needed: caps,
            _codec: PhantomData,
        };
        odom.map_mut()
            .map_err(|_| ConfigError::ArenaTooSmall)?
            .clear();
        Ok(odom)
    }

    fn fresh_threshold(config: &Config<T>) -> Thresholds<T> {
        Thresholds::new(
            config.initial_threshold,
            config.min_motion_threshold,
            config.max_range,
        )
    }

    /// Back to the state [`Self::new`] left: empty map, identity pose and velocity, the
    /// threshold's seed, frame count and high-water marks at zero. The same frames then give
    /// the same poses as on a new odometry.
    pub fn reset(&mut self) {
        self.use_config(self.asked);
        if let Ok(mut map) = self.map_mut() {
            map.clear();
        }
        self.map.reset_high_water();
        self.threshold = Self::fresh_threshold(&self.config);
        self.last_pose = Pose::identity();
        self.last_delta = Pose::identity();
        self.scan_motion = Pose::identity();
        self.deskew_motion = Pose::identity();
        self.sweep_rotation = None;
        self.scan_rotation = None;
        self.frames = 0;
        self.constrained = false;
        self.merge_len = 0;
        self.source_len = 0;
        self.high = HighWater::default();
        self.needed = self.caps;
    }

    /// Runs `config` from here on, with an empty map of its voxels; the caller has nothing in
    /// the map to lose. Nothing changes when `config` is the one in use, or invalid (a voxel
    /// grown past the largest scalar).
    fn use_config(&mut self, config: Config<T>) {
        if config == self.config || config.validate().is_err() {
            return;
        }
        let state = MapState::new(
            config.voxel_size,
            config.max_range,
            config.max_points_per_voxel,
            self.caps.map_voxels,
            &self.layout.map,
        );
        if let Some(state) = state {
            self.map = state;
            self.config = config;
            if let Ok(mut map) = self.map_mut() {
                map.clear();
            }
        }
    }

    /// The configuration a first scan keeping `kept` points maps with: `asked`'s sparse-scan
    /// form for a sparse one (see [`Config::for_first_scan`]), if valid; else the one in use.
    fn first_scan_config(&self, kept: usize) -> Config<T> {
        let c = self.asked.for_first_scan(kept);
        if c.validate().is_ok() {
            c
        } else {
            self.config
        }
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
    /// correspondence search on `exec`. Returns the end-of-sweep pose and a report.
    ///
    /// Timestamps that are the wrong length, not finite or all equal are ignored (the scan is
    /// registered without deskewing) and the report says why.
    ///
    /// [`FrameError::EmptyScan`] (no finite point within range) leaves every part of the state
    /// as it was: pose, velocity, map, threshold, frame count. The caller then either drops the
    /// frame, or calls [`Self::skip_frame`] to advance one frame on the constant-velocity
    /// model, which is what the reference does with an empty scan (`kiss-odom run` does that,
    /// so poses stay one per frame).
    pub fn register_frame_with<E: Executor>(
        &mut self,
        exec: &E,
        points: &[[T; 3]],
        stamps: Option<&[f64]>,
    ) -> Result<FrameReport<T>, FrameError> {
        self.room_for(Capacities {
            scan_points: points.len(),
            ..rehome::nothing()
        })?;
        let scan = self.receive(points, stamps, self.last_delta);
        let first = self.align(exec, scan, None)?;
        if !self.redeskews(&first) {
            return self.commit(first);
        }
        // Step 1 again: the sweep deskewed with its own motion, from its first registration.
        let motion = self.last_pose.inverse() * first.pose();
        let scan = self.receive(points, stamps, motion);
        let again = self.align(exec, scan, Some(first.pose()))?;
        self.commit(again)
    }

    /// Starts a scan that arrives in pieces (sensor packets), for callers that cannot hold a
    /// whole sweep: push points with [`FrameInput::push`], then register with
    /// [`FrameInput::finish`]. `span` is the sweep's first and last capture time (the
    /// reference normalises per-point times by the scan's own minimum and maximum); `None`
    /// registers without deskewing. Such a scan is deskewed once: a second deskew
    /// ([`Config::redeskew`]) needs the whole scan.
    ///
    /// Dropping the [`FrameInput`] unfinished leaves the odometry as it was (pose, velocity,
    /// map, threshold, counters, the last [`Self::source`]) except [`Self::merge_cloud`]: the
    /// new scan streams into the merge cloud's buffer, so that is empty until the next scan
    /// registers.
    pub fn begin_frame(&mut self, span: Option<(f64, f64)>) -> FrameInput<'_, T, P, S> {
        self.begin_span(span)
    }

    /// Advances one frame on the constant-velocity model alone, as the reference does when a
    /// scan is empty: the pose becomes the prediction and the velocity is kept.
    pub fn skip_frame(&mut self) -> Pose<T> {
        self.sweep_rotation = None;
        self.threshold.predict_with(false);
        self.last_pose *= self.last_delta;
        renormalize(&mut self.last_pose);
        self.frames += 1;
        self.last_pose
    }

    /// The latest pose (kiss-icp's `last_pose`).
    pub fn last_pose(&self) -> &Pose<T> {
        &self.last_pose
    }
    /// The latest pose; the same as [`Self::last_pose`].
    pub fn pose(&self) -> &Pose<T> {
        &self.last_pose
    }
    /// The latest relative motion, the constant-velocity model (kiss-icp's `last_delta`).
    pub fn last_delta(&self) -> &Pose<T> {
        &self.last_delta
    }
    /// The motion the last registered scan was deskewed with: the constant-velocity model
    /// (`last_delta`) as it stood before that scan was registered, or the motion its first
    /// registration found if it was deskewed again ([`Config::redeskew`]). Deskewing put the
    /// sensor at fraction `s` of that sweep at `pose * Exp((s - 1) Log(scan_motion))`, turned
    /// as measured instead if a [`Self::set_sweep_rotation`] was given for it.
    pub fn scan_motion(&self) -> &Pose<T> {
        &self.scan_motion
    }
    /// The motion from the sensor at normalised time `s` of the last registered sweep to its
    /// end, as deskewing applied it: `last_pose() * scan_motion_at(s)` is the sensor's pose at
    /// `s`.
    pub fn scan_motion_at(&self, s: f64) -> Pose<T> {
        SweepMotion::new(&self.scan_motion, self.scan_rotation).at(s)
    }
    /// Replaces the latest pose, from which the next scan is predicted (kiss-icp's Python
    /// users assign `last_pose`, e.g. to start at a known pose). The map stays where it is.
    /// A pose with a non-finite entry is refused (`false`) and nothing changes.
    pub fn set_last_pose(&mut self, pose: Pose<T>) -> bool {
        let ok = is_finite_pose(&pose);
        if ok {
            self.last_pose = pose;
            renormalize(&mut self.last_pose);
        }
        ok
    }
    /// Replaces the constant-velocity model that predicts and deskews the next scan
    /// (kiss-icp's assignable `last_delta`), and drops a [`Self::set_sweep_rotation`].
    /// Non-finite: refused (`false`), nothing changes.
    pub fn set_last_delta(&mut self, delta: Pose<T>) -> bool {
        self.predict_next(delta, false)
    }
    /// [`Self::set_last_delta`] with a motion measured by another sensor (a gyroscope, wheel
    /// odometry): the scan's correspondences are then gated by the adaptive threshold learnt
    /// from the errors of measured predictions, not from the constant-velocity model's, which
    /// are larger. Each kind keeps its own, so a sensor that drops out leaves the
    /// constant-velocity model the threshold of its own errors.
    pub fn set_measured_delta(&mut self, delta: Pose<T>) -> bool {
        self.predict_next(delta, true)
    }
    fn predict_next(&mut self, delta: Pose<T>, measured: bool) -> bool {
        let ok = is_finite_pose(&delta);
        if ok {
            self.last_delta = delta;
            renormalize(&mut self.last_delta);
            self.sweep_rotation = None;
            self.threshold.predict_with(measured);
        }
        ok
    }
    /// Deskews the next scan with the sensor's rotation through its sweep as measured (a
    /// gyroscope's), point by point, instead of `last_delta`'s constant rate; the translation
    /// and the prediction stay `last_delta`'s. Holds for the next registered or skipped scan
    /// only; `None` goes back to the constant rate.
    pub fn set_sweep_rotation(&mut self, rotation: Option<SweepRotation<T>>) {
        self.sweep_rotation = rotation;
    }
    /// Empties the local map and keeps the poses, threshold and counters (kiss-icp's
    /// `local_map.clear()`): the next scan takes its prediction and seeds the map again.
    pub fn clear_map(&mut self) {
        if let Ok(mut map) = self.map_mut() {
            map.clear();
        }
    }
    /// The current `sigma` of the threshold that gates the next scan.
    pub fn sigma(&self) -> T {
        self.threshold.in_use().sigma()
    }
    /// The local map (kiss-icp's `local_map`): its points, occupancy and search. An empty
    /// view if the storage no longer holds the layout (see [`FrameError::Storage`]).
    pub fn map(&self) -> MapView<'_, T, P> {
        let words = self.storage.as_ref();
        let map_words = words.get(self.layout.map.keys.start..).unwrap_or(&[]);
        MapView::of(&self.map, &self.layout.map, map_words)
            .unwrap_or_else(|_| MapView::empty(&self.map))
    }
    /// The last registered scan's merge cloud `P*_merge` (sensor frame, deskewed, in the
    /// reference's order); empty while a new scan is being received.
    pub fn merge_cloud(&self) -> &[[T; 3]] {
        self.cloud(self.layout.merge, self.merge_len)
    }
    /// The last registered scan's registration cloud `P^*` (sensor frame, deskewed): the
    /// `source` kiss-icp's `register_frame` returns. `last_pose() * p` puts it in the world.
    pub fn source(&self) -> &[[T; 3]] {
        self.cloud(self.layout.source, self.source_len)
    }
    fn cloud(&self, region: crate::storage::Region, len: usize) -> &[[T; 3]] {
        let words = self
            .storage
            .as_ref()
            .get(region.start..region.end())
            .unwrap_or(&[]);
        crate::storage::view_ref(words, len).unwrap_or(&[])
    }
    /// Deskews and crops `points` as the last registered scan was (same motion, same range
    /// shell) into `out`: the deskewed frame kiss-icp's `register_frame` returns, without the
    /// odometry keeping a copy of every scan. Call it with the scan just registered.
    pub fn deskewed_scan(
        &self,
        points: &[[T; 3]],
        stamps: Option<&[f64]>,
        out: &mut [[T; 3]],
    ) -> Preprocessed {
        let c = &self.config;
        let span = Preprocessor::<T>::span(c.deskew, stamps, points.len());
        let (lo, hi) = (c.min_range, c.max_range);
        Preprocessor::with_span(lo, hi, span, &self.scan_motion, self.scan_rotation)
            .run(points, stamps, out)
    }
    /// Parameters in use: those it was built with, or from the first scan on their
    /// sparse-scan form (see [`Config::sparse_scan_points`]).
    pub fn config(&self) -> &Config<T> {
        &self.config
    }

    /// Whether the first scan gave this run the sparse-scan map, so that [`Self::config`]
    /// differs from the configuration the odometry was built with.
    pub fn sparse_scan_map(&self) -> bool {
        self.config != self.asked
    }
    /// Capacities in use.
    pub fn capacities(&self) -> &Capacities {
        &self.caps
    }
    /// Where each buffer lives in the storage.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }
    /// Frames registered or skipped so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }
    /// High-water marks since start.
    pub fn high_water(&self) -> HighWater {
        self.high
    }
    /// Bytes of state: the storage in use plus this struct. Fixed at construction.
    pub fn state_bytes(&self) -> usize {
        self.layout.words * 8 + core::mem::size_of::<Self>()
    }

    /// Write access to the map.
    fn map_mut(&mut self) -> Result<MapMut<'_, T, P>, FrameError> {
        let words = self.storage.as_mut();
        let map_words = words
            .get_mut(self.layout.map.keys.start..)
            .ok_or(FrameError::Storage)?;
        MapMut::of(&mut self.map, &self.layout.map, map_words).map_err(|_| FrameError::Storage)
    }
}

#[cfg(feature = "alloc")]
impl<T: Real, P: PointCodec<T>> Odometry<T, P, alloc::boxed::Box<[u64]>> {
    /// An odometry owning a heap buffer of exactly the size `caps` needs (host only: the
    /// `alloc` feature, which bare-metal builds do not enable).
    pub fn boxed(config: Config<T>, caps: Capacities) -> Result<Self, ConfigError> {
        let words = alloc::vec![0u64; caps.arena_words::<T, P>()].into_boxed_slice();
        Self::new(config, caps, words)
    }
}

fn is_finite_pose<T: Real>(p: &Pose<T>) -> bool {
    p.translation.vector.iter().all(|v| v.is_finite())
        && p.rotation.coords.iter().all(|v| v.is_finite())
}
