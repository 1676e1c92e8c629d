//! The odometry's accessors: the pose, velocity and threshold, the map and the last clouds,
//! and the setters a caller uses to seed or steer the next frame (kiss-icp's assignable
//! `last_pose` and `last_delta`, a measured motion, a measured sweep rotation).

use super::{Layout, Odometry};
use crate::config::{Capacities, Config};
use crate::deskew::{SweepMotion, SweepRotation};
use crate::geometry::Pose;
use crate::lie::renormalize;
use crate::local_map::{MapView, PointCodec};
use crate::preprocess::{Preprocessed, Preprocessor};
use crate::report::HighWater;
use crate::scalar::Real;
use crate::storage::Storage;

impl<T: Real, P: PointCodec<T>, S: Storage> Odometry<T, P, S> {
    /// The latest pose (kiss-icp's `last_pose`).
    pub fn last_pose(&self) -> &Pose<T> {
        &self.motion.pose
    }
    /// The latest pose; the same as [`Self::last_pose`].
    pub fn pose(&self) -> &Pose<T> {
        &self.motion.pose
    }
    /// The latest relative motion, the constant-velocity model (kiss-icp's `last_delta`).
    pub fn last_delta(&self) -> &Pose<T> {
        &self.motion.delta
    }
    /// The motion the last registered scan was deskewed with: the constant-velocity model
    /// (`last_delta`) as it stood before that scan was registered, or the motion its first
    /// registration found if it was deskewed again ([`Config::redeskew`]). Deskewing put the
    /// sensor at fraction `s` of that sweep at `pose * Exp((s - 1) Log(scan_motion))`, turned
    /// as measured instead if a [`Self::set_sweep_rotation`] was given for it.
    pub fn scan_motion(&self) -> &Pose<T> {
        &self.sweep.last_motion
    }
    /// The motion from the sensor at normalised time `s` of the last registered sweep to its
    /// end, as deskewing applied it: `last_pose() * scan_motion_at(s)` is the sensor's pose at
    /// `s`.
    pub fn scan_motion_at(&self, s: f64) -> Pose<T> {
        SweepMotion::new(&self.sweep.last_motion, self.sweep.last_rotation).at(s)
    }
    /// Replaces the latest pose, from which the next scan is predicted (kiss-icp's Python
    /// users assign `last_pose`, e.g. to start at a known pose). The map stays where it is.
    /// A pose with a non-finite entry is refused (`false`) and nothing changes.
    pub fn set_last_pose(&mut self, pose: Pose<T>) -> bool {
        let ok = is_finite_pose(&pose);
        if ok {
            self.motion.pose = pose;
            renormalize(&mut self.motion.pose);
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
            self.motion.delta = delta;
            renormalize(&mut self.motion.delta);
            self.sweep.rotation = None;
            self.threshold.predict_with(measured);
        }
        ok
    }
    /// Deskews the next scan with the sensor's rotation through its sweep as measured (a
    /// gyroscope's), point by point, instead of `last_delta`'s constant rate; the translation
    /// and the prediction stay `last_delta`'s. Holds for the next registered or skipped scan
    /// only; `None` goes back to the constant rate.
    pub fn set_sweep_rotation(&mut self, rotation: Option<SweepRotation<T>>) {
        self.sweep.rotation = rotation;
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
    /// view if the storage no longer holds the layout (see [`FrameError::Storage`](crate::FrameError::Storage)).
    pub fn map(&self) -> MapView<'_, T, P> {
        let words = self.buffers.storage.as_ref();
        let map_words = words
            .get(self.buffers.layout.map.keys.start..)
            .unwrap_or(&[]);
        MapView::of(&self.map, &self.buffers.layout.map, map_words)
            .unwrap_or_else(|_| MapView::empty(&self.map))
    }
    /// The last registered scan's merge cloud `P*_merge` (sensor frame, deskewed, in the
    /// reference's order); empty while a new scan is being received.
    pub fn merge_cloud(&self) -> &[[T; 3]] {
        self.cloud(self.buffers.layout.merge, self.buffers.merge_len)
    }
    /// The last registered scan's registration cloud `P^*` (sensor frame, deskewed): the
    /// `source` kiss-icp's `register_frame` returns. `last_pose() * p` puts it in the world.
    pub fn source(&self) -> &[[T; 3]] {
        self.cloud(self.buffers.layout.source, self.buffers.source_len)
    }
    fn cloud(&self, region: crate::storage::Region, len: usize) -> &[[T; 3]] {
        let words = self
            .buffers
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
        Preprocessor::with_span(
            lo,
            hi,
            span,
            &self.sweep.last_motion,
            self.sweep.last_rotation,
        )
        .run(points, stamps, out)
    }
    /// Parameters in use.
    pub fn config(&self) -> &Config<T> {
        &self.config
    }
    /// Capacities in use.
    pub fn capacities(&self) -> &Capacities {
        &self.buffers.caps
    }
    /// Where each buffer lives in the storage.
    pub fn layout(&self) -> &Layout {
        &self.buffers.layout
    }
    /// Frames registered or skipped so far.
    pub fn frames(&self) -> u64 {
        self.motion.frames
    }
    /// High-water marks since start.
    pub fn high_water(&self) -> HighWater {
        self.buffers.high
    }
    /// Bytes of state: the storage in use plus this struct. Fixed at construction.
    pub fn state_bytes(&self) -> usize {
        self.buffers.layout.words * 8 + core::mem::size_of::<Self>()
    }
}

fn is_finite_pose<T: Real>(p: &Pose<T>) -> bool {
    p.translation.vector.iter().all(|v| v.is_finite())
        && p.rotation.coords.iter().all(|v| v.is_finite())
}
