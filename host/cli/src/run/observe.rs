//! What watches a run as it goes: an [`Observer`] is called after every frame and once at the
//! end. `--save-map`, `--save-cloud` and `--rerun` are observers (`run::viz`), and so is
//! `live`, which prints each pose as its sweep completes. Observers never change what the
//! driver computes.

use super::record::FrameRow;
use anyhow::Result;
use kiss_odom_drive::{Driver, Outcome};
use kiss_odom_io::SweepInfo;
use nalgebra::Isometry3;

/// One frame as an observer sees it, after the driver registered (or skipped) it.
pub struct Seen<'a> {
    /// The driver, in the state the frame left it (its clouds are the frame's).
    pub driver: &'a Driver,
    /// What became of the frame.
    pub outcome: &'a Outcome,
    /// The frame's points as read (sensor frame), `None` when it could not be read.
    pub points: Option<&'a [[f64; 3]]>,
    /// The pose the run records for the frame (at the instant `output.pose_time` chooses).
    pub pose: Isometry3<f64>,
    /// The frame's time (s): its own, else the dataset's `times.txt`.
    pub time: Option<f64>,
    /// For a sweep decoded from sensor packets: its statistics and time span.
    pub sweep: Option<&'a SweepInfo>,
    /// The frame's ground-truth pose, in the frame of the first ground-truth pose.
    pub ground_truth: Option<Isometry3<f64>>,
}

/// An output built frame by frame from the run loop's outcomes.
pub trait Observer {
    /// Called after every frame, in order, with the frame's row of `frames.csv`, which an
    /// observer that measures something of the frame fills in.
    fn frame(&mut self, seen: &Seen<'_>, row: &mut FrameRow) -> Result<()>;
    /// Called once after the last frame (also after an interrupted or failed run, so that the
    /// output holds the frames processed); returns the warnings to print.
    fn finish(&mut self, driver: &Driver) -> Result<Vec<String>>;
}
