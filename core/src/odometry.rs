//! The pipeline: one call per scan runs the paper's steps in order (Sec. III).
//!
//! ```text
//! scan --crop/deskew--> P* --alpha v--> P*_merge --beta v--> P^* --ICP vs map--> T_t
//!                                         |                                       |
//!                                         +----------- map update at T_t <--------+
//! ```
//!
//! [`Odometry::register_frame_with`] is the frame, one call per step. Bookkeeping follows the
//! reference: the prediction is `T_{t-1} dT_{t-1}` (constant velocity, Eq. (1)), the first
//! frame returns the identity and seeds the map, the second starts from an identity
//! prediction, and the model deviation `(T_{t-1} T_pred)^-1 T_t` (Eq. (13)) feeds the adaptive
//! threshold.
//!
//! `steps` holds the steps, `input` step 1 as points arrive ([`FrameInput`]), `icp` step 4 in
//! the configured mode, `strategy` what the accurate preset adds, `state` the state's groups,
//! `access` the accessors, `layout` where each buffer lives in the storage and `rehome` how a
//! host moves it all into larger storage.

mod access;
mod icp;
mod input;
mod layout;
mod rehome;
mod state;
mod steps;
mod strategy;

pub use input::FrameInput;
pub use layout::Layout;
pub use state::WhenFull;

use crate::config::{Capacities, Config, Degeneracy};
use crate::error::{ConfigError, FrameError};
use crate::geometry::Pose;
use crate::lie::renormalize;
use crate::local_map::{Exact, MapMut, MapState, PointCodec};
use crate::registration::{Executor, Sequential};
use crate::report::FrameReport;
use crate::scalar::Real;
use crate::storage::Storage;
use crate::threshold::Thresholds;
use core::marker::PhantomData;
use state::{Buffers, Motion, Sweep};
use steps::Registration;
use strategy::Strategy;

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
    /// `T_{t-1}` and the constant-velocity model `dT_{t-1}` (Eq. (1)), frames so far.
    motion: Motion<T>,
    /// How the last sweep was deskewed and the next one will be (Eq. (4)).
    sweep: Sweep<T>,
    /// `sigma_t` of Eq. (7), one per kind of prediction.
    threshold: Thresholds<T>,
    /// The configuration it was built with.
    config: Config<T>,
    /// The local map's bookkeeping (Sec. III-C); its buffers are in the storage.
    map: MapState<T>,
    /// The storage, its layout and capacities, the last clouds, the high-water marks.
    buffers: Buffers<S>,
    /// What the accurate preset keeps from frame to frame.
    strategy: Strategy,
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
            motion: Motion::start(),
            sweep: Sweep::start(),
            threshold: fresh_threshold(&config),
            config,
            map,
            buffers: Buffers::new(storage, layout, caps, WhenFull::Drop),
            strategy: Strategy::default(),
            _codec: PhantomData,
        };
        odom.map_mut()
            .map_err(|_| ConfigError::ArenaTooSmall)?
            .clear();
        Ok(odom)
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
        self.room_for_scan(points.len())?;
        let registered = self.predict_and_register(exec, points, stamps)?;
        // Sec. III-C and III-D: the map update at T_t and the threshold's sample (Eq. (13)).
        self.update(registered)
    }

    /// [`Self::register_frame_with`], the registration put to `accept` before the map takes
    /// it. `accept` is given the motion registered over the frame (`T_{t-1}^-1 T_t`) and may
    /// refuse it: a motion another sensor measured and set as the prediction
    /// ([`Self::set_measured_delta`], [`Self::set_sweep_rotation`]) that the registration
    /// contradicts, say. The scan is then registered again as without that prediction: from
    /// `fallback` (the constant-velocity model's motion, as [`Self::set_last_delta`] sets
    /// it), deskewed at its constant rate, and that registration is the frame's. With
    /// `against_fallback`, the scan is first registered from `fallback` too and `accept` is
    /// also given that motion, which the prediction did not lead (a registration may follow
    /// a wrong prediction all the way); the prediction's registration is the same bits
    /// either way. Returns the report and whether the prediction's registration was
    /// accepted. A `fallback` that is not finite leaves the prediction's registration the
    /// frame's.
    pub fn register_frame_checked<E: Executor>(
        &mut self,
        exec: &E,
        points: &[[T; 3]],
        stamps: Option<&[f64]>,
        fallback: Pose<T>,
        against_fallback: bool,
        accept: impl FnOnce(&Pose<T>, Option<&Pose<T>>) -> bool,
    ) -> Result<(FrameReport<T>, bool), FrameError> {
        self.room_for_scan(points.len())?;
        let from = self.motion.pose;
        let mut judge = None;
        if against_fallback {
            let prediction = (self.motion.delta, self.sweep, self.threshold);
            let registered = if self.set_last_delta(fallback) {
                Some(self.predict_and_register(exec, points, stamps))
            } else {
                None
            };
            (self.motion.delta, self.sweep, self.threshold) = prediction;
            judge = registered.transpose()?.map(|r| from.inverse() * r.pose());
        }
        let mut registered = self.predict_and_register(exec, points, stamps)?;
        let accepted = accept(&(from.inverse() * registered.pose()), judge.as_ref());
        if !accepted && self.set_last_delta(fallback) {
            registered = self.predict_and_register(exec, points, stamps)?;
        }
        Ok((self.update(registered)?, accepted))
    }

    /// Steps 1-4 of the paper for one scan, up to the pose it registers at.
    fn predict_and_register<E: Executor>(
        &mut self,
        exec: &E,
        points: &[[T; 3]],
        stamps: Option<&[f64]>,
    ) -> Result<Registration<T>, FrameError> {
        // Step 1 (Sec. III-A): predict with the constant-velocity model (Eq. (1)) and deskew
        // the sweep with it (Eq. (2)-(4)); step 2 (Sec. III-B) starts as the points arrive.
        let scan = self.deskew(points, stamps, self.motion.delta);
        // Steps 2-4 (Sec. III-B to III-E): P*_merge and P^*, tau_t = 3 sigma_t, robust ICP.
        let mut registered = self.register(exec, scan, None)?;
        // The preset's strategy: the sweep deskewed again with the motion it registered at.
        if let Some(motion) = self.deskew_again(&registered) {
            let scan = self.deskew(points, stamps, motion);
            registered = self.register(exec, scan, Some(registered.pose()))?;
        }
        Ok(registered)
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
        self.sweep.rotation = None;
        self.threshold.predict_with(false);
        let m = &mut self.motion;
        m.pose *= m.delta;
        renormalize(&mut m.pose);
        m.frames += 1;
        m.pose
    }

    /// Back to the state [`Self::new`] left: empty map, identity pose and velocity, the
    /// threshold's seed, frame count and high-water marks at zero. The same frames then give
    /// the same poses as on a new odometry.
    pub fn reset(&mut self) {
        if let Ok(mut map) = self.map_mut() {
            map.clear();
        }
        self.map.reset_high_water();
        self.threshold = fresh_threshold(&self.config);
        self.motion = Motion::start();
        self.sweep = Sweep::start();
        self.strategy = Strategy::default();
        let b = &mut self.buffers;
        (b.merge_len, b.source_len) = (0, 0);
        b.high = Default::default();
        b.needed = b.caps;
    }

    /// Write access to the map.
    fn map_mut(&mut self) -> Result<MapMut<'_, T, P>, FrameError> {
        let b = &mut self.buffers;
        let words = b.storage.as_mut();
        let map_words = words
            .get_mut(b.layout.map.keys.start..)
            .ok_or(FrameError::Storage)?;
        MapMut::of(&mut self.map, &b.layout.map, map_words).map_err(|_| FrameError::Storage)
    }
}

/// The threshold's seed for `config` (`tau_0`, Sec. III-D).
fn fresh_threshold<T: Real>(config: &Config<T>) -> Thresholds<T> {
    Thresholds::new(
        config.initial_threshold,
        config.min_motion_threshold,
        config.max_range,
    )
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
