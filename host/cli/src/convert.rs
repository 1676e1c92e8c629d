//! `kiss-odom convert`: any recording `run` reads (a pcap of sensor packets, a bag, an MCAP
//! file, a ROS 2 sqlite3 bag, a folder of frames) written as the generic layout, so that it can be inspected, fed
//! to other tools (the reference's generic loader reads it) and compared point by point.
//!
//! Frame `k` (its identity in the recording, see [`kiss_odom_io::Frame::index`]) becomes
//! `velodyne/NNNNNN.bin` (float32 x, y, z, intensity; intensity 0 where the reader keeps none)
//! and, when it has per-point times, `timestamps/NNNNNN.bin` (float64, as the reader gives
//! them: seconds since the sweep began for a sensor recording); `times.txt` has the frame
//! times when every frame from 0 on has one; `imu.csv` ([`kiss_odom_io::imu`]) the IMU
//! samples that came with the frames written, where the sensor sends them. A frame that cannot be read is left out with a warning
//! (the generic reader sees the gap); a damaged container ends the conversion with its error
//! after the frames before it. Every file is written under a temporary name and renamed when
//! complete ([`kiss_odom_io::write`]), so a full disk or a signal leaves whole frames only.
//! It replaces nothing: a file already at one of those names (an earlier conversion's, or the
//! user's own) refuses the conversion before the recording is opened.

use crate::args::InputArgs;
use anyhow::{bail, Context, Result};
use kiss_odom_drive::Settings;
use kiss_odom_io::folders::{bin, generic};
use kiss_odom_io::{self as io, Item};
use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};

/// `kiss-odom convert` arguments.
#[derive(Debug, clap::Args)]
pub struct ConvertArgs {
    /// Recording: a .pcap/.pcapng (with --calibration for Ouster), a .bag, an .mcap, a ROS 2 bag
    /// (its folder or a .db3) or a folder.
    pub path: PathBuf,
    /// Output folder; its `velodyne/` and `timestamps/` must be empty or missing, and it must
    /// have no `times.txt` or `imu.csv` (nothing there is replaced).
    #[arg(long)]
    pub out: PathBuf,
    /// Nothing printed but warnings.
    #[arg(long, short)]
    pub quiet: bool,
    /// Which frames, how read.
    #[command(flatten, next_help_heading = "Input")]
    pub input: InputArgs,
    /// How sensor packets become frames, by key: `input.port`, `input.cut_angle`,
    /// `input.frame_period` (the book's configuration reference); repeatable.
    #[arg(long, value_name = "input.KEY=VALUE")]
    pub set: Vec<String>,
}

fn create(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))
}

/// Refuses an output folder that already holds a file `convert` would write: a frame or
/// stamp file, `times.txt`, `imu.csv`. Convert into a new folder, so that nothing of another
/// recording stays and nothing of the user's is replaced.
fn refuse_occupied(out: &Path) -> Result<()> {
    for dir in ["velodyne", "timestamps"].map(|d| out.join(d)) {
        let first = std::fs::read_dir(&dir)
            .ok()
            .and_then(|mut d| d.next())
            .and_then(Result::ok);
        if let Some(entry) = first {
            bail!(
                "{}: already there ({} is not empty); convert into a new folder, so that nothing \
                 is replaced",
                entry.path().display(),
                dir.display()
            );
        }
    }
    for name in ["times.txt", kiss_odom_io::imu::CSV_NAME] {
        let path = out.join(name);
        if std::fs::symlink_metadata(&path).is_ok() {
            bail!(
                "{}: already there; convert into a new folder, so that nothing is replaced",
                path.display()
            );
        }
    }
    Ok(())
}

/// Runs `kiss-odom convert`.
pub fn execute(args: &ConvertArgs, err: &mut dyn Write) -> Result<i32> {
    let frames_dir = args.out.join("velodyne");
    refuse_occupied(&args.out)?;
    if let Some(a) = args
        .set
        .iter()
        .find(|a| !a.trim_start().starts_with("input."))
    {
        bail!("--set {a}: convert takes only the input.* settings");
    }
    let input = Settings::default().with_set(&args.set)?.input;
    let mut dataset = io::open(
        &args.path,
        args.input.format,
        &args.input.open_options(usize::MAX, &input),
    )?;
    create(&frames_dir)?;
    let range = args.input.range();
    let (mut written, mut times) = (0usize, Some(String::new()));
    let mut imu = String::new();
    let stamps_dir = args.out.join("timestamps");
    let end = loop {
        if let Some(sig) = crate::interrupt::requested() {
            break Ok(crate::interrupt::exit_status(sig));
        }
        let item = match dataset.frames.next_item() {
            Ok(Some(item)) => item,
            Ok(None) => break Ok(0),
            Err(e) => break Err(e),
        };
        if range.is_past(item.index()) {
            break Ok(0);
        }
        if !range.contains(item.index()) {
            continue;
        }
        let frame = match item {
            Item::Frame(f) => f,
            Item::Skipped { reason, .. } => {
                writeln!(err, "warning: {reason} (left out)")?;
                continue;
            }
        };
        for w in &frame.warnings {
            writeln!(err, "warning: {w}")?;
        }
        let name = format!("{:06}.bin", frame.index);
        let bytes = bin::encode_with_intensity(&frame.points, frame.intensity.as_deref());
        // Whole or not at all: a frame cut short by a full disk would read as a shorter frame.
        kiss_odom_io::write::write(&frames_dir.join(&name), &bytes)?;
        if let Some(stamps) = &frame.stamps {
            create(&stamps_dir)?;
            generic::write_timestamps(&stamps_dir.join(&name), stamps)?;
        }
        for sample in &frame.imu {
            sample.push_csv_row(&mut imu);
        }
        // Row k of times.txt is frame k's: only a run of frames from 0 without gaps has one.
        times = match (times, frame.time) {
            (Some(mut text), Some(t)) if frame.index == written => {
                let _ = writeln!(text, "{t}");
                Some(text)
            }
            _ => None,
        };
        written += 1;
    };
    for w in dataset.frames.trailer().warnings {
        writeln!(err, "warning: {w}")?;
    }
    if let Some(text) = times.filter(|_| written > 0) {
        kiss_odom_io::write::write(&args.out.join("times.txt"), text.as_bytes())?;
    }
    if !imu.is_empty() {
        let text = format!("{}\n{imu}", kiss_odom_io::imu::CSV_HEADER);
        kiss_odom_io::write::write(&args.out.join(kiss_odom_io::imu::CSV_NAME), text.as_bytes())?;
    }
    if !args.quiet {
        println!("{written} frames written to {}", args.out.display());
    }
    end
}
