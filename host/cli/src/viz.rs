//! What a run shows beside its poses: observers ([`Observer`]) the run loop calls after every
//! frame and once at the end, each turning the driver's outcomes into one output. `--save-map` writes the
//! final local map, `--save-cloud` the whole run's registered points voxel-thinned on the host
//! ([`export`]), and `--rerun`/`--rerun-connect` record every frame for the Rerun viewer
//! (`recording` module, cargo feature `rerun`). They never change what the driver computes: a run
//! with them gives the same poses, byte for byte, as one without.

pub mod export;
#[cfg(feature = "rerun")]
pub mod recording;

use crate::run::observe::Observer;
use anyhow::{bail, Result};
use std::path::{Path, PathBuf};

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

/// Checks `args` without creating anything: the file types, the cloud's voxel, what this
/// build can record, and that no file named is one of the run's `inputs` (the file at an
/// output's name is removed before the run starts, so this comes first).
pub fn check(args: &ViewArgs, inputs: &[&Path]) -> Result<()> {
    if let Some(path) = &args.save_map {
        export::MapExport::new(path)?;
    }
    if let Some(path) = &args.save_cloud {
        export::CloudExport::new(path, args.save_cloud_voxel, args.save_cloud_max_points)?;
    }
    if args.rerun.is_some() || args.rerun_connect.is_some() {
        rerun_available()?;
    }
    if let Some(path) = &args.rerun {
        let rrd = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("rrd"));
        if !rrd {
            bail!("{}: give a .rrd file name", path.display());
        }
    }
    for path in files(args) {
        kiss_odom_io::write::refuse_input(path, inputs)?;
    }
    Ok(())
}

/// The observers `args` ask for, in the order they run; an error for a file type or an option
/// this build cannot serve ([`check`] says so before anything is created).
pub fn observers(args: &ViewArgs) -> Result<Vec<Box<dyn Observer>>> {
    let mut out: Vec<Box<dyn Observer>> = Vec::new();
    if let Some(path) = &args.save_map {
        out.push(Box::new(export::MapExport::new(path)?));
    }
    if let Some(path) = &args.save_cloud {
        out.push(Box::new(export::CloudExport::new(
            path,
            args.save_cloud_voxel,
            args.save_cloud_max_points,
        )?));
    }
    if args.rerun.is_some() || args.rerun_connect.is_some() {
        out.push(rerun_observer(args)?);
    }
    Ok(out)
}

#[cfg(feature = "rerun")]
fn rerun_observer(args: &ViewArgs) -> Result<Box<dyn Observer>> {
    Ok(Box::new(recording::Recorder::new(args)?))
}

#[cfg(not(feature = "rerun"))]
fn rerun_observer(_: &ViewArgs) -> Result<Box<dyn Observer>> {
    bail!("{RERUN_MISSING}")
}

/// Why a build without the `rerun` feature refuses `--rerun` and `--rerun-connect`.
const RERUN_MISSING: &str = "--rerun and --rerun-connect need the `rerun` cargo feature: \
     cargo build --release -p kiss-odom --features rerun";

/// Whether this build can record for Rerun.
fn rerun_available() -> Result<()> {
    if !cfg!(feature = "rerun") {
        bail!("{RERUN_MISSING}");
    }
    Ok(())
}

/// The files `args` name that a run writes, for removing stale ones before it starts.
pub fn files(args: &ViewArgs) -> impl Iterator<Item = &PathBuf> {
    [&args.save_map, &args.save_cloud, &args.rerun]
        .into_iter()
        .flatten()
}
