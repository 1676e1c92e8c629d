//! The LiDAR simulator and the `simulate` command (being written).

use anyhow::{bail, Result};
use std::path::PathBuf;

/// `kiss-odom simulate` arguments.
#[derive(Debug, clap::Args)]
pub struct SimulateArgs {
    /// Output folder (generic layout).
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs `kiss-odom simulate`.
pub fn execute(_args: &SimulateArgs) -> Result<i32> {
    bail!("simulate is not implemented yet")
}
