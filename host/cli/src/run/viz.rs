//! What a run shows beside its poses: observers ([`Observer`]) the run loop calls after every
//! frame and once at the end, each turning the driver's outcomes into one output. `--save-map` writes the
//! final local map, `--save-cloud` the whole run's registered points voxel-thinned on the host
//! ([`export`]), and `--rerun` records every frame for the Rerun viewer
//! (`recording` module, cargo feature `rerun`). They never change what the driver computes: a run
//! with them gives the same poses, byte for byte, as one without.

pub mod export;
mod options;
#[cfg(feature = "rerun")]
pub mod recording;

pub use options::ViewArgs;

use super::observe::Observer;
use anyhow::{bail, Result};
use kiss_odom_drive::settings::Output;
use std::path::Path;

/// Checks `args` with the settings' `output` without creating anything: the file types, the cloud's
/// voxel, what this build can record, that no two options name one file (one would replace the
/// other) and that no file named is one of the run's `inputs` (the file at an output's name is
/// removed before the run starts, so this comes first).
pub fn check(args: &ViewArgs, output: &Output, inputs: &[&Path]) -> Result<()> {
    if let Some(path) = &args.save_map {
        export::MapExport::new(path)?;
    }
    if let Some(path) = &args.save_cloud {
        export::CloudExport::new(path, output.cloud_voxel, output.cloud_max_points)?;
    }
    if args.rerun.is_some() {
        rerun_available()?;
    }
    kiss_odom_io::write::refuse_shared(&[
        ("--save-map", args.save_map.as_deref()),
        ("--save-cloud", args.save_cloud.as_deref()),
        ("--rerun", args.rerun_file()),
    ])?;
    for path in args.files() {
        kiss_odom_io::write::refuse_input(path, inputs)?;
    }
    Ok(())
}

/// The observers `args` ask for, in the order they run; an error for a file type or an option
/// this build cannot serve ([`check`] says so before anything is created).
pub fn observers(args: &ViewArgs, output: &Output) -> Result<Vec<Box<dyn Observer>>> {
    let mut out: Vec<Box<dyn Observer>> = Vec::new();
    if let Some(path) = &args.save_map {
        out.push(Box::new(export::MapExport::new(path)?));
    }
    if let Some(path) = &args.save_cloud {
        out.push(Box::new(export::CloudExport::new(
            path,
            output.cloud_voxel,
            output.cloud_max_points,
        )?));
    }
    if args.rerun.is_some() {
        out.push(rerun_observer(args, output)?);
    }
    Ok(out)
}

#[cfg(feature = "rerun")]
fn rerun_observer(args: &ViewArgs, output: &Output) -> Result<Box<dyn Observer>> {
    Ok(Box::new(recording::Recorder::new(args, output)?))
}

#[cfg(not(feature = "rerun"))]
fn rerun_observer(_: &ViewArgs, _: &Output) -> Result<Box<dyn Observer>> {
    bail!("{RERUN_MISSING}")
}

/// Why a build without the `rerun` feature refuses `--rerun`.
const RERUN_MISSING: &str = "--rerun needs the `rerun` cargo feature: \
     cargo build --release -p kiss-odom --features rerun";

/// Whether this build can record for Rerun.
fn rerun_available() -> Result<()> {
    if !cfg!(feature = "rerun") {
        bail!("{RERUN_MISSING}");
    }
    Ok(())
}
