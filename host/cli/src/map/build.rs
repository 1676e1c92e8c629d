//! `kiss-odom map build`: points into a prior map file through
//! [`kiss_odom_drive::map_build::MapBuilder`]. A recording's frames are deskewed and cropped
//! as the odometry takes them in, moved by their poses and added in order; a `.ply`/`.pcd`
//! cloud is added as it is. The file is written whole or not at all
//! ([`kiss_odom_io::write`]).

use crate::args::CommonArgs;
use anyhow::{bail, ensure, Context, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use kiss_odom_core::Config;
use kiss_odom_drive::map_build::{MapBuilder, MapParams, MapStats};
use kiss_odom_drive::Settings;
use kiss_odom_io::dataset::Format;
use kiss_odom_io::folders::generic;
use kiss_odom_io::{self as io, Item, Selection};
use nalgebra::Isometry3;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

/// `map build --help`'s description.
pub(super) const LONG_ABOUT: &str = "\
Write a prior map file (.komap) for localization (`run --map`).

From a recording: INPUT is any dataset `run` reads and --poses a KITTI file with one pose per \
frame of it, in order (the poses_kitti.txt `run` wrote for the same recording and options, or \
its ground truth, e.g. a simulated folder's poses.txt). Each frame is deskewed over the motion \
between its pose and the previous one and cropped to the run's ranges, as the odometry takes \
it in, then moved by its pose.

From a cloud: INPUT is a .ply or .pcd file already in the map frame (no --poses); every point \
is added.

Points are kept with the local map's rule at the run's voxel size (the setting \
mapping.voxel_size, else --max-range / 100, so a map built with a run's options matches its \
map): at most --points-per-voxel a voxel, none closer than v / sqrt(N) to another. The map is \
cut into --tile-size tiles for loading a part at a time. Prints one line: tiles, voxels, points \
kept of those read, the x-y extent, the file's bytes.

Example: kiss-odom map build seq/ --poses out/poses_kitti.txt --out city.komap";

/// `kiss-odom map build` arguments.
#[derive(Debug, clap::Args)]
pub struct BuildArgs {
    /// A recording `run` reads (with --poses), or a .ply or .pcd cloud in the map frame.
    pub input: PathBuf,
    /// The map file to write (suggested extension .komap); replaced if it exists, never an
    /// input.
    #[arg(long)]
    pub out: PathBuf,
    /// KITTI poses, one per frame of INPUT in order (with --frames, of those frames).
    #[arg(long)]
    pub poses: Option<PathBuf>,
    /// Tile edge (m), a whole multiple of the voxel size.
    #[arg(long, default_value_t = 50.0)]
    pub tile_size: f64,
    /// Points kept per voxel at most (1 to 255).
    #[arg(long, default_value_t = 5)]
    pub points_per_voxel: u32,
    /// The map frame's name (ASCII, at most 16 bytes).
    #[arg(long, default_value = "map")]
    pub frame: String,
    /// Input, pipeline and core options (the voxel size and ranges come from here).
    #[command(flatten)]
    pub common: CommonArgs,
}

/// Runs `kiss-odom map build`.
pub fn execute(args: &BuildArgs, err: &mut dyn Write) -> Result<i32> {
    let settings = args.common.settings(None)?;
    let config = settings.core_config::<f64>()?;
    let mut builder = MapBuilder::new(MapParams {
        voxel_size: config.voxel_size,
        tile_size: args.tile_size,
        points_per_voxel: args.points_per_voxel,
        frame: args.frame.clone(),
    })?;
    let cloud = cloud_format(&args.input).filter(|_| args.poses.is_none());
    let inputs: Vec<&Path> = [Some(args.input.as_path()), args.poses.as_deref()]
        .into_iter()
        .chain([args.common.pipeline.config.as_deref()])
        .flatten()
        .collect();
    kiss_odom_io::write::refuse_input(&args.out, &inputs)?;
    ensure!(
        !args.out.is_dir(),
        "{}: is a folder; --out names the map file",
        args.out.display()
    );
    match (cloud, &args.poses) {
        (Some(format), _) => {
            let c = generic::read_cloud(&args.input, format, usize::MAX)?;
            builder.add(&c.points)?;
        }
        (None, Some(poses)) => add_recording(args, &settings, &config, poses, &mut builder, err)?,
        (None, None) => bail!(
            "{}: a recording needs --poses (one KITTI pose per frame); only a .ply or .pcd \
             cloud is read without",
            args.input.display()
        ),
    }
    let (bytes, stats) = builder
        .encode()
        .with_context(|| args.input.display().to_string())?;
    kiss_odom_io::write::write(&args.out, &bytes)?;
    println!("{}", summary(&stats, args.tile_size, &args.out));
    Ok(0)
}

/// The line the command prints.
fn summary(s: &MapStats, tile_size: f64, out: &Path) -> String {
    format!(
        "map: {} tiles of {tile_size} m, {} voxels, {} points (of {} in), {:.1} x {:.1} m, {} \
         bytes -> {}",
        s.tiles,
        s.voxels,
        s.points_kept,
        s.points_in,
        s.extent[0],
        s.extent[1],
        s.bytes,
        out.display()
    )
}

/// The cloud format of a `.ply` or `.pcd` file name.
fn cloud_format(path: &Path) -> Option<Format> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    match ext.as_str() {
        "ply" => Some(Format::Ply),
        "pcd" => Some(Format::Pcd),
        _ => None,
    }
}

/// Adds every frame of the recording, pose `k` to item `k` (a frame that cannot be read keeps
/// its pose unused, as `run` writes one for it).
fn add_recording(
    args: &BuildArgs,
    settings: &Settings,
    config: &Config<f64>,
    poses_path: &Path,
    builder: &mut MapBuilder,
    err: &mut dyn Write,
) -> Result<()> {
    let poses = io::poses::read_kitti(poses_path)?;
    let scan_points = settings.capacities()?.scan_points;
    let options = args.common.open_options(scan_points, &settings.input);
    let mut dataset = io::open(&args.input, args.common.input.format, &options)?;
    for w in &dataset.info.warnings {
        writeln!(err, "warning: {w}")?;
    }
    let mut frames = Selection::new(dataset.frames.as_mut(), args.common.input.range());
    let counts = |frames: usize| {
        anyhow::anyhow!(
            "{}: {} poses for {frames} frames of {}; give one pose per frame",
            poses_path.display(),
            poses.len(),
            args.input.display()
        )
    };
    if let Some(n) = frames.len_hint().filter(|&n| n != poses.len()) {
        return Err(counts(n));
    }
    let bar = progress_bar(frames.len_hint());
    let (mut items, mut undeskewed) = (0, 0);
    for item in &mut frames {
        let k = items;
        items += 1;
        let Some(pose) = poses.get(k) else {
            continue;
        };
        match item? {
            Item::Skipped { reason, .. } => {
                bar.suspend(|| writeln!(err, "warning: {reason} (left out)"))?;
            }
            Item::Frame(f) => {
                for w in &f.warnings {
                    bar.suspend(|| writeln!(err, "warning: {w}"))?;
                }
                let motion = match k {
                    0 => Isometry3::identity(),
                    _ => poses[k - 1].inverse() * pose,
                };
                let stamps = f.stamps.as_deref();
                let pre = builder.add_scan(&f.points, stamps, &motion, pose, config)?;
                undeskewed += usize::from(pre.stamp_problem.is_some());
            }
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    if items != poses.len() {
        return Err(counts(items));
    }
    if undeskewed > 0 {
        writeln!(
            err,
            "warning: {undeskewed} frames' timestamps were unusable; added without deskewing"
        )?;
    }
    Ok(())
}

/// A bar of frames on a terminal, hidden otherwise.
fn progress_bar(total: Option<usize>) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
    }
    let bar = total.map_or_else(ProgressBar::new_spinner, |n| ProgressBar::new(n as u64));
    let style = ProgressStyle::with_template("{spinner} [{bar:40}] {pos}/{len} frames ({eta})")
        .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style.progress_chars("=> "));
    bar
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_ply_and_pcd_names_are_clouds() {
        assert_eq!(cloud_format(Path::new("a/b.PLY")), Some(Format::Ply));
        assert_eq!(cloud_format(Path::new("b.pcd")), Some(Format::Pcd));
        for other in ["seq", "x.bag", "y.bin", "ply"] {
            assert_eq!(cloud_format(Path::new(other)), None, "{other}");
        }
    }
}
