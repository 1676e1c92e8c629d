//! The odometry's state, grouped as the paper's quantities: the pose and velocity (Eq. (1)),
//! how sweeps are deskewed (Eq. (4)), and the storage with what the frames left in it. The
//! threshold (`threshold`), the map's bookkeeping (`local_map`) and the preset's own state
//! (`strategy`) are their modules' types.

use super::layout::Layout;
use crate::config::Capacities;
use crate::deskew::SweepRotation;
use crate::geometry::Pose;
use crate::lie::renormalize;
use crate::report::HighWater;
use crate::scalar::Real;
use crate::storage::Storage;

/// What a frame that would overfill a buffer does.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum WhenFull {
    /// Each full buffer drops by its documented rule and the report says so: fixed storage, a
    /// board's choice.
    #[default]
    Drop,
    /// The frame is refused ([`FrameError::Full`](crate::FrameError::Full)) with the state unchanged, so that the caller
    /// can move the odometry into larger storage ([`Odometry::rehome`](super::Odometry::rehome)) and register it again:
    /// a host's choice. A scan pushed in pieces ([`Odometry::begin_frame`](super::Odometry::begin_frame)) whose points
    /// overflowed is refused too, and cannot be registered again from the odometry alone.
    Refuse,
}

/// `T_{t-1}`, the constant-velocity model `dT_{t-1} = T_{t-2}^-1 T_{t-1}` (Eq. (1)) and the
/// frames registered or skipped so far.
#[derive(Clone, Copy, Debug)]
pub(super) struct Motion<T: Real> {
    pub(super) pose: Pose<T>,
    pub(super) delta: Pose<T>,
    pub(super) frames: u64,
}

impl<T: Real> Motion<T> {
    pub(super) fn start() -> Self {
        Self {
            pose: Pose::identity(),
            delta: Pose::identity(),
            frames: 0,
        }
    }

    /// Eq. (1): the constant-velocity prediction `T_{t-1} dT_{t-1}`.
    pub(super) fn prediction(&self) -> Pose<T> {
        self.pose * self.delta
    }

    /// The pose becomes `T_t`; `dT_t = T_{t-1}^-1 T_t` predicts the next scan.
    pub(super) fn advance_to(&mut self, pose: Pose<T>) {
        self.delta = self.pose.inverse() * pose;
        self.pose = pose;
        renormalize(&mut self.pose);
    }
}

/// What deskewing (Eq. (4)) used for the last registered sweep and uses for the one arriving.
#[derive(Clone, Copy, Debug)]
pub(super) struct Sweep<T: Real> {
    /// The motion the last registered sweep was deskewed with.
    pub(super) last_motion: Pose<T>,
    /// The measured rotation through it, if one was given.
    pub(super) last_rotation: Option<SweepRotation<T>>,
    /// The motion the sweep arriving is deskewed with.
    pub(super) motion: Pose<T>,
    /// The measured rotation through the next sweep, if one was given.
    pub(super) rotation: Option<SweepRotation<T>>,
}

impl<T: Real> Sweep<T> {
    pub(super) fn start() -> Self {
        Self {
            last_motion: Pose::identity(),
            last_rotation: None,
            motion: Pose::identity(),
            rotation: None,
        }
    }

    /// The sweep arriving was registered: it is now the last one.
    pub(super) fn registered(&mut self) {
        self.last_motion = self.motion;
        self.last_rotation = self.rotation.take();
    }
}

/// The storage and what the frames left in it: its layout and capacities, the lengths of the
/// last clouds, the high-water marks, and what a frame that would overfill it does.
pub(super) struct Buffers<S: Storage> {
    pub(super) storage: S,
    pub(super) layout: Layout,
    pub(super) caps: Capacities,
    /// Points of the last merge and registration clouds in their buffers.
    pub(super) merge_len: usize,
    pub(super) source_len: usize,
    pub(super) high: HighWater,
    pub(super) when_full: WhenFull,
    /// What the last refused frame needed (see `rehome`).
    pub(super) needed: Capacities,
}

impl<S: Storage> Buffers<S> {
    pub(super) fn new(storage: S, layout: Layout, caps: Capacities, when_full: WhenFull) -> Self {
        Self {
            storage,
            layout,
            caps,
            merge_len: 0,
            source_len: 0,
            high: HighWater::default(),
            when_full,
            needed: caps,
        }
    }
}
