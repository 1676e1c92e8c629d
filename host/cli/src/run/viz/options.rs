//! `run`'s options for what a run shows beside its poses.

use std::path::{Path, PathBuf};

/// The run command's options for what a run shows (`kiss-odom run --help`, "View and export");
/// how much it shows is the settings' `[output]`.
#[derive(Debug, Clone, clap::Args)]
#[command(next_help_heading = "View and export")]
pub struct ViewArgs {
    /// Record the run for the Rerun viewer: in FILE.rrd (open it with `rerun FILE.rrd`), or
    /// streamed to a running viewer at ADDR (`rerun+http://HOST:PORT/proxy` or `HOST:PORT`);
    /// the `rerun` cargo feature.
    #[arg(long, value_name = "FILE.rrd|ADDR")]
    pub rerun: Option<PathBuf>,
    /// Write the local map after the last frame to FILE (.ply or .pcd, f64 coordinates).
    #[arg(long, value_name = "FILE")]
    pub save_map: Option<PathBuf>,
    /// Write every registered frame's merge cloud in the world frame to FILE (.ply or .pcd),
    /// thinned to one point per voxel of `output.cloud_voxel`.
    #[arg(long, value_name = "FILE")]
    pub save_cloud: Option<PathBuf>,
}

impl ViewArgs {
    /// The recording file `--rerun` names: a `.rrd` name.
    pub fn rerun_file(&self) -> Option<&Path> {
        self.rerun.as_deref().filter(|p| is_rrd(p))
    }

    /// The viewer `--rerun` names: any other name.
    pub fn rerun_address(&self) -> Option<String> {
        let addr = self.rerun.as_deref().filter(|p| !is_rrd(p))?;
        Some(addr.to_string_lossy().into_owned())
    }

    /// The files these options name that a run writes.
    pub fn files(&self) -> impl Iterator<Item = &Path> {
        [
            self.save_map.as_deref(),
            self.save_cloud.as_deref(),
            self.rerun_file(),
        ]
        .into_iter()
        .flatten()
    }
}

fn is_rrd(p: &Path) -> bool {
    p.extension().is_some_and(|e| e.eq_ignore_ascii_case("rrd"))
}
