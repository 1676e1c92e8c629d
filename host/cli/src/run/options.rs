//! `kiss-odom run`'s options, and the instant within a sweep a pose refers to.

use super::viz::ViewArgs;
use crate::args::CommonArgs;
use kiss_odom_drive::SweepMotions;
use nalgebra::Isometry3;
use std::path::PathBuf;

/// `kiss-odom run` arguments. Flags override `--config`, which overrides the defaults (the
/// reference's: max range 100 m, voxel max_range/100, deskew on).
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// Dataset: a KITTI `sequences/XX` folder, a folder of .bin/.ply/.pcd frames, a .bag or an
    /// .mcap file, or a .pcap/.pcapng recording of Velodyne or Ouster packets.
    pub path: PathBuf,
    /// Outputs and how the run goes.
    #[command(flatten)]
    pub run: RunOptions,
    /// Input, pipeline and core options.
    #[command(flatten)]
    pub common: CommonArgs,
    /// Rerun recording and point-cloud exports.
    #[command(flatten)]
    pub view: ViewArgs,
}

/// What `run` and `live` share: where the outputs go and how the run goes.
#[derive(Debug, Clone, clap::Args)]
pub struct RunOptions {
    /// Output folder (created if missing); the outputs of an earlier run there are replaced,
    /// and a file of an output's name that no earlier run wrote refuses the run.
    #[arg(long)]
    pub out: PathBuf,
    /// Treat a skipped frame, ignored timestamps or a dataset warning as an error (exit 1).
    #[arg(long)]
    pub strict: bool,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
    /// The instant within a deskewed sweep each pose refers to: the reference deskews to the
    /// end; `start` and `middle` move the pose back along the frame's motion. The TUM file's
    /// first line states it.
    #[arg(long, value_enum, default_value_t = PoseTime::End)]
    pub pose_time: PoseTime,
}

/// The instant within a sweep a pose refers to (`--pose-time`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
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
