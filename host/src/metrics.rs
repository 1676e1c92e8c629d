//! Trajectory metrics and the `eval` command (being written).

use anyhow::{bail, Result};
use std::path::PathBuf;

/// `kiss-odom eval` arguments.
#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    /// Estimated trajectory (KITTI 3x4 per line).
    pub estimate: PathBuf,
    /// Ground truth (KITTI 3x4 per line, same frame as the estimate).
    pub ground_truth: PathBuf,
}

/// Runs `kiss-odom eval`.
pub fn execute(_args: &EvalArgs) -> Result<i32> {
    bail!("eval is not implemented yet")
}
