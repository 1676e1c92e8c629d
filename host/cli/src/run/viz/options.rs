//! `run`'s options for what a run shows beside its poses.

use kiss_odom_drive::settings::Output;
use std::path::PathBuf;

/// The run command's options for what a run shows (`kiss-odom run --help`, "View and export");
/// the fields without a flag come from the settings' `[output]` ([`ViewArgs::resolved`]).
#[derive(Debug, Clone, clap::Args)]
#[command(next_help_heading = "View and export")]
pub struct ViewArgs {
    /// Record the run for the Rerun viewer: in FILE.rrd (open it with `rerun FILE.rrd`), or
    /// streamed to a running viewer at ADDR (`rerun+http://HOST:PORT/proxy` or `HOST:PORT`);
    /// the `rerun` cargo feature.
    #[arg(long, value_name = "FILE.rrd|ADDR")]
    pub rerun: Option<PathBuf>,
    /// The viewer `--rerun` names when it is not a .rrd file.
    #[arg(skip)]
    pub rerun_connect: Option<String>,
    /// `[output] rerun_scan_stride`.
    #[arg(skip)]
    pub rerun_scan_stride: u32,
    /// `[output] rerun_map_every`.
    #[arg(skip)]
    pub rerun_map_every: u32,
    /// Write the local map after the last frame to FILE (.ply or .pcd, f64 coordinates).
    #[arg(long, value_name = "FILE")]
    pub save_map: Option<PathBuf>,
    /// Write every registered frame's merge cloud in the world frame to FILE (.ply or .pcd),
    /// thinned to one point per voxel of `output.cloud_voxel`.
    #[arg(long, value_name = "FILE")]
    pub save_cloud: Option<PathBuf>,
    /// `[output] cloud_voxel`.
    #[arg(skip)]
    pub save_cloud_voxel: f64,
    /// `[output] cloud_max_points`.
    #[arg(skip)]
    pub save_cloud_max_points: usize,
}

impl ViewArgs {
    /// These options with the settings' `[output]` values, and `--rerun` split into a file or
    /// a viewer's address by its name.
    pub fn resolved(&self, output: &Output) -> Self {
        let rrd = |p: &PathBuf| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("rrd"));
        let (rerun, rerun_connect) = match &self.rerun {
            Some(p) if !rrd(p) => (None, Some(p.to_string_lossy().into_owned())),
            other => (other.clone(), None),
        };
        Self {
            rerun,
            rerun_connect,
            rerun_scan_stride: output.rerun_scan_stride,
            rerun_map_every: output.rerun_map_every,
            save_map: self.save_map.clone(),
            save_cloud: self.save_cloud.clone(),
            save_cloud_voxel: output.cloud_voxel,
            save_cloud_max_points: output.cloud_max_points,
        }
    }
}
