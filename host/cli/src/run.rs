//! `kiss-odom run`: odometry over a recording, with poses, per-frame records, a summary,
//! metrics against ground truth and a plot written to the output folder.
//!
//! The frames go through the [`Driver`]; this module decides what stops a run and what is written
//! (`record`, `files`), and hands every outcome to its [`observe::Observer`]s: those of `viz`
//! (`--rerun`, `--save-map`, `--save-cloud`) and whatever the caller adds (`live` prints each pose
//! as it comes). The rules (the book's failure reference): a frame-level problem is a warning and a
//! counted skip (an error under `output.strict`); a damaged container, a `output.strict` stop or a run in
//! which no frame could be registered ends with exit 1 and its own reason, never an output error in
//! its place; SIGINT/SIGTERM stop after the current frame with `128 + signal`. In every case the
//! outputs hold the frames processed so far (pose files and the plot only when a frame was
//! registered), written atomically, and no output of an earlier run stays beside them; a file in
//! the output folder that no earlier command wrote (a hand-written `config.toml`, the data set's
//! own) refuses the run before anything is removed.

mod files;
pub mod observe;
mod options;
pub(crate) mod record;
pub(crate) mod viz;

pub use files::OUTPUTS;
use kiss_odom_drive::settings::Output;
pub(crate) use kiss_odom_drive::settings::PoseTime;
pub(crate) use options::{RunArgs, RunOptions};
pub(crate) use record::{FrameRow, Record, RowKind};

use anyhow::{anyhow, Context, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use kiss_odom_core::Flag;
use kiss_odom_drive::localize::MapLocalizer;
use kiss_odom_drive::{CapacityWarnings, Driver, Outcome, PriorWarnings, Step};
use kiss_odom_io::write::outputs::Earlier;
use kiss_odom_io::{self as io, Item, Selection, SweepInfo};
use nalgebra::Isometry3;
use observe::{Observer, Seen};
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

/// Why the frame loop ended.
enum End {
    /// Every frame in range was read.
    Finished,
    /// An error: a damaged container, a `output.strict` stop.
    Failed(anyhow::Error),
    /// SIGINT or SIGTERM.
    Interrupted(i32),
}

/// Runs `kiss-odom run`.
pub fn execute(args: &RunArgs, err: &mut dyn Write) -> Result<i32> {
    let open = |opts: &io::OpenOptions| io::open(&args.path, args.common.input.format, opts);
    execute_on(args, open, Vec::new(), err)
}

/// Runs `run` on the dataset `open` gives (the options ask for the settings' scan
/// capacity), with `watchers` beside the observers the view options ask for: `kiss-odom run`,
/// and `live` with a socket for a dataset and a watcher that prints its poses.
///
/// Every argument is checked and every input read before any file is removed: a run refused
/// for its arguments, or for a file in the output folder that is not an earlier command's
/// output, changes nothing, and a `--config` inside the output folder is read before the
/// folder's old outputs go. An input that cannot be opened refuses the run after
/// those are removed, writing nothing; once it is open, `summary.json` is written however the
/// run ends.
pub(crate) fn execute_on(
    args: &RunArgs,
    open: impl FnOnce(&io::OpenOptions) -> Result<io::Dataset>,
    watchers: Vec<Box<dyn Observer>>,
    err: &mut dyn Write,
) -> Result<i32> {
    let settings = args.common.settings(None)?;
    let output = &settings.output;
    let inputs = inputs(args);
    viz::check(&args.view, output, &inputs)?;
    // The sensor's file is read while the input opens; `--config` is read by now, and
    // `config.toml` is the settings it gave, written back.
    for name in OUTPUTS {
        kiss_odom_io::write::refuse_input(&args.run.out.join(name), &inputs[1..2])?;
    }
    // Only the files an earlier command wrote there are replaced; any other refuses the run.
    let earlier = Earlier::check(&args.run.out, &OUTPUTS)?;
    let mut driver = Driver::new(&settings)?;
    let mut localizer = localizer(&args.run, &settings, &driver)?;
    let opened = open(
        &args
            .common
            .open_options(settings.capacities()?.scan_points, &settings.input),
    );
    // Whatever happens next, no output of an earlier run stays to be taken for this one's.
    earlier.remove()?;
    for path in args.view.files() {
        kiss_odom_io::write::remove_stale_file(path)?;
    }
    // An input that cannot be opened refuses the run before it starts: nothing is written.
    let mut dataset = opened?;
    std::fs::create_dir_all(&args.run.out)
        .with_context(|| format!("{}: cannot create output folder", args.run.out.display()))?;
    let mut record = Record::default();
    // After the folder: a recording or cloud may be asked for inside it.
    let mut observers = match viz::observers(&args.view, output) {
        Ok(o) => watchers.into_iter().chain(o).collect::<Vec<_>>(),
        Err(e) => {
            let end = End::Failed(e);
            return finish(args, &settings, &dataset.info, &driver, &record, end, err);
        }
    };
    let mut warn = |record: &mut Record, bar: &ProgressBar, text: &str| {
        bar.suspend(|| writeln!(err, "warning: {text}")).ok();
        record.warnings += 1;
    };
    let hidden = ProgressBar::hidden();
    if let Some(w) = settings.threads_warning() {
        warn(&mut record, &hidden, &w);
    }
    let mut end = End::Finished;
    for w in settings
        .unused_warnings()
        .iter()
        .chain(&dataset.info.warnings)
    {
        warn(&mut record, &hidden, w);
        if output.strict {
            end = End::Failed(anyhow!("{w} (output.strict)"));
            break;
        }
    }
    if matches!(end, End::Finished) {
        let mut capacity =
            CapacityWarnings::new(driver.build().capacities, settings.data.max_range);
        end = frame_loop(
            args,
            output,
            &mut driver,
            &mut capacity,
            &mut dataset,
            &mut record,
            &mut observers,
            localizer.as_mut(),
            &mut warn,
        );
    }
    record.localizer_bytes = localizer.as_ref().map(MapLocalizer::state_bytes);
    record.localizer_board_bytes = localizer
        .as_ref()
        .map(|_| MapLocalizer::board_bytes(driver.build().capacities.source_points));
    // What the source found after its last frame (a sensor recording's packets refused after
    // the last sweep) is warned about and counted like a frame's findings.
    let trailer = dataset.frames.trailer();
    for w in &trailer.warnings {
        warn(&mut record, &hidden, w);
    }
    if let (Some(p), Some(row)) = (
        trailer.packets,
        record.rows.iter_mut().rev().find(|r| r.packets.is_some()),
    ) {
        row.add_packets(&p);
    }
    if let (true, End::Finished, Some(w)) = (output.strict, &end, trailer.warnings.first()) {
        end = End::Failed(anyhow!("{w} (output.strict)"));
    }
    // The observers' files hold the frames processed, however the loop ended.
    for observer in &mut observers {
        match observer.finish(&driver) {
            Ok(warnings) => warnings.iter().for_each(|w| warn(&mut record, &hidden, w)),
            Err(e) if matches!(end, End::Finished) => end = End::Failed(e),
            Err(e) => warn(&mut record, &hidden, &kiss_odom_drive::one_line(&e)),
        }
    }
    let end = match end {
        End::Finished if record.rows.is_empty() => {
            End::Failed(anyhow!("{}: no frames in range", args.path.display()))
        }
        End::Finished if record.registered() == 0 => End::Failed(anyhow!(
            "{}: {}",
            args.path.display(),
            nothing_registered(&record)
        )),
        other => other,
    };
    let code = finish(args, &settings, &dataset.info, &driver, &record, end, err);
    drop(dataset); // readers' temporary files go now, before the process exits
    code
}

/// The localizer `--map` asks for, opened before anything is written: a map that cannot be
/// used refuses the run.
fn localizer(
    run: &RunOptions,
    settings: &kiss_odom_drive::settings::Settings,
    driver: &Driver,
) -> Result<Option<MapLocalizer>> {
    let Some(path) = &run.map else {
        return Ok(None);
    };
    let Some(pose) = &run.initial_pose else {
        anyhow::bail!(
            "--map needs --initial-pose X,Y,Z,ROLL,PITCH,YAW: the start is not searched for \
             over the whole map"
        );
    };
    let initial = io::poses::parse_xyz_rpy(pose).context("--initial-pose")?;
    MapLocalizer::for_driver(path, settings, driver, initial).map(Some)
}

/// The files this run reads, which no output of it may replace: the dataset, `--calibration`,
/// `--config` (the ones not given are empty paths, which name nothing).
fn inputs(args: &RunArgs) -> [&Path; 3] {
    let sensor = &args.common.input.sensor;
    let none = Path::new("");
    [
        Some(&args.path),
        sensor.calibration.as_ref(),
        args.common.pipeline.config.as_ref(),
    ]
    .map(|p| p.map_or(none, PathBuf::as_path))
}

/// An error from the frames: an interruption if a signal ended the input (a `live` socket
/// closed by Ctrl-C before any packet came), else a failure.
fn stopped_by(e: anyhow::Error) -> End {
    match crate::interrupt::requested() {
        Some(sig) => End::Interrupted(sig),
        None => End::Failed(e),
    }
}

/// Writes the outputs of a run that ended with `end` and gives its exit status: the stop
/// reason is the error, a failed write after it only a warning.
fn finish(
    args: &RunArgs,
    settings: &kiss_odom_drive::settings::Settings,
    info: &io::DatasetInfo,
    driver: &Driver,
    record: &Record,
    end: End,
    err: &mut dyn Write,
) -> Result<i32> {
    let (interrupted, stop) = match &end {
        End::Finished => (None, None),
        End::Failed(e) => (None, Some(kiss_odom_drive::one_line(e))),
        End::Interrupted(sig) => (Some(*sig), None),
    };
    let run = files::Run {
        args,
        settings,
        info,
        driver,
        record,
        interrupted,
        stop,
    };
    let written = run.write();
    let summary = match (written, end) {
        (Ok(summary), End::Finished) => summary,
        (Err(e), End::Finished) => return Err(e),
        (written, End::Failed(e)) => {
            if let Err(w) = written {
                writeln!(
                    err,
                    "warning: outputs incomplete: {}",
                    kiss_odom_drive::one_line(&w)
                )?;
            }
            return Err(e);
        }
        (written, End::Interrupted(sig)) => {
            let summary = written?;
            writeln!(
                err,
                "interrupted by signal {sig} after {} frames: the outputs hold those frames",
                summary.frames
            )?;
            return Ok(crate::interrupt::exit_status(sig));
        }
    };
    if !args.run.quiet {
        files::print_summary(&summary);
    }
    Ok(0)
}

fn nothing_registered(r: &Record) -> String {
    let count = |k: RowKind| r.rows.iter().filter(|row| row.outcome == k).count();
    format!(
        "no frame could be registered ({} of {} unreadable, {} without a usable point)",
        count(RowKind::Skipped),
        r.rows.len(),
        count(RowKind::Empty)
    )
}

/// Feeds the frames in range to the driver, recording each outcome and showing it to the
/// observers, until the end, an error, a `output.strict` stop or a signal.
#[allow(clippy::too_many_arguments)]
fn frame_loop(
    args: &RunArgs,
    output: &Output,
    driver: &mut Driver,
    capacity: &mut CapacityWarnings,
    dataset: &mut io::Dataset,
    record: &mut Record,
    observers: &mut [Box<dyn Observer>],
    mut localizer: Option<&mut MapLocalizer>,
    warn: &mut dyn FnMut(&mut Record, &ProgressBar, &str),
) -> End {
    let info = &dataset.info;
    // Ground truth in the estimate's frame: estimate times ground truth at the first frame
    // that has both (as the metrics re-base them).
    let mut gt_base: Option<Isometry3<f64>> = None;
    let mut frames = Selection::new(dataset.frames.as_mut(), args.common.input.range());
    let bar = progress_bar(frames.len_hint(), args.run.quiet);
    let mut core_s = 0.0;
    let mut prior = PriorWarnings::default();
    let end = loop {
        if let Some(sig) = crate::interrupt::requested() {
            break End::Interrupted(sig);
        }
        let item = match frames.next() {
            // A live source ends when a signal arrives while it waits for packets.
            None => match crate::interrupt::requested() {
                Some(sig) => break End::Interrupted(sig),
                None => break End::Finished,
            },
            Some(Err(e)) => break stopped_by(e),
            Some(Ok(item)) => item,
        };
        let problems: Vec<String> = match &item {
            Item::Skipped { reason, .. } => vec![reason.clone()],
            Item::Frame(f) => f.warnings.clone(),
        };
        for p in &problems {
            warn(record, &bar, p);
        }
        if let (true, Some(first)) = (output.strict, problems.first()) {
            break End::Failed(anyhow!("{first} (output.strict)"));
        }
        let (outcome, frame) = match item {
            Item::Frame(frame) => (driver.register(&frame), Some(frame)),
            skipped => (driver.feed(skipped), None),
        };
        let outcome = match outcome {
            Ok(o) => o,
            Err(e) => break End::Failed(e),
        };
        if let Some(report) = outcome.report() {
            if output.strict && report.status.contains(Flag::TimestampsIgnored) {
                break End::Failed(anyhow!(
                    "{}: timestamps unusable ({:?}), frame not deskewed (output.strict)",
                    outcome.meta.source,
                    report.stamp_problem
                ));
            }
            core_s += outcome.latency.as_secs_f64();
        }
        // The first scan of one plane, held to the prediction (robust mode), warns once.
        if let Some(w) = driver.one_plane_warning(&outcome) {
            warn(record, &bar, &w);
        }
        // Growth stopped by the memory limit warns once, before what the fixed rule then does.
        if let Some(w) = driver.growth_warning() {
            warn(record, &bar, &w);
        }
        // A capacity rule that can change a pose warns on its first frame.
        let full = capacity.check(&outcome, &driver.memory().capacities);
        for w in &full {
            warn(record, &bar, w);
        }
        if let (true, Some(first)) = (output.strict, full.first()) {
            break End::Failed(anyhow!("{first} (output.strict)"));
        }
        // So does a frame the gyroscope prior, asked for, could not predict.
        // And the first time the IMU consistency check rejects the gyroscope.
        if let Some(w) = driver.imu_check_warning(false) {
            warn(record, &bar, &w);
            if output.strict {
                break End::Failed(anyhow!("{w} (output.strict)"));
            }
        }
        if let Some(w) = prior.check(&outcome) {
            warn(record, &bar, &w);
            if output.strict {
                break End::Failed(anyhow!("{w} (output.strict)"));
            }
        }
        if outcome.step == Step::Empty {
            warn(
                record,
                &bar,
                &format!("{}: no usable point", outcome.meta.source),
            );
        }
        // With a prior map, the pose is the map frame's.
        let mut outcome = outcome;
        let located = localizer.as_mut().map(|l| l.locate(driver, &outcome));
        if let Some(l) = &located {
            outcome.pose = l.pose;
            let held = &mut record.prior_held;
            *held = (held.0.max(l.held_tiles), held.1.max(l.held_points));
        }
        if let Some(w) = localizer.as_mut().and_then(|l| l.damaged_warning()) {
            warn(record, &bar, &w);
        }
        let sweep = frame.as_ref().and_then(|f| f.sweep);
        add(record, info, &outcome, sweep.as_ref(), output.pose_time);
        if let (Some(l), Some(row)) = (&located, record.rows.last_mut()) {
            row.localization = Some(l.state.name());
            row.map_inlier_share = Some(l.inlier_share);
            row.map_observability = l.observability;
            row.map_correction_m = Some(l.correction);
        }
        if !observers.is_empty() {
            let ground_truth = info
                .ground_truth
                .as_ref()
                .and_then(|g| g.get(outcome.meta.index))
                .map(|g| *gt_base.get_or_insert(outcome.pose * g.inverse()) * g);
            let seen = Seen {
                driver,
                outcome: &outcome,
                points: frame.as_ref().map(|f| f.points.as_slice()),
                pose: *record.poses.last().unwrap_or(&outcome.pose),
                time: record.times.last().copied().flatten(),
                sweep: sweep.as_ref(),
                ground_truth,
            };
            let Some(row) = record.rows.last_mut() else {
                break End::Failed(anyhow!("{}: no row recorded", outcome.meta.source));
            };
            if let Some(e) = observers.iter_mut().find_map(|o| o.frame(&seen, row).err()) {
                break End::Failed(e);
            }
        }
        bar.inc(1);
        if core_s > 0.0 {
            let hz = record.registered() as f64 / core_s;
            bar.set_message(format!("{hz:.1} Hz"));
        }
    };
    // A rejection in the run's last frames names its cause from the frames it had.
    if let Some(w) = driver.imu_check_warning(true) {
        warn(record, &bar, &w);
    }
    bar.finish_and_clear();
    end
}

/// Records an outcome. A sweep decoded from packets gets its packet columns and the
/// sensor-clock instant `pose_time` chooses; a deskewed frame's pose is moved to that instant
/// along the motion its points were deskewed with (not the motion registration then found:
/// on the first deskewed frame the two differ by half a sweep, see [`PoseTime::pose`]).
fn add(
    record: &mut Record,
    info: &io::DatasetInfo,
    o: &Outcome,
    sweep: Option<&SweepInfo>,
    pose_time: PoseTime,
) {
    let index = o.meta.index;
    let mut time = o.meta.time.or_else(|| {
        info.frame_times
            .as_ref()
            .and_then(|t| t.get(index).copied())
    });
    let mut row = FrameRow::of(o);
    if let Some(s) = sweep {
        row = row.with_packets(&s.stats);
        time = Some(s.start_s + pose_time.fraction() * (s.end_s - s.start_s));
        record.sweeps = true;
    }
    let pose = match o.report() {
        Some(r) if r.deskewed => pose_time.pose(&o.pose, &o.sweep),
        _ => o.pose,
    };
    record.rows.push(row);
    record.poses.push(pose);
    record.times.push(time);
    record.indices.push(index);
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
