//! The `bench` command (being written).

use anyhow::{bail, Result};
use std::io::Write;
use std::path::PathBuf;

/// `kiss-odom bench` arguments.
#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Dataset folder or file.
    pub dataset: PathBuf,
}

/// Runs `kiss-odom bench`.
pub fn execute(_args: &BenchArgs, _err: &mut dyn Write) -> Result<i32> {
    bail!("bench is not implemented yet")
}
