//! `kiss-odom bench`: speed, latency and memory of kiss-odom next to the reference kiss-icp
//! 1.3.0 on the same frames.
//!
//! The frames are read into memory first (file reading is never timed) and handed to the
//! reference byte for byte ([`reference`]); then both implementations run over all of them,
//! each run a fresh pipeline, taking turns (ours, ref, ref, ours, ...) so that machine drift
//! hits both alike. Only the per-frame odometry call is timed. The headline is the ratio
//! ours/reference of frames per second, paired run by run; absolute times are context, since
//! the machine may be shared. Latency percentiles are taken over the per-frame median of the
//! timed runs, after the first `--latency-from` frames (the map is still filling there).

pub mod reference;

use crate::exec::Pool;
use crate::io::{self, Format, Item, OpenOptions};
use crate::run::{percentile, widen, FrameRange, Preset};
use crate::settings::{Scalar, Settings, Storage};
use anyhow::{bail, Context, Result};
use kiss_odom_core::{Capacities, Exact, Odometry, PointCodec, Quantized, Real};
use nalgebra::{Isometry3, Matrix4};
use reference::{RefRun, Reference};
use serde::Serialize;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

/// `kiss-odom bench` arguments.
#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Dataset: a KITTI `sequences/XX` folder, a folder of .bin/.ply/.pcd frames, a .bag or an
    /// .mcap file (read as `run` reads it).
    pub dataset: PathBuf,
    /// Input format.
    #[arg(long, value_enum, default_value_t = Format::Auto)]
    pub format: Format,
    /// Frames to load, `A..B` (B excluded), `A..` or `..B`.
    #[arg(long)]
    pub frames: Option<FrameRange>,
    /// Threads for both implementations (the reference's `max_num_threads`); 0 = all cores.
    #[arg(long, default_value_t = 1)]
    pub threads: usize,
    /// Scalar type of our core (the reference is always f64).
    #[arg(long, value_enum, default_value_t = Scalar::F64)]
    pub scalar: Scalar,
    /// Our map point storage.
    #[arg(long, value_enum, default_value_t = Storage::Exact)]
    pub storage: Storage,
    /// Capacity preset of our core (default: the settings', i.e. full scale).
    #[arg(long, value_enum)]
    pub capacities: Option<Preset>,
    /// Settings file as `run` takes it (range, voxel size and deskewing go to both sides).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Timed runs per implementation (after one untimed warm-up run each).
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Latency percentiles skip the frames before this one (the map is still filling there).
    #[arg(long, default_value_t = 10)]
    pub latency_from: usize,
    /// Time kiss-odom alone.
    #[arg(long)]
    pub no_reference: bool,
    /// Python with kiss-icp 1.3.0 (default: `KISS_ODOM_PYTHON`, else `python3`).
    #[arg(long)]
    pub python: Option<PathBuf>,
    /// The reference driver (default: `KISS_ODOM_DRIVER`, else `tests/reference/driver.py`).
    #[arg(long)]
    pub driver: Option<PathBuf>,
    /// Also write every figure (and the per-frame times) to this JSON file.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// One frame held in memory.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// File or message name.
    pub name: String,
    /// Points as read (KITTI scans already corrected).
    pub points: Vec<[f64; 3]>,
    /// Per-point times, if the format has them.
    pub stamps: Option<Vec<f64>>,
}

/// One timed run of ours.
#[derive(Clone, Debug, Serialize)]
pub struct OurRun {
    /// Seconds in `register_frame_with`, per frame.
    pub seconds: Vec<f64>,
    /// RSS when the run started (frames loaded).
    pub rss_before_bytes: Option<u64>,
    /// Peak RSS during the run.
    pub peak_rss_bytes: Option<u64>,
    /// Poses, row-major 4x4, widened to f64.
    #[serde(skip)]
    pub poses: Vec<Isometry3<f64>>,
    /// ICP iterations per frame.
    #[serde(skip)]
    pub iterations: Vec<u32>,
    /// Frames whose status was not ok.
    pub degraded_frames: usize,
    /// Empty frames (no usable point).
    pub empty_frames: usize,
    /// Fixed state bytes.
    #[serde(skip)]
    pub state_bytes: usize,
    /// High-water marks.
    #[serde(skip)]
    pub high_water: kiss_odom_core::HighWater,
    /// Most input points of a frame.
    #[serde(skip)]
    pub max_input_points: usize,
}

/// Frame rate and latency of one implementation over the timed runs.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SideStats {
    /// Frames per second of odometry time, per timed run.
    pub fps_runs: Vec<f64>,
    /// Their median.
    pub fps: f64,
    /// Per-frame latency percentiles (ms) of the per-frame median over runs.
    pub p50_ms: f64,
    /// 99th percentile.
    pub p99_ms: f64,
    /// Worst frame.
    pub max_ms: f64,
    /// Worst single frame time over every timed run (ms), noise included.
    pub max_any_run_ms: f64,
    /// Largest peak RSS of a timed run.
    pub peak_rss_bytes: Option<u64>,
    /// Largest growth of RSS during a timed run (peak minus RSS at its start).
    pub rss_growth_bytes: Option<u64>,
}

impl SideStats {
    fn of(runs: &[(Vec<f64>, Option<u64>, Option<u64>)], latency_from: usize) -> Self {
        let mut s = SideStats::default();
        if runs.is_empty() {
            return s;
        }
        s.fps_runs = runs
            .iter()
            .map(|(sec, _, _)| sec.len() as f64 / sec.iter().sum::<f64>().max(1e-12))
            .collect();
        s.fps = median(&s.fps_runs);
        let n = runs[0].0.len();
        let mut per_frame: Vec<f64> = (latency_from.min(n.saturating_sub(1))..n)
            .map(|i| median(&runs.iter().map(|r| r.0[i]).collect::<Vec<_>>()) * 1e3)
            .collect();
        per_frame.sort_by(f64::total_cmp);
        s.p50_ms = percentile(&per_frame, 50.0);
        s.p99_ms = percentile(&per_frame, 99.0);
        s.max_ms = per_frame.last().copied().unwrap_or(0.0);
        s.max_any_run_ms = runs
            .iter()
            .flat_map(|r| r.0.iter().skip(latency_from))
            .fold(0.0f64, |a, &b| a.max(b * 1e3));
        s.peak_rss_bytes = runs.iter().filter_map(|r| r.2).max();
        s.rss_growth_bytes = runs
            .iter()
            .filter_map(|r| Some(r.2?.saturating_sub(r.1?)))
            .max();
        s
    }
}

/// Memory figures of ours and the reference's local map.
#[derive(Clone, Debug, Serialize)]
pub struct Memory {
    /// Bytes of our whole core state, fixed at start.
    pub state_bytes: usize,
    /// Bytes the state would need with capacities equal to the high-water marks.
    pub state_high_water_bytes: Option<usize>,
    /// Bytes of our local map (voxel table and point pool), fixed at start.
    pub map_bytes: usize,
    /// Bytes of a map sized to the high-water marks.
    pub map_high_water_bytes: usize,
    /// High-water marks against capacities: merge, source, voxels, point slots.
    pub high_water: serde_json::Value,
    /// The reference's most voxels (after any frame).
    pub reference_voxels: Option<usize>,
    /// The reference's most points.
    pub reference_points: Option<usize>,
    /// Its point buffers: `max_points_per_voxel` x 24 B reserved per voxel.
    pub reference_map_bytes: Option<usize>,
    /// Plus malloc chunk headers and the robin-map bucket array (estimate, see BENCHMARKS.md).
    pub reference_map_bytes_with_table: Option<usize>,
}

/// Everything `bench` measured.
#[derive(Debug, Serialize)]
pub struct Report {
    /// Dataset path.
    pub dataset: String,
    /// Frames timed.
    pub frames: usize,
    /// Points in them.
    pub points: usize,
    /// Threads on both sides.
    pub threads: usize,
    /// f64 or f32.
    pub scalar: Scalar,
    /// Map point storage.
    pub storage: Storage,
    /// Timed runs per side.
    pub repeats: usize,
    /// First frame in the latency statistics.
    pub latency_from: usize,
    /// Ours.
    pub ours: SideStats,
    /// The reference.
    pub reference: Option<SideStats>,
    /// Median of the per-repeat ratios ours/reference of frames per second.
    pub speed_ratio: Option<f64>,
    /// The per-repeat ratios.
    pub speed_ratio_runs: Vec<f64>,
    /// Memory.
    pub memory: Memory,
    /// Worst-case nearest-neighbour distance evaluations per frame from the capacities.
    pub worst_case_distance_evaluations: u64,
    /// Most ICP iterations of a frame.
    pub max_iterations_seen: u32,
    /// Largest translation difference of our poses from the reference's (m).
    pub pose_diff_m: Option<f64>,
    /// Largest rotation difference (rad).
    pub pose_diff_rad: Option<f64>,
    /// Whether every run of ours gave the same poses bit for bit.
    pub ours_repeatable: bool,
    /// Frames with a non-ok status in our warm-up run.
    pub degraded_frames: usize,
    /// Share of the reference's frame time spent converting the input frame to a C++ vector.
    pub reference_binding_share: Option<f64>,
    /// Versions of the reference.
    pub reference_versions: Option<serde_json::Value>,
    /// Per-frame seconds of each timed run, ours then the reference's.
    pub per_frame_seconds: serde_json::Value,
}

fn median(v: &[f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        (s[n / 2 - 1] + s[n / 2]) / 2.0
    }
}

fn proc_status_bytes(field: &str) -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with(field))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Resets the kernel's peak-RSS counter to the current RSS (Linux); false if it cannot.
pub fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// Current resident set size (Linux).
pub fn rss_bytes() -> Option<u64> {
    proc_status_bytes("VmRSS:")
}

/// Reads the frames of `args.dataset` in range into memory.
pub fn load(args: &BenchArgs, err: &mut dyn Write) -> Result<Vec<Loaded>> {
    let mut dataset = io::open(&args.dataset, args.format, &OpenOptions::default())?;
    let range = args.frames.unwrap_or(FrameRange {
        start: 0,
        end: None,
    });
    if range.start > 0 {
        dataset.frames.seek(range.start);
    }
    let mut out = Vec::new();
    while let Some(item) = dataset.frames.next_item()? {
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
        match item {
            Item::Frame(f) => {
                for w in &f.warnings {
                    writeln!(err, "warning: {w}")?;
                }
                out.push(Loaded {
                    name: f.name,
                    points: f.points,
                    stamps: f.stamps,
                });
            }
            Item::Skipped { reason, .. } => writeln!(err, "warning: {reason} (left out)")?,
        }
    }
    if out.is_empty() {
        bail!("{}: no frames in range", args.dataset.display());
    }
    Ok(out)
}

fn settings_for(args: &BenchArgs) -> Result<Settings> {
    let mut s = match &args.config {
        Some(p) => Settings::load(p)?,
        None => Settings::default(),
    };
    s.runtime.scalar = args.scalar;
    s.runtime.map_storage = args.storage;
    s.runtime.threads = args.threads;
    if let Some(p) = args.capacities {
        s.capacities = match p {
            Preset::Full => Capacities::FULL_SCALE,
            Preset::Small => Capacities::SMALL,
            Preset::Tiny => Capacities::TINY,
        }
        .into();
    }
    Ok(s)
}

/// Runs `kiss-odom bench`.
pub fn execute(args: &BenchArgs, err: &mut dyn Write) -> Result<i32> {
    if args.repeats == 0 {
        bail!("--repeats must be at least 1");
    }
    let settings = settings_for(args)?;
    settings.core_config::<f64>()?;
    settings.capacities()?;
    let threads = settings.threads();
    let frames = load(args, err)?;
    let mut reference = if args.no_reference {
        None
    } else {
        let python = reference::python(args.python.as_deref());
        let driver = reference::driver(args.driver.as_deref());
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
    let report = match (args.scalar, args.storage) {
        (Scalar::F64, Storage::Exact) => {
            drive::<f64, Exact>(args, &settings, threads, frames, reference.as_mut(), err)?
        }
        (Scalar::F64, Storage::Quantized) => {
            drive::<f64, Quantized>(args, &settings, threads, frames, reference.as_mut(), err)?
        }
        (Scalar::F32, Storage::Exact) => {
            drive::<f32, Exact>(args, &settings, threads, frames, reference.as_mut(), err)?
        }
        (Scalar::F32, Storage::Quantized) => {
            drive::<f32, Quantized>(args, &settings, threads, frames, reference.as_mut(), err)?
        }
    };
    drop(reference);
    print_report(&report);
    if let Some(path) = &args.json {
        let json = serde_json::to_string_pretty(&report)?;
        std::fs::write(path, json + "\n").with_context(|| format!("{}", path.display()))?;
    }
    Ok(0)
}

/// Frames converted to the core's scalar once, before any timing.
struct Prepared<T> {
    points: Vec<Vec<[T; 3]>>,
    stamps: Vec<Option<Vec<f64>>>,
}

fn run_ours<T: Real, P: PointCodec<T>>(
    settings: &Settings,
    pool: &Pool,
    frames: &Prepared<T>,
) -> Result<OurRun> {
    let config = settings.core_config::<T>()?;
    let caps = settings.capacities()?;
    let reset = reset_peak_rss();
    let rss_before = rss_bytes();
    let mut arena = vec![0u64; caps.arena_words::<T, P>()];
    let mut odom = Odometry::<T, P, _>::new(config, caps, &mut arena[..])
        .map_err(|e| anyhow::anyhow!("cannot build the odometry: {e}"))?;
    let n = frames.points.len();
    let mut run = OurRun {
        seconds: Vec::with_capacity(n),
        rss_before_bytes: rss_before,
        peak_rss_bytes: None,
        poses: Vec::with_capacity(n),
        iterations: Vec::with_capacity(n),
        degraded_frames: 0,
        empty_frames: 0,
        state_bytes: odom.state_bytes(),
        high_water: Default::default(),
        max_input_points: 0,
    };
    for (pts, stamps) in frames.points.iter().zip(&frames.stamps) {
        let t0 = Instant::now();
        let result = odom.register_frame_with(pool, pts, stamps.as_deref());
        run.seconds.push(t0.elapsed().as_secs_f64());
        match result {
            Ok(r) => {
                run.iterations.push(r.iterations);
                if !r.status.is_ok() {
                    run.degraded_frames += 1;
                }
            }
            Err(_) => {
                // As `run` does: the pose follows the constant-velocity model.
                run.empty_frames += 1;
                run.iterations.push(0);
                odom.skip_frame();
            }
        }
        run.max_input_points = run.max_input_points.max(pts.len());
        run.poses.push(widen(odom.pose()));
    }
    run.high_water = odom.high_water();
    drop(arena);
    run.peak_rss_bytes = if reset {
        proc_status_bytes("VmHWM:")
    } else {
        None
    };
    Ok(run)
}

fn ref_pose(m: &[f64]) -> Option<Isometry3<f64>> {
    if m.len() != 16 {
        return None;
    }
    let m = Matrix4::from_row_slice(m);
    let rot = nalgebra::Rotation3::from_matrix_unchecked(m.fixed_view::<3, 3>(0, 0).into_owned());
    let t = nalgebra::Translation3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]);
    Some(Isometry3::from_parts(
        t,
        nalgebra::UnitQuaternion::from_rotation_matrix(&rot),
    ))
}

fn drive<T: Real, P: PointCodec<T>>(
    args: &BenchArgs,
    settings: &Settings,
    threads: usize,
    frames: Vec<Loaded>,
    mut reference: Option<&mut Reference>,
    err: &mut dyn Write,
) -> Result<Report> {
    let points: usize = frames.iter().map(|f| f.points.len()).sum();
    let n = frames.len();
    let prepared = {
        let mut p = Prepared {
            points: Vec::with_capacity(n),
            stamps: Vec::with_capacity(n),
        };
        for f in frames {
            p.points.push(
                f.points
                    .iter()
                    .map(|q| [T::of(q[0]), T::of(q[1]), T::of(q[2])])
                    .collect(),
            );
            p.stamps.push(f.stamps);
        }
        p
    };
    let pool = Pool::new(threads)?;

    // Warm-up: untimed, gives poses, high-water marks and the reference's map size.
    writeln!(err, "bench: warm-up runs ({n} frames, {threads} thread(s))")?;
    let warm = run_ours::<T, P>(settings, &pool, &prepared)?;
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
            ours_runs.push(run_ours::<T, P>(settings, &pool, &prepared)?);
        }
        if let Some(rf) = reference.as_deref_mut() {
            ref_runs.push(rf.run(false, false)?);
        }
        if !ours_first {
            ours_runs.push(run_ours::<T, P>(settings, &pool, &prepared)?);
        }
    }

    let triples_ours: Vec<_> = ours_runs
        .iter()
        .map(|r| (r.seconds.clone(), r.rss_before_bytes, r.peak_rss_bytes))
        .collect();
    let ours = SideStats::of(&triples_ours, args.latency_from);
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
            let b = ref_pose(b).context("the reference sent a malformed pose")?;
            dm = dm.max((a.translation.vector - b.translation.vector).amax());
            dr = dr.max(a.rotation.angle_to(&b.rotation));
        }
        pose_diff_m = Some(dm);
        pose_diff_rad = Some(dr);
    }

    // Memory.
    let caps = settings.capacities()?;
    let stored = core::mem::size_of::<P::Stored>();
    let hw = warm.high_water;
    let hw_caps = Capacities {
        scan_points: warm.max_input_points.clamp(1, caps.scan_points),
        merge_points: hw.merge_points.max(1),
        source_points: hw.source_points.max(1),
        map_voxels: hw.map_voxels.max(1),
        map_points: hw.map_point_slots.max(1),
    };
    let state_high_water_bytes = hw_caps
        .validate()
        .ok()
        .map(|_| hw_caps.arena_words::<T, P>() * 8 + core::mem::size_of::<Odometry<T, P>>());
    let ref_voxels = ref_warm.as_ref().and_then(|r| r.map_voxels_peak);
    let n_max = settings.mapping.max_points_per_voxel as usize;
    let memory = Memory {
        state_bytes: warm.state_bytes,
        state_high_water_bytes,
        map_bytes: caps.map_bytes(stored),
        map_high_water_bytes: hw_caps.map_bytes(stored),
        high_water: serde_json::json!({
            "merge_points": [hw.merge_points, caps.merge_points],
            "source_points": [hw.source_points, caps.source_points],
            "map_voxels": [hw.map_voxels, caps.map_voxels],
            "map_point_slots": [hw.map_point_slots, caps.map_points],
        }),
        reference_voxels: ref_voxels,
        reference_points: ref_warm.as_ref().and_then(|r| r.map_points_peak),
        reference_map_bytes: ref_voxels.map(|v| v * n_max * 24),
        reference_map_bytes_with_table: ref_voxels.map(|v| reference_map_estimate(v, n_max)),
    };
    let reference_binding_share = ref_warm.as_ref().and_then(|r| {
        let b: f64 = r.binding_seconds.as_ref()?.iter().sum();
        Some(b / r.seconds.iter().sum::<f64>())
    });
    let worst_case_distance_evaluations = caps.source_points as u64
        * 27
        * settings.mapping.max_points_per_voxel as u64
        * settings.registration.max_num_iterations as u64;
    Ok(Report {
        dataset: args.dataset.display().to_string(),
        frames: n,
        points,
        threads,
        scalar: args.scalar,
        storage: args.storage,
        repeats: args.repeats,
        latency_from: args.latency_from,
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

fn mib(b: u64) -> f64 {
    b as f64 / (1u64 << 20) as f64
}

fn print_report(r: &Report) {
    println!(
        "bench: {} ({} frames, {} points), {} thread(s), {:?} {:?}, {} timed runs each after \
         a warm-up, alternating",
        r.dataset, r.frames, r.points, r.threads, r.scalar, r.storage, r.repeats
    );
    println!(
        "latency: per-frame median over the runs, frames {}.. ; max(any run) includes machine \
         noise",
        r.latency_from
    );
    println!(
        "{:<16} {:>9} {:>8} {:>8} {:>8} {:>8} {:>8} {:>13} {:>10} {:>10}",
        "",
        "frames/s",
        "p50 ms",
        "p99 ms",
        "max ms",
        "p99/p50",
        "max/p50",
        "max(any) ms",
        "peak RSS",
        "RSS grow"
    );
    let row = |name: &str, s: &SideStats| {
        println!(
            "{:<16} {:>9.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>13.2} {:>6.1} MiB {:>6.1} MiB",
            name,
            s.fps,
            s.p50_ms,
            s.p99_ms,
            s.max_ms,
            s.p99_ms / s.p50_ms,
            s.max_ms / s.p50_ms,
            s.max_any_run_ms,
            s.peak_rss_bytes.map_or(f64::NAN, mib),
            s.rss_growth_bytes.map_or(f64::NAN, mib),
        )
    };
    row("kiss-odom", &r.ours);
    if let Some(rs) = &r.reference {
        row("kiss-icp 1.3.0", rs);
    }
    if let Some(ratio) = r.speed_ratio {
        let runs: Vec<String> = r
            .speed_ratio_runs
            .iter()
            .map(|x| format!("{x:.2}"))
            .collect();
        println!(
            "speed ours/reference: {ratio:.2}x frames/s (median of paired runs: {})",
            runs.join(" ")
        );
    }
    let m = &r.memory;
    println!(
        "kiss-odom state: {:.2} MiB fixed at start ({:.2} MiB at the high-water marks); \
         local map {:.2} MiB fixed ({:.2} MiB at the high-water marks)",
        mib(m.state_bytes as u64),
        m.state_high_water_bytes.map_or(f64::NAN, |b| mib(b as u64)),
        mib(m.map_bytes as u64),
        mib(m.map_high_water_bytes as u64),
    );
    println!("high-water / capacity: {}", m.high_water);
    if let (Some(v), Some(b), Some(bt)) = (
        m.reference_voxels,
        m.reference_map_bytes,
        m.reference_map_bytes_with_table,
    ) {
        println!(
            "reference local map: at most {v} voxels ({} points): {:.2} MiB of point buffers, \
             {:.2} MiB with chunk headers and buckets; ours (fixed) / reference: {:.2} \
             ({:.2} with table)",
            m.reference_points.unwrap_or(0),
            mib(b as u64),
            mib(bt as u64),
            m.map_bytes as f64 / b as f64,
            m.map_bytes as f64 / bt as f64,
        );
    }
    if let Some(s) = r.reference_binding_share {
        println!(
            "reference: numpy -> C++ conversion of the input scan is {:.1}% of its frame time",
            s * 100.0
        );
    }
    println!(
        "worst case per frame from the capacities: {} distance evaluations (source x 27 x \
         N_max x iteration cap); most iterations seen: {}",
        r.worst_case_distance_evaluations, r.max_iterations_seen
    );
    match (r.pose_diff_m, r.pose_diff_rad) {
        (Some(dm), Some(dr)) => println!(
            "poses vs reference: max {dm:.3e} m, {dr:.3e} rad; our runs bit-identical: {}; \
             degraded frames: {}",
            r.ours_repeatable, r.degraded_frames
        ),
        _ => println!(
            "our runs bit-identical: {}; degraded frames: {}",
            r.ours_repeatable, r.degraded_frames
        ),
    }
}
