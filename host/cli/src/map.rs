//! `kiss-odom map`: prior maps for localization. `map build` turns a recording and its poses,
//! or a point cloud already in the map frame, into the tiled map file `run --map` reads
//! (`kiss_odom_core::prior_map`).

mod build;

use anyhow::Result;
use std::io::Write;

/// `kiss-odom map` arguments.
#[derive(Debug, clap::Args)]
pub struct MapArgs {
    /// What to do with a map.
    #[command(subcommand)]
    pub command: MapCommand,
}

/// `kiss-odom map` subcommands.
#[derive(Debug, clap::Subcommand)]
pub enum MapCommand {
    /// Write a prior map file (.komap) from a recording and its poses, or from a .ply/.pcd
    /// point cloud in the map frame.
    #[command(long_about = build::LONG_ABOUT)]
    Build(build::BuildArgs),
}

/// Runs `kiss-odom map`.
pub fn execute(args: &MapArgs, err: &mut dyn Write) -> Result<i32> {
    match &args.command {
        MapCommand::Build(a) => build::execute(a, err),
    }
}
