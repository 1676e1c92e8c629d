//! `kiss-odom run`'s options.

use super::viz::ViewArgs;
use crate::args::CommonArgs;
use std::path::PathBuf;

/// `kiss-odom run` arguments. Flags override `--set`, which overrides `--config`, which
/// overrides the defaults (the reference's: max range 100 m, voxel max_range/100, deskew on).
#[derive(Debug, Clone, clap::Args)]
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

/// What `run` and `live` share: where the outputs go and how the run goes (the rest of it is
/// the settings' `[output]`).
#[derive(Debug, Clone, clap::Args)]
pub struct RunOptions {
    /// Output folder (created if missing); the outputs of an earlier run there are replaced,
    /// and a file of an output's name that no earlier run wrote refuses the run.
    #[arg(long)]
    pub out: PathBuf,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
    /// Localize in this prior map (`kiss-odom map build`): the poses are written in the map's
    /// frame and frames.csv's `localization` column says how sure each is.
    #[arg(long, requires = "initial_pose")]
    pub map: Option<PathBuf>,
    /// With --map: the start pose in the map frame, X,Y,Z,ROLL,PITCH,YAW (metres, degrees;
    /// R = Rz(yaw) Ry(pitch) Rx(roll)).
    #[arg(long, requires = "map", allow_hyphen_values = true)]
    pub initial_pose: Option<String>,
}
