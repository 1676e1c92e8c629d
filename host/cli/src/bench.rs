//! `kiss-odom-dev bench`: speed, latency and memory of kiss-odom next to the reference kiss-icp
//! 1.3.0 on the same frames.
//!
//! The frames are read into memory first (file reading is never timed) and handed to the
//! reference byte for byte ([`mod@reference`]); then both implementations run over all of them,
//! each run a fresh pipeline, taking turns (ours, ref, ref, ours, ...) so that machine drift
//! hits both alike. Only the per-frame odometry call is timed. The headline is the ratio
//! ours/reference of frames per second, paired run by run; absolute times are context, since
//! the machine may be shared. Latency percentiles are taken over the per-frame median of the
//! timed runs, after the first `--latency-from` frames (the map is still filling there).

mod print;
pub mod reference;
pub mod report;

use crate::args::CommonArgs;
use crate::memory::{peak_rss_bytes, reset_peak_rss, rss_bytes};
use crate::reference::ReferenceArgs;
use crate::stats::median;
use anyhow::{bail, Context, Result};
use kiss_odom_core::Capacities;
use kiss_odom_drive::settings::Settings;
use kiss_odom_drive::{Driver, Preloaded, Step};
use kiss_odom_io::pose::{pose_difference, pose_of_row_major};
use kiss_odom_io::Selection;
use kiss_odom_io::{self as io, Frame, Item};
use reference::{RefRun, Reference};
use report::{first_counted, Memory, OurRun, Report, SideStats, Spread};
use std::io::Write;
use std::path::PathBuf;

/// `kiss-odom-dev bench` arguments.
#[derive(Debug, clap::Args)]
#[command(
    mut_arg("config", |a| a.help(crate::reference::CONFIG_HELP_WITH_REFERENCE)),
    mut_arg("threads", |a| a.help(crate::reference::THREADS_HELP_WITH_REFERENCE)),
)]
pub struct BenchArgs {
    /// Dataset: a KITTI `sequences/XX` folder, a folder of .bin/.ply/.pcd frames, a .bag or an
    /// .mcap file (read as `run` reads it).
    pub dataset: PathBuf,
    /// Timed runs per implementation (after one untimed warm-up run each).
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Latency percentiles skip the frames before this one (the map is still filling there).
    #[arg(long, default_value_t = 10)]
    pub latency_from: usize,
    /// Time kiss-odom alone.
    #[arg(long)]
    pub no_reference: bool,
    /// Also write every figure (and the per-frame times) to this JSON file.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Input, pipeline and core options.
    #[command(flatten)]
    pub common: CommonArgs,
    /// Where the reference is.
    #[command(flatten, next_help_heading = "Reference")]
    pub reference: ReferenceArgs,
}

/// Reads the frames of `args.dataset` in range into memory; unreadable frames are left out.
pub fn load(args: &BenchArgs, settings: &Settings, err: &mut dyn Write) -> Result<Vec<Frame>> {
    let mut dataset = io::open(
        &args.dataset,
        args.common.input.format,
        &args
            .common
            .open_options(settings.capacities()?.scan_points, &settings.input),
    )?;
    let mut out = Vec::new();
    for item in Selection::new(dataset.frames.as_mut(), args.common.input.range()) {
        match item? {
            Item::Frame(f) => {
                for w in &f.warnings {
                    writeln!(err, "warning: {w}")?;
                }
                out.push(f);
            }
            Item::Skipped { reason, .. } => writeln!(err, "warning: {reason} (left out)")?,
        }
    }
    if out.is_empty() {
        bail!("{}: no frames in range", args.dataset.display());
    }
    Ok(out)
}

/// Runs `kiss-odom-dev bench`.
pub fn execute(args: &BenchArgs, err: &mut dyn Write) -> Result<i32> {
    if args.repeats == 0 {
        bail!("--repeats must be at least 1");
    }
    if let Some(path) = &args.json {
        kiss_odom_io::write::remove_stale_file(path)?;
    }
    let settings = args.common.settings(Some(1))?;
    if !args.no_reference {
        crate::reference::check_reference_compatible(&settings)?;
    }
    if let Some(w) = settings.threads_warning() {
        writeln!(err, "warning: {w}")?;
    }
    let threads = settings.threads();
    let frames = load(args, &settings, err)?;
    let mut reference = if args.no_reference {
        None
    } else {
        let python = args.reference.python();
        let driver = args.reference.driver()?;
        Some(Reference::start(
            &python, &driver, &frames, &settings, threads,
        )?)
    };
    if let Some(r) = &reference {
        if r.ready.frames != frames.len() {
            bail!(
                "the reference loaded {} frames, we have {}",
                r.ready.frames,
                frames.len()
            );
        }
    }
    let points: usize = frames.iter().map(|f| f.points.len()).sum();
    let preloaded = Driver::new(&settings)?.preload(&frames);
    drop(frames);
    let report = measure(args, &settings, &preloaded, points, reference.as_mut(), err)?;
    drop(reference);
    print::print_report(&report);
    if let Some(path) = &args.json {
        let json = serde_json::to_string_pretty(&report)? + "\n";
        kiss_odom_io::write::write(path, json.as_bytes())?;
    }
    Ok(0)
}

/// One run of a fresh driver over every preloaded frame, timing only the core's calls.
fn run_ours(settings: &Settings, frames: &Preloaded) -> Result<OurRun> {
    let reset = reset_peak_rss();
    let rss_before = rss_bytes();
    let mut driver = Driver::new(settings)?;
    let n = frames.len();
    let mut run = OurRun {
        seconds: Vec::with_capacity(n),
        cpu_seconds: Vec::with_capacity(n),
        rss_before_bytes: rss_before,
        peak_rss_bytes: None,
        poses: Vec::with_capacity(n),
        iterations: Vec::with_capacity(n),
        degraded_frames: 0,
        empty_frames: 0,
        memory: None,
    };
    let mut max_input_points = 0;
    for k in 0..n {
        let o = driver.register_preloaded(frames, k)?;
        run.seconds.push(o.latency.as_secs_f64());
        run.cpu_seconds.push(o.cpu.as_secs_f64());
        run.iterations.push(o.report().map_or(0, |r| r.iterations));
        run.degraded_frames += usize::from(o.status().is_some_and(|s| !s.is_ok()));
        run.empty_frames += usize::from(o.step == Step::Empty);
        max_input_points = max_input_points.max(o.input_points);
        run.poses.push(o.pose);
    }
    run.memory = Some(memory(&driver, max_input_points));
    drop(driver);
    run.peak_rss_bytes = if reset { peak_rss_bytes() } else { None };
    Ok(run)
}

/// Our memory figures after a run: fixed, and what capacities at the high-water marks need.
fn memory(driver: &Driver, max_input_points: usize) -> Memory {
    let caps = driver.memory().capacities;
    let stored = driver.build().map_point_bytes;
    let hw = driver.high_water();
    let hw_caps = Capacities {
        scan_points: max_input_points.clamp(1, caps.scan_points),
        merge_points: hw.merge_points.max(1),
        source_points: hw.source_points.max(1),
        map_voxels: hw.map_voxels.max(1),
        map_points: hw.map_point_slots.max(1),
        plane_terms: caps.plane_terms,
    };
    Memory {
        state_bytes: driver.memory().bytes,
        state_high_water_bytes: hw_caps
            .validate()
            .ok()
            .map(|_| driver.state_bytes_for(&hw_caps)),
        map_bytes: caps.map_bytes(stored),
        map_high_water_bytes: hw_caps.map_bytes(stored),
        high_water: serde_json::json!({
            "merge_points": [hw.merge_points, caps.merge_points],
            "source_points": [hw.source_points, caps.source_points],
            "map_voxels": [hw.map_voxels, caps.map_voxels],
            "map_point_slots": [hw.map_point_slots, caps.map_points],
        }),
        reference_voxels: None,
        reference_points: None,
        reference_map_bytes: None,
        reference_map_bytes_with_table: None,
    }
}

/// The warm-up runs, then the timed runs taking turns, then every figure.
fn measure(
    args: &BenchArgs,
    settings: &Settings,
    frames: &Preloaded,
    points: usize,
    mut reference: Option<&mut Reference>,
    err: &mut dyn Write,
) -> Result<Report> {
    let n = frames.len();
    let threads = settings.threads();

    // Warm-up: untimed, gives poses, high-water marks and the reference's map size.
    writeln!(err, "bench: warm-up runs ({n} frames, {threads} thread(s))")?;
    let warm = run_ours(settings, frames)?;
    let ref_warm = match reference.as_deref_mut() {
        Some(r) => Some(r.run(true, true)?),
        None => None,
    };

    let mut ours_runs: Vec<OurRun> = Vec::new();
    let mut ref_runs: Vec<RefRun> = Vec::new();
    for r in 0..args.repeats {
        writeln!(err, "bench: timed repeat {}/{}", r + 1, args.repeats)?;
        // ABBA order: drift over the session hits both sides alike.
        let ours_first = r % 2 == 0;
        if ours_first {
            ours_runs.push(run_ours(settings, frames)?);
        }
        if let Some(rf) = reference.as_deref_mut() {
            ref_runs.push(rf.run(false, false)?);
        }
        if !ours_first {
            ours_runs.push(run_ours(settings, frames)?);
        }
    }

    let triples_ours: Vec<_> = ours_runs
        .iter()
        .map(|r| (r.seconds.clone(), r.rss_before_bytes, r.peak_rss_bytes))
        .collect();
    let mut ours = SideStats::of(&triples_ours, args.latency_from);
    if threads == 1 {
        let cpu: Vec<&[f64]> = ours_runs.iter().map(|r| r.cpu_seconds.as_slice()).collect();
        ours.cpu = Some(Spread::of(&cpu, args.latency_from));
    }
    let ref_stats = reference.as_ref().map(|_| {
        let t: Vec<_> = ref_runs
            .iter()
            .map(|r| (r.seconds.clone(), r.rss_before_bytes, r.peak_rss_bytes))
            .collect();
        SideStats::of(&t, args.latency_from)
    });
    let speed_ratio_runs: Vec<f64> = match &ref_stats {
        Some(rs) => ours
            .fps_runs
            .iter()
            .zip(&rs.fps_runs)
            .map(|(a, b)| a / b)
            .collect(),
        None => Vec::new(),
    };
    let speed_ratio = (!speed_ratio_runs.is_empty()).then(|| median(&speed_ratio_runs));

    // Poses: ours against the reference's warm-up run, and our runs against each other.
    let ours_repeatable = ours_runs.iter().all(|r| r.poses == warm.poses);
    let (mut pose_diff_m, mut pose_diff_rad) = (None, None);
    if let Some(rp) = ref_warm.as_ref().and_then(|r| r.poses.as_ref()) {
        let (mut dm, mut dr) = (0.0f64, 0.0f64);
        for (a, b) in warm.poses.iter().zip(rp) {
            let b = pose_of_row_major(b).context("the reference sent a malformed pose")?;
            let (t, r) = pose_difference(a, &b);
            dm = dm.max(t);
            dr = dr.max(r);
        }
        pose_diff_m = Some(dm);
        pose_diff_rad = Some(dr);
    }

    let mut memory = warm
        .memory
        .clone()
        .context("the warm-up run has no memory figures")?;
    let ref_voxels = ref_warm.as_ref().and_then(|r| r.map_voxels_peak);
    let n_max = settings.mapping.max_points_per_voxel as usize;
    memory.reference_voxels = ref_voxels;
    memory.reference_points = ref_warm.as_ref().and_then(|r| r.map_points_peak);
    memory.reference_map_bytes = ref_voxels.map(|v| v * n_max * 24);
    memory.reference_map_bytes_with_table = ref_voxels.map(|v| reference_map_estimate(v, n_max));
    let reference_binding_share = ref_warm.as_ref().and_then(|r| {
        let b: f64 = r.binding_seconds.as_ref()?.iter().sum();
        Some(b / r.seconds.iter().sum::<f64>())
    });
    let caps = settings.capacities()?;
    let worst_case_distance_evaluations = caps.source_points as u64
        * 27
        * settings.mapping.max_points_per_voxel as u64
        * settings.registration.max_num_iterations as u64;
    Ok(Report {
        dataset: args.dataset.display().to_string(),
        frames: n,
        points,
        threads,
        scalar: settings.runtime.scalar,
        storage: settings.runtime.map_storage,
        repeats: args.repeats,
        latency_from: first_counted(args.latency_from, n),
        ours,
        reference: ref_stats,
        speed_ratio,
        speed_ratio_runs,
        memory,
        worst_case_distance_evaluations,
        max_iterations_seen: warm.iterations.iter().copied().max().unwrap_or(0),
        pose_diff_m,
        pose_diff_rad,
        ours_repeatable,
        degraded_frames: warm.degraded_frames,
        reference_binding_share,
        reference_versions: reference.as_ref().map(|r| r.ready.versions.clone()),
        per_frame_seconds: serde_json::json!({
            "ours": ours_runs.iter().map(|r| &r.seconds).collect::<Vec<_>>(),
            "reference": ref_runs.iter().map(|r| &r.seconds).collect::<Vec<_>>(),
        }),
    })
}

/// The reference's local-map bytes for `voxels` voxels, counted generously for it: each voxel's
/// `std::vector` reserves `n_max` points of 24 B in one malloc chunk (glibc: request + 8 rounded
/// up to 16), and the `tsl::robin_map` keeps a 48-byte bucket (16-bit probe distance, flag,
/// then the 12-byte key and 24-byte vector aligned to 8) for each of its power-of-two buckets,
/// at least twice the most voxels it held (max load 0.5; it never shrinks).
pub fn reference_map_estimate(voxels: usize, n_max: usize) -> usize {
    let chunk = (n_max * 24 + 8).div_ceil(16) * 16;
    let buckets = (2 * voxels).next_power_of_two();
    voxels * chunk + buckets * 48
}
