//! `run`'s options for what a run shows beside its poses.

use std::path::PathBuf;

/// The run command's options for what a run shows (`kiss-odom run --help`, "View and export").
#[derive(Debug, Clone, clap::Args)]
#[command(next_help_heading = "View and export")]
pub struct ViewArgs {
    /// Record the run for the Rerun viewer in FILE.rrd (open it with `rerun FILE.rrd`; the
    /// `rerun` cargo feature).
    #[arg(long, value_name = "FILE.rrd", conflicts_with = "rerun_connect")]
    pub rerun: Option<PathBuf>,
    /// Stream the run to a running Rerun viewer at ADDR (`rerun+http://HOST:PORT/proxy`, or
    /// `HOST:PORT`); the `rerun` cargo feature.
    #[arg(long, value_name = "ADDR")]
    pub rerun_connect: Option<String>,
    /// Log every Nth input point of a scan to Rerun (the full scan is 120k points a frame).
    #[arg(long, value_name = "N", default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..))]
    pub rerun_scan_stride: u32,
    /// Log the local map (and the trajectory so far) to Rerun every N frames, and after the
    /// last.
    #[arg(long, value_name = "N", default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..))]
    pub rerun_map_every: u32,
    /// Write the local map after the last frame to FILE (.ply or .pcd, f64 coordinates).
    #[arg(long, value_name = "FILE")]
    pub save_map: Option<PathBuf>,
    /// Write every registered frame's merge cloud in the world frame to FILE (.ply or .pcd),
    /// one point per voxel of `--save-cloud-voxel`.
    #[arg(long, value_name = "FILE")]
    pub save_cloud: Option<PathBuf>,
    /// Voxel edge (m) of the accumulated cloud: the first point in a voxel is kept.
    #[arg(long, value_name = "M", default_value_t = 0.2)]
    pub save_cloud_voxel: f64,
    /// Most points the accumulated cloud keeps; points in new voxels past it are dropped
    /// with a warning.
    #[arg(long, value_name = "N", default_value_t = 5_000_000)]
    pub save_cloud_max_points: usize,
}
