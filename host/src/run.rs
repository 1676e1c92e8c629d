//! The `run` command (being written).

use anyhow::{bail, Result};
use std::io::Write;
use std::path::PathBuf;

/// `kiss-odom run` arguments.
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// Dataset folder or file.
    pub path: PathBuf,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs `kiss-odom run`.
pub fn execute(_args: &RunArgs, _err: &mut dyn Write) -> Result<i32> {
    bail!("run is not implemented yet")
}
