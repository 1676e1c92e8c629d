//! The `crosscheck` command (being written).

use anyhow::{bail, Result};
use std::io::Write;
use std::path::PathBuf;

/// `kiss-odom crosscheck` arguments.
#[derive(Debug, clap::Args)]
pub struct CrosscheckArgs {
    /// Dataset folder or file.
    pub dataset: PathBuf,
}

/// Runs `kiss-odom crosscheck`.
pub fn execute(_args: &CrosscheckArgs, _err: &mut dyn Write) -> Result<i32> {
    bail!("crosscheck is not implemented yet")
}
