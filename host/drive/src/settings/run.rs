//! What a run reads and writes beside the pipeline: how a sensor recording is cut into frames
//! (`[input]`) and what the outputs hold (`[output]`). The core never sees them; `config.toml`
//! lists each section only when a value differs from its default.

use crate::outcome::SweepMotions;
use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};

/// How sensor packets become frames (pcap, bags of packets, `live`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Input {
    /// UDP port of the sensor's data packets; absent: the vendor's (Velodyne and Hesai 2368,
    /// Ouster the metadata's lidar port, else 7502, Livox 56001, Robosense 6699).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub port: Option<u16>,
    /// Velodyne and Hesai: the azimuth (degrees) where one sweep ends and the next begins;
    /// absent: a full turn from where the recording starts.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cut_angle: Option<f64>,
    /// Livox: seconds of points in a frame; absent: 0.1 (a bag's CustomMsg: each message).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frame_period: Option<f64>,
}

/// What the outputs hold, and what refuses a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Output {
    /// A skipped frame, ignored timestamps or a dataset warning is an error (exit 1).
    pub strict: bool,
    /// The instant within a deskewed sweep each pose refers to.
    pub pose_time: PoseTime,
    /// Every Nth input point of a scan goes to Rerun.
    pub rerun_scan_stride: u32,
    /// The local map and trajectory go to Rerun every N frames, and after the last.
    pub rerun_map_every: u32,
    /// Voxel edge (m) of `--save-cloud`'s accumulated cloud: the first point in a voxel stays.
    pub cloud_voxel: f64,
    /// Most points `--save-cloud` keeps; points in new voxels past it are dropped, warned.
    pub cloud_max_points: usize,
    /// With `--map`: the frame the prior map must be in; the poses are written in it.
    pub map_frame: String,
}

impl Default for Output {
    fn default() -> Self {
        Self {
            strict: false,
            pose_time: PoseTime::End,
            rerun_scan_stride: 4,
            rerun_map_every: 10,
            cloud_voxel: 0.2,
            cloud_max_points: 5_000_000,
            map_frame: "map".into(),
        }
    }
}

impl Output {
    /// Whether every value is the default (the section is then left out of `config.toml`).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// The values out of range, named.
    pub(super) fn fault(&self) -> Option<String> {
        if self.rerun_scan_stride == 0 || self.rerun_map_every == 0 {
            return Some("output.rerun_scan_stride and output.rerun_map_every are >= 1".into());
        }
        if kiss_odom_core::prior_map::Header::frame_field(&self.map_frame).is_none() {
            return Some(format!(
                "output.map_frame = {:?}: not ASCII of at most 16 bytes",
                self.map_frame
            ));
        }
        if !(self.cloud_voxel.is_finite() && self.cloud_voxel > 0.0) {
            return Some(format!(
                "output.cloud_voxel = {}: not > 0",
                self.cloud_voxel
            ));
        }
        None
    }
}

impl Input {
    /// Whether every value is the default.
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// The values out of range, named.
    pub(super) fn fault(&self) -> Option<String> {
        if let Some(a) = self.cut_angle.filter(|a| !a.is_finite()) {
            return Some(format!("input.cut_angle = {a}: not a finite angle"));
        }
        if let Some(p) = self.frame_period.filter(|p| !(p.is_finite() && *p > 0.0)) {
            return Some(format!("input.frame_period = {p}: not > 0 s"));
        }
        None
    }
}

/// The instant within a sweep a pose refers to (`[output] pose_time`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PoseTime {
    /// The end of the sweep (the reference's poses).
    #[default]
    End,
    /// The start of the sweep.
    Start,
    /// The middle of the sweep.
    Middle,
}

impl PoseTime {
    /// The instant as a fraction of the sweep: 0 start, 1 end.
    pub fn fraction(self) -> f64 {
        match self {
            Self::End => 1.0,
            Self::Start => 0.0,
            Self::Middle => 0.5,
        }
    }

    /// `end`, `start` or `middle`.
    pub fn name(self) -> &'static str {
        match self {
            Self::End => "end",
            Self::Start => "start",
            Self::Middle => "middle",
        }
    }

    /// The pose at this instant of a sweep whose end pose is `end`, `sweep` being where
    /// deskewing put the sensor within it. The map's own frames keep that convention; the
    /// motion registration finds afterwards does not (the first deskewed frame's pose is
    /// relative to undeskewed sweeps, which sit at their middle).
    pub fn pose(self, end: &Isometry3<f64>, sweep: &SweepMotions) -> Isometry3<f64> {
        match self {
            Self::End => *end,
            Self::Start => end * sweep.start,
            Self::Middle => end * sweep.middle,
        }
    }
}
