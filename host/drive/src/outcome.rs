//! What the driver answers for each frame: where it came from, what became of it, the pose
//! after it and what it cost.

use kiss_odom_core::{FrameReport, Prior, Status};
use kiss_odom_io::Frame;
use nalgebra::Isometry3;
use std::time::Duration;

/// Where a frame came from, as the outcome reports it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameMeta {
    /// The frame's identity in its dataset (or a running count for a live stream).
    pub index: usize,
    /// Its source: a file path, `file:topic@time` for a bag or MCAP message, a topic.
    pub source: String,
    /// Acquisition time (s), if known.
    pub time: Option<f64>,
}

impl FrameMeta {
    /// The meta data of a frame read from a dataset.
    pub fn of(frame: &Frame) -> Self {
        Self {
            index: frame.index,
            source: frame.name.clone(),
            time: frame.time,
        }
    }
}

/// What became of a frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// Registered: the core's report (pose, status flags, ICP and buffer figures), in `f64`.
    Registered(FrameReport<f64>),
    /// No finite point within range (`FrameError::EmptyScan`).
    Empty,
    /// Could not be read; the reason names the file.
    Skipped(String),
}

/// The motions from the sensor at the start and at the middle of a sweep to its end, as the
/// frame was deskewed (the constant-velocity model before it was registered, turning as the
/// gyroscope measured with the prior): the sensor's pose then is the frame's pose times one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweepMotions {
    /// From the sweep's start.
    pub start: Isometry3<f64>,
    /// From its middle.
    pub middle: Isometry3<f64>,
}

/// The map a run registers on, from the core's configuration in use (`Odometry::config`).
/// Values in the build's scalar, widened.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapInUse {
    /// Voxel size (m).
    pub voxel_size: f64,
    /// Points a voxel.
    pub max_points_per_voxel: u32,
}

impl Default for SweepMotions {
    fn default() -> Self {
        Self {
            start: Isometry3::identity(),
            middle: Isometry3::identity(),
        }
    }
}

/// The answer to one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// Where the frame came from.
    pub meta: FrameMeta,
    /// What became of it.
    pub step: Step,
    /// The pose after it (sensor at the end of the sweep, in the frame of the first scan).
    pub pose: Isometry3<f64>,
    /// The threshold's sigma the frame was registered with (as it stood before the frame).
    pub sigma: f64,
    /// Time in the core's frame call (zero when skipped).
    pub latency: Duration,
    /// The calling thread's CPU time in that call: the whole call's with one thread, free of
    /// other processes' share of the machine (zero when skipped).
    pub cpu: Duration,
    /// Points given.
    pub input_points: usize,
    /// Where deskewing put the sensor at the sweep's start and middle.
    pub sweep: SweepMotions,
    /// What the gyroscope prior did, when it is on.
    pub imu: Option<ImuUse>,
    /// Moves of the core's state into larger storage this frame took (see `growth`).
    pub moves: u32,
}

/// What the gyroscope prior did for a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuUse {
    /// Used, or why not.
    pub prior: Prior,
    /// IMU samples that came with the frame.
    pub samples: usize,
    /// The bias estimate after the frame, LiDAR axes, rad/s.
    pub bias: [f64; 3],
    /// How far ICP's rotation rate was from the gyroscope's, rad/s, if the frame used it.
    pub residual: Option<f64>,
    /// Whether the IMU consistency check had rejected the gyroscope: the frame was predicted
    /// and deskewed without it, which it could have been (its rotation was measured).
    pub rejected: bool,
    /// The angle between the gyroscope's rotation over the frame and ICP's (rad), when the
    /// check measured it.
    pub disagreement: Option<f64>,
}

impl ImuUse {
    /// What the prior did, as reports name it: `rejected` for a frame the IMU consistency
    /// check kept from it, else [`Prior::name`].
    pub fn state(&self) -> &'static str {
        if self.rejected {
            "rejected"
        } else {
            self.prior.name()
        }
    }
}

impl Outcome {
    /// The core's report, if the frame was registered.
    pub fn report(&self) -> Option<&FrameReport<f64>> {
        match &self.step {
            Step::Registered(r) => Some(r),
            _ => None,
        }
    }

    /// The report's status, if the frame was registered.
    pub fn status(&self) -> Option<Status> {
        self.report().map(|r| r.status)
    }
}
