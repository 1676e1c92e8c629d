//! `kiss-odom run`: odometry over a recording, with poses, per-frame records, a summary,
//! metrics against ground truth and a plot written to the output folder.

use crate::exec::Pool;
use crate::io::{self, Format, Item, OpenOptions};
use crate::settings::{Scalar, Settings, Storage};
use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use kiss_odom_core::{
    Capacities, Exact, Flag, FrameError, FrameReport, Odometry, PointCodec, Quantized, Real,
};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use serde::Serialize;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Instant;

/// `kiss-odom run` arguments. Flags override `--config`, which overrides the defaults (the
/// reference's: max range 100 m, voxel max_range/100, deskew on).
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// Dataset: a KITTI `sequences/XX` folder, a folder of .bin/.ply/.pcd frames, a .bag or an
    /// .mcap file.
    pub path: PathBuf,
    /// Output folder (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// Input format; `auto` picks KITTI only for the benchmark layout.
    #[arg(long, value_enum, default_value_t = Format::Auto)]
    pub format: Format,
    /// Settings file (TOML, as written to `config.toml` by a previous run).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Maximum range r_max (m).
    #[arg(long)]
    pub max_range: Option<f64>,
    /// Minimum range (m).
    #[arg(long)]
    pub min_range: Option<f64>,
    /// Map voxel size v (m); default max_range / 100.
    #[arg(long)]
    pub voxel_size: Option<f64>,
    /// Deskew scans that carry per-point timestamps (default).
    #[arg(long, overrides_with = "no_deskew")]
    pub deskew: bool,
    /// Do not deskew.
    #[arg(long, overrides_with = "deskew")]
    pub no_deskew: bool,
    /// Scalar type of the core.
    #[arg(long, value_enum)]
    pub scalar: Option<Scalar>,
    /// Map point storage (exact agrees with the reference; quantized uses 6 bytes a point).
    #[arg(long, value_enum)]
    pub storage: Option<Storage>,
    /// Capacity preset of the core's buffers.
    #[arg(long, value_enum)]
    pub capacities: Option<Preset>,
    /// Worker threads for the correspondence search (0 = all cores); results are identical for
    /// any count.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Frames to process, `A..B` (B excluded), `A..` or `..B`.
    #[arg(long)]
    pub frames: Option<FrameRange>,
    /// Bag/MCAP topic (default: the only PointCloud2 topic).
    #[arg(long)]
    pub topic: Option<String>,
    /// Treat a skipped frame or ignored timestamps as an error (exit 1).
    #[arg(long)]
    pub strict: bool,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Capacity presets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Preset {
    /// `Capacities::FULL_SCALE` (KITTI-like sensors at 100 m).
    Full,
    /// `Capacities::SMALL` (microcontroller budget).
    Small,
    /// `Capacities::TINY` (16-beam sensor in 512 KiB); also sets the parameters it was sized
    /// for (`Config::tiny`: max range 50 m, voxel 2 m, 10 points a voxel) unless given.
    Tiny,
}

/// A half-open range of frame indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    /// First frame.
    pub start: usize,
    /// One past the last frame, if bounded.
    pub end: Option<usize>,
}

impl FrameRange {
    /// Whether `i` is inside.
    pub fn contains(&self, i: usize) -> bool {
        i >= self.start && self.end.is_none_or(|e| i < e)
    }
}

impl FromStr for FrameRange {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let bad = || format!("'{s}' is not a frame range like 10..20, 10.. or ..20");
        let (a, b) = s.split_once("..").ok_or_else(bad)?;
        let start = if a.is_empty() {
            0
        } else {
            a.trim().parse().map_err(|_| bad())?
        };
        let end = if b.is_empty() {
            None
        } else {
            Some(b.trim().parse().map_err(|_| bad())?)
        };
        if end.is_some_and(|e| e <= start) {
            return Err(format!("'{s}' is empty"));
        }
        Ok(Self { start, end })
    }
}

/// One line of `frames.csv`.
#[derive(Clone, Debug, Serialize)]
pub struct FrameRow {
    /// Frame index in the dataset.
    pub index: usize,
    /// Time in the core's frame call (ms).
    pub latency_ms: f64,
    /// ICP iterations.
    pub iterations: u32,
    /// Correspondences in the last iteration.
    pub correspondences: u32,
    /// sigma used.
    pub sigma: f64,
    /// Map voxels after the update.
    pub map_voxels: u32,
    /// Map points after the update.
    pub map_points: u32,
    /// Points given.
    pub input_points: u32,
    /// Merge cloud points.
    pub merge_points: u32,
    /// Registration cloud points.
    pub source_points: u32,
    /// Non-finite points skipped.
    pub dropped_non_finite: u32,
    /// Points past the scan capacity.
    pub dropped_truncated: u32,
    /// Merge voxels dropped (full).
    pub dropped_merge_full: u32,
    /// Source voxels dropped (full).
    pub dropped_source_full: u32,
    /// Map voxels refused (table full).
    pub dropped_map_voxels_full: u32,
    /// Map points refused (pool full).
    pub dropped_map_points_full: u32,
    /// Observability ratio (empty on the first frame).
    pub observability: Option<f64>,
    /// Whether the scan was deskewed.
    pub deskewed: bool,
    /// `ok`, the core's flags, `skipped` or `empty`.
    pub status: String,
}

/// Latency statistics (ms).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Latency {
    /// Median.
    pub p50: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Worst frame.
    pub max: f64,
}

/// `summary.json`.
#[derive(Debug, Serialize)]
pub struct Summary {
    /// Frames written (registered, empty and skipped).
    pub frames: usize,
    /// Seconds spent in the core's frame calls (file reading excluded).
    pub odometry_s: f64,
    /// Registered frames per second of core time.
    pub hz: f64,
    /// Per-frame core latency.
    pub latency_ms: Latency,
    /// Peak resident memory of the process (bytes), if the OS tells.
    pub peak_rss_bytes: Option<u64>,
    /// Bytes of the core's state (fixed at start).
    pub state_bytes: usize,
    /// Frames that could not be read (their pose is the constant-velocity prediction).
    pub skipped_frames: usize,
    /// Frames with no usable point (their pose is the prediction).
    pub empty_frames: usize,
    /// Frames whose status was not ok, by flag.
    pub degraded_frames: std::collections::BTreeMap<String, usize>,
    /// Largest buffer occupancy against capacity.
    pub high_water: serde_json::Value,
    /// Warnings printed while reading.
    pub warnings: usize,
    /// Input path, format and settings summary.
    pub input: serde_json::Value,
    /// Metrics against ground truth, when it exists.
    pub metrics: Option<serde_json::Value>,
}

/// What the frame loop produced.
struct Outcome {
    poses: Vec<Isometry3<f64>>,
    indices: Vec<usize>,
    times: Vec<Option<f64>>,
    rows: Vec<FrameRow>,
    state_bytes: usize,
    high_water: serde_json::Value,
    skipped: usize,
    empty: usize,
    warnings: usize,
    stop: Option<anyhow::Error>,
}

/// Resolves the settings: defaults, then `--config`, then flags.
pub fn settings_for(args: &RunArgs) -> Result<Settings> {
    let mut s = match &args.config {
        Some(p) => Settings::load(p)?,
        None => Settings::default(),
    };
    if args.capacities == Some(Preset::Tiny) {
        let t = kiss_odom_core::Config::<f64>::tiny();
        s.data.max_range = t.max_range;
        s.mapping.voxel_size = Some(t.voxel_size);
        s.mapping.max_points_per_voxel = t.max_points_per_voxel;
    }
    if let Some(r) = args.max_range {
        s.data.max_range = r;
    }
    if let Some(r) = args.min_range {
        s.data.min_range = r;
    }
    if let Some(v) = args.voxel_size {
        s.mapping.voxel_size = Some(v);
    }
    if args.deskew {
        s.data.deskew = true;
    }
    if args.no_deskew {
        s.data.deskew = false;
    }
    if let Some(x) = args.scalar {
        s.runtime.scalar = x;
    }
    if let Some(x) = args.storage {
        s.runtime.map_storage = x;
    }
    if let Some(p) = args.capacities {
        s.capacities = match p {
            Preset::Full => Capacities::FULL_SCALE,
            Preset::Small => Capacities::SMALL,
            Preset::Tiny => Capacities::TINY,
        }
        .into();
    }
    if let Some(t) = args.threads {
        s.runtime.threads = t;
    }
    Ok(s)
}

/// Runs `kiss-odom run`.
pub fn execute(args: &RunArgs, err: &mut dyn Write) -> Result<i32> {
    let settings = settings_for(args)?;
    // Validate before touching the disk.
    settings.core_config::<f64>()?;
    settings.capacities()?;
    let opts = OpenOptions {
        topic: args.topic.clone(),
        scan_points: settings.capacities()?.scan_points,
    };
    let dataset = io::open(&args.path, args.format, &opts)?;
    // What the dataset layer found before the first frame (counted in the summary).
    for w in &dataset.info.warnings {
        writeln!(err, "warning: {w}")?;
    }
    if let (true, Some(w)) = (args.strict, dataset.info.warnings.first()) {
        bail!("{w} (--strict)");
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("{}: cannot create output folder", args.out.display()))?;
    let info = dataset.info.clone();
    let outcome = match (settings.runtime.scalar, settings.runtime.map_storage) {
        (Scalar::F64, Storage::Exact) => drive::<f64, Exact>(&settings, dataset, args, err)?,
        (Scalar::F64, Storage::Quantized) => {
            drive::<f64, Quantized>(&settings, dataset, args, err)?
        }
        (Scalar::F32, Storage::Exact) => drive::<f32, Exact>(&settings, dataset, args, err)?,
        (Scalar::F32, Storage::Quantized) => {
            drive::<f32, Quantized>(&settings, dataset, args, err)?
        }
    };
    let summary = write_outputs(args, &settings, &info, &outcome)?;
    if !args.quiet {
        print_summary(&summary);
    }
    match outcome.stop {
        Some(e) => Err(e),
        None => Ok(0),
    }
}

fn drive<T: Real, P: PointCodec<T>>(
    settings: &Settings,
    mut dataset: io::Dataset,
    args: &RunArgs,
    err: &mut dyn Write,
) -> Result<Outcome> {
    let config = settings.core_config::<T>()?;
    let caps = settings.capacities()?;
    let mut arena = vec![0u64; caps.arena_words::<T, P>()];
    let mut odom = Odometry::<T, P, _>::new(config, caps, &mut arena[..])
        .map_err(|e| anyhow::anyhow!("cannot build the odometry: {e}"))?;
    let pool = Pool::new(settings.threads())?;
    let range = args.frames.unwrap_or(FrameRange {
        start: 0,
        end: None,
    });
    let total = dataset.frames.len_hint().map(|n| {
        let end = range.end.map_or(n, |e| e.min(n));
        end.saturating_sub(range.start)
    });
    let bar = progress_bar(total, args.quiet);
    if range.start > 0 {
        dataset.frames.seek(range.start);
    }
    let mut out = Outcome {
        poses: Vec::new(),
        indices: Vec::new(),
        times: Vec::new(),
        rows: Vec::new(),
        state_bytes: odom.state_bytes(),
        high_water: serde_json::Value::Null,
        skipped: 0,
        empty: 0,
        warnings: 0,
        stop: None,
    };
    let mut core_s = 0.0;
    loop {
        let item = match dataset.frames.next_item() {
            Ok(Some(item)) => item,
            Ok(None) => break,
            Err(e) => {
                out.stop = Some(e);
                break;
            }
        };
        let index = match &item {
            Item::Frame(f) => f.index,
            Item::Skipped { index, .. } => *index,
        };
        if !range.contains(index) {
            if range.end.is_some_and(|e| index >= e) {
                break;
            }
            continue;
        }
        let (row, time) = match item {
            Item::Skipped { reason, time, .. } => {
                bar.suspend(|| writeln!(err, "warning: {reason}")).ok();
                out.warnings += 1;
                if args.strict {
                    out.stop = Some(anyhow::anyhow!("{reason} (--strict)"));
                    break;
                }
                out.skipped += 1;
                odom.skip_frame();
                (placeholder_row(index, "skipped"), time)
            }
            Item::Frame(frame) => {
                for w in &frame.warnings {
                    bar.suspend(|| writeln!(err, "warning: {w}")).ok();
                    out.warnings += 1;
                }
                if args.strict && !frame.warnings.is_empty() {
                    out.stop = Some(anyhow::anyhow!("{} (--strict)", frame.warnings[0]));
                    break;
                }
                let pts: Vec<[T; 3]> = frame
                    .points
                    .iter()
                    .map(|p| [T::of(p[0]), T::of(p[1]), T::of(p[2])])
                    .collect();
                let t0 = Instant::now();
                let result = odom.register_frame_with(&pool, &pts, frame.stamps.as_deref());
                let dt = t0.elapsed().as_secs_f64();
                let row = match result {
                    Ok(report) => {
                        core_s += dt;
                        if args.strict && report.status.contains(Flag::TimestampsIgnored) {
                            out.stop = Some(anyhow::anyhow!(
                                "{}: timestamps unusable ({:?}), frame not deskewed (--strict)",
                                frame.name,
                                report.stamp_problem
                            ));
                            break;
                        }
                        row_of(index, dt, &report)
                    }
                    Err(e @ FrameError::Storage) => bail!("{}: {e}", frame.name),
                    Err(FrameError::EmptyScan) => {
                        bar.suspend(|| writeln!(err, "warning: {}: no usable point", frame.name))
                            .ok();
                        out.warnings += 1;
                        out.empty += 1;
                        odom.skip_frame();
                        placeholder_row(index, "empty")
                    }
                };
                let time = frame.time.or_else(|| {
                    dataset
                        .info
                        .frame_times
                        .as_ref()
                        .and_then(|t| t.get(index).copied())
                });
                (row, time)
            }
        };
        out.poses.push(widen(odom.pose()));
        out.indices.push(index);
        out.times.push(time);
        out.rows.push(row);
        bar.inc(1);
        if core_s > 0.0 {
            let n = out.rows.len() - out.skipped - out.empty;
            bar.set_message(format!("{:.1} Hz", n as f64 / core_s));
        }
    }
    bar.finish_and_clear();
    let hw = odom.high_water();
    let c = odom.capacities();
    out.high_water = serde_json::json!({
        "merge_points": [hw.merge_points, c.merge_points],
        "source_points": [hw.source_points, c.source_points],
        "map_voxels": [hw.map_voxels, c.map_voxels],
        "map_point_slots": [hw.map_point_slots, c.map_points],
    });
    if out.poses.is_empty() && out.stop.is_none() {
        bail!("{}: no frames in range", args.path.display());
    }
    Ok(out)
}

fn progress_bar(total: Option<usize>, quiet: bool) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
    }
    let bar = match total {
        Some(n) => ProgressBar::new(n as u64),
        None => ProgressBar::new_spinner(),
    };
    let style =
        ProgressStyle::with_template("{spinner} [{bar:40}] {pos}/{len} frames {msg} ({eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style.progress_chars("=> "));
    bar
}

/// A pose in any scalar as `f64`.
pub fn widen<T: Real>(p: &Isometry3<T>) -> Isometry3<f64> {
    let q = p.rotation.coords;
    let t = p.translation.vector;
    Isometry3::from_parts(
        Translation3::new(t.x.wide(), t.y.wide(), t.z.wide()),
        UnitQuaternion::new_normalize(Quaternion::new(
            q.w.wide(),
            q.x.wide(),
            q.y.wide(),
            q.z.wide(),
        )),
    )
}

fn row_of<T: Real>(index: usize, dt: f64, r: &FrameReport<T>) -> FrameRow {
    FrameRow {
        index,
        latency_ms: dt * 1e3,
        iterations: r.iterations,
        correspondences: r.correspondences,
        sigma: r.sigma.wide(),
        map_voxels: r.map_voxels,
        map_points: r.map_points,
        input_points: r.input_points,
        merge_points: r.merge_points,
        source_points: r.source_points,
        dropped_non_finite: r.dropped.non_finite,
        dropped_truncated: r.dropped.truncated,
        dropped_merge_full: r.dropped.merge_full,
        dropped_source_full: r.dropped.source_full,
        dropped_map_voxels_full: r.dropped.map_voxels_full,
        dropped_map_points_full: r.dropped.map_points_full,
        observability: r.observability.map(|o| o.wide()),
        deskewed: r.deskewed,
        status: r.status.to_string(),
    }
}

fn placeholder_row(index: usize, status: &str) -> FrameRow {
    FrameRow {
        index,
        latency_ms: 0.0,
        iterations: 0,
        correspondences: 0,
        sigma: f64::NAN,
        map_voxels: 0,
        map_points: 0,
        input_points: 0,
        merge_points: 0,
        source_points: 0,
        dropped_non_finite: 0,
        dropped_truncated: 0,
        dropped_merge_full: 0,
        dropped_source_full: 0,
        dropped_map_voxels_full: 0,
        dropped_map_points_full: 0,
        observability: None,
        deskewed: false,
        status: status.to_string(),
    }
}

/// Percentile by nearest rank of sorted values.
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let rank = ((p / 100.0) * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

/// Peak resident set size of this process from `/proc/self/status` (Linux).
pub fn peak_rss_bytes() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

fn write_outputs(
    args: &RunArgs,
    settings: &Settings,
    info: &io::DatasetInfo,
    o: &Outcome,
) -> Result<Summary> {
    let dir = &args.out;
    let path = |name: &str| dir.join(name);
    io::poses::write_kitti(&path("poses_kitti.txt"), &o.poses)?;
    // TUM needs a time per pose: the frames' own if every frame has one, else the frame
    // number for all (as the reference does without times), never a mix.
    let seconds = o.times.iter().all(Option::is_some);
    let timed: Vec<io::poses::TimedPose> = o
        .times
        .iter()
        .zip(&o.indices)
        .zip(&o.poses)
        .map(|((t, &i), p)| io::poses::TimedPose {
            time: t.filter(|_| seconds).unwrap_or(i as f64),
            pose: *p,
        })
        .collect();
    io::poses::write_tum(&path("poses_tum.txt"), &timed)?;
    std::fs::write(path("config.toml"), settings.to_toml()?)
        .with_context(|| format!("{}", path("config.toml").display()))?;
    write_csv(&path("frames.csv"), &o.rows)?;

    // Metrics over the frames that have ground truth (the dataset warned about the others),
    // both trajectories re-based to the first of them.
    let gt_rows = info.ground_truth_for(&o.indices);
    let paired: Vec<usize> = (0..gt_rows.len())
        .filter(|&k| gt_rows[k].is_some())
        .collect();
    let gt: Option<Vec<Isometry3<f64>>> =
        (!paired.is_empty()).then(|| gt_rows.iter().flatten().copied().collect());
    let metrics = match (&gt, paired.first()) {
        (Some(gt), Some(&first)) => {
            let base = o.poses[first].inverse();
            let est: Vec<Isometry3<f64>> = paired
                .iter()
                .map(|&k| {
                    if first == 0 {
                        o.poses[k]
                    } else {
                        base * o.poses[k]
                    }
                })
                .collect();
            Some(serde_json::to_value(crate::metrics::evaluate(&est, gt)?)?)
        }
        _ => None,
    };
    let gt = gt.map(|gt| {
        let origin = paired
            .first()
            .map_or(Isometry3::identity(), |&k| o.poses[k]);
        gt.iter().map(|p| origin * p).collect::<Vec<_>>()
    });
    let title = args
        .path
        .file_name()
        .map_or_else(|| "trajectory".into(), |n| n.to_string_lossy().into_owned());
    crate::plot::trajectory_png(&path("trajectory.png"), &o.poses, gt.as_deref(), &title)?;

    let mut lat: Vec<f64> = o
        .rows
        .iter()
        .filter(|r| r.status != "skipped" && r.status != "empty")
        .map(|r| r.latency_ms)
        .collect();
    lat.sort_by(|a, b| a.total_cmp(b));
    let odometry_s = lat.iter().sum::<f64>() / 1e3;
    let mut degraded = std::collections::BTreeMap::new();
    for r in &o.rows {
        if r.status != "ok" {
            for flag in r.status.split('|') {
                *degraded.entry(flag.to_string()).or_insert(0) += 1;
            }
        }
    }
    let summary = Summary {
        frames: o.rows.len(),
        odometry_s,
        hz: if odometry_s > 0.0 {
            lat.len() as f64 / odometry_s
        } else {
            0.0
        },
        latency_ms: Latency {
            p50: percentile(&lat, 50.0),
            p99: percentile(&lat, 99.0),
            max: lat.last().copied().unwrap_or(0.0),
        },
        peak_rss_bytes: peak_rss_bytes(),
        state_bytes: o.state_bytes,
        skipped_frames: o.skipped,
        empty_frames: o.empty,
        degraded_frames: degraded,
        high_water: o.high_water.clone(),
        warnings: o.warnings + info.warnings.len(),
        input: serde_json::json!({
            "path": args.path.display().to_string(),
            "format": info.format,
            "kitti_correction": info.kitti_correction,
            "ground_truth": info.ground_truth_path.as_ref().map(|p| p.display().to_string()),
            "scalar": settings.runtime.scalar,
            "map_storage": settings.runtime.map_storage,
            "threads": settings.threads(),
            "tum_times": if seconds { "seconds" } else { "frame numbers" },
        }),
        metrics,
    };
    let json = serde_json::to_string_pretty(&summary)?;
    std::fs::write(path("summary.json"), json + "\n")
        .with_context(|| format!("{}", path("summary.json").display()))?;
    Ok(summary)
}

fn write_csv(path: &Path, rows: &[FrameRow]) -> Result<()> {
    let mut s = String::from(
        "index,latency_ms,iterations,correspondences,sigma,map_voxels,map_points,input_points,\
         merge_points,source_points,dropped_non_finite,dropped_truncated,dropped_merge_full,\
         dropped_source_full,dropped_map_voxels_full,dropped_map_points_full,observability,\
         deskewed,status\n",
    );
    for r in rows {
        s.push_str(&format!(
            "{},{:.3},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
            r.index,
            r.latency_ms,
            r.iterations,
            r.correspondences,
            r.sigma,
            r.map_voxels,
            r.map_points,
            r.input_points,
            r.merge_points,
            r.source_points,
            r.dropped_non_finite,
            r.dropped_truncated,
            r.dropped_merge_full,
            r.dropped_source_full,
            r.dropped_map_voxels_full,
            r.dropped_map_points_full,
            r.observability.map_or(String::new(), |o| format!("{o:.4}")),
            r.deskewed,
            r.status
        ));
    }
    std::fs::write(path, s).with_context(|| format!("{}", path.display()))
}

fn print_summary(s: &Summary) {
    println!(
        "{} frames, {:.1} Hz in the core (p50 {:.1} ms, p99 {:.1} ms, max {:.1} ms), state {:.1} MiB",
        s.frames,
        s.hz,
        s.latency_ms.p50,
        s.latency_ms.p99,
        s.latency_ms.max,
        s.state_bytes as f64 / (1 << 20) as f64
    );
    if let Some(m) = &s.metrics {
        if let Some(obj) = m.as_object() {
            let parts: Vec<String> = obj
                .iter()
                .filter(|(_, v)| v.is_number())
                .map(|(k, v)| format!("{k} {:.4}", v.as_f64().unwrap_or(f64::NAN)))
                .collect();
            println!("metrics: {}", parts.join(", "));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges_parse_and_reject_nonsense() {
        assert_eq!(
            "3..7".parse(),
            Ok(FrameRange {
                start: 3,
                end: Some(7)
            })
        );
        assert_eq!(
            "5..".parse(),
            Ok(FrameRange {
                start: 5,
                end: None
            })
        );
        assert_eq!(
            "..4".parse(),
            Ok(FrameRange {
                start: 0,
                end: Some(4)
            })
        );
        assert!("7..3".parse::<FrameRange>().is_err());
        assert!("x".parse::<FrameRange>().is_err());
    }

    #[test]
    fn percentiles_use_nearest_rank() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(percentile(&v, 50.0), 50.0);
        assert_eq!(percentile(&v, 99.0), 99.0);
        assert_eq!(percentile(&[4.0], 99.0), 4.0);
    }
}
