//! Recorded data in, trajectories out.
//!
//! Every input format is a [`FrameSource`]: a stream of scans read one at a time, so a long
//! recording never has to fit in memory. Damage confined to one frame (a truncated `.bin`, a
//! garbage PLY header, timestamps of the wrong length) is reported as a [`Item::Skipped`] frame
//! or a frame [`Frame::warnings`] entry and the run goes on; damage to a container (a bag or
//! MCAP file cut in the middle) ends the stream with an error after the frames before it.

use anyhow::Result;
use nalgebra::Isometry3;
use std::path::{Path, PathBuf};

/// One scan as read from disk, in the sensor frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    /// Position of the frame in the sequence (0-based, counting skipped frames).
    pub index: usize,
    /// Where it came from: a file path, or `file:topic@stamp` for bags.
    pub name: String,
    /// Points in metres, sensor frame.
    pub points: Vec<[f64; 3]>,
    /// Per-point capture times in any unit and offset (one per point), if the format has them.
    pub stamps: Option<Vec<f64>>,
    /// Acquisition time of the frame in seconds, if known.
    pub time: Option<f64>,
    /// Problems that did not stop the frame from being used (e.g. timestamps ignored).
    pub warnings: Vec<String>,
}

/// What a source yields.
#[derive(Clone, Debug, PartialEq)]
pub enum Item {
    /// A usable frame.
    Frame(Frame),
    /// A frame that could not be read; `reason` names the file and what was wrong.
    Skipped {
        /// Position in the sequence.
        index: usize,
        /// One-line reason, naming the file.
        reason: String,
    },
}

/// A stream of scans.
pub trait FrameSource {
    /// Number of frames if known in advance.
    fn len_hint(&self) -> Option<usize>;
    /// The next frame, `Ok(None)` at the end, or `Err` when the container is damaged and
    /// nothing after this point can be trusted.
    fn next_item(&mut self) -> Result<Option<Item>>;
    /// Positions the stream so that the next item has index `index`, if the format can seek;
    /// returns false otherwise (the caller then reads and drops frames).
    fn seek(&mut self, _index: usize) -> bool {
        false
    }
}

/// Input formats (`--format`).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// KITTI if the folder has the benchmark layout, otherwise the generic layout.
    Auto,
    /// KITTI odometry benchmark layout (`sequences/XX`).
    Kitti,
    /// Generic layout with `.bin` frames.
    Bin,
    /// Generic layout with `.ply` frames.
    Ply,
    /// Generic layout with `.pcd` frames.
    Pcd,
    /// ROS 1 bag with `sensor_msgs/PointCloud2`.
    Bag,
    /// ROS 2 MCAP with `sensor_msgs/msg/PointCloud2`.
    Mcap,
}

/// Everything known about a dataset besides its frames.
#[derive(Clone, Debug, Default)]
pub struct DatasetInfo {
    /// Ground truth in the LiDAR frame, one pose per frame, if present.
    pub ground_truth: Option<Vec<Isometry3<f64>>>,
    /// Where the ground truth came from.
    pub ground_truth_path: Option<PathBuf>,
    /// Frame times in seconds (`times.txt`), if present.
    pub frame_times: Option<Vec<f64>>,
    /// The format actually used (never `Auto`).
    pub format: Option<Format>,
    /// Whether the reference's KITTI vertical-angle correction is applied to every scan.
    pub kitti_correction: bool,
}

/// An opened dataset: its frames and what else is known about it.
pub struct Dataset {
    /// The frames.
    pub frames: Box<dyn FrameSource>,
    /// Ground truth, times, format.
    pub info: DatasetInfo,
}

/// Options that affect how a dataset is opened.
#[derive(Clone, Debug, Default)]
pub struct OpenOptions {
    /// Topic to read from a bag or MCAP file (default: the only point-cloud topic).
    pub topic: Option<String>,
}

/// Whether `path` looks like a KITTI benchmark sequence folder: a `calib.txt` with a `Tr`
/// line and no `timestamps/` folder.
pub fn is_kitti_layout(path: &Path) -> bool {
    if path.join("timestamps").is_dir() {
        return false;
    }
    std::fs::read_to_string(path.join("calib.txt"))
        .map(|s| {
            s.lines()
                .any(|l| l.starts_with("Tr:") || l.starts_with("Tr "))
        })
        .unwrap_or(false)
}

pub mod bin;
pub mod generic;
pub mod kitti;
pub mod mcap;
pub mod open;
pub mod pcd;
pub mod ply;
pub mod pointcloud2;
pub mod poses;
pub mod rosbag;

pub use open::open;
