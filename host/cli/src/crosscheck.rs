//! `kiss-odom-dev crosscheck`: kiss-odom against the reference kiss-icp 1.3.0 on the same data.
//!
//! It sits beside the pipeline as its referee. Stage checks run the core's public stage APIs
//! and the matching reference entry points (through `tests/reference/driver.py`) on identical
//! inputs from a few frames; end to end runs both pipelines over every selected frame, compares
//! the poses frame by frame, scores both against ground truth and times both in the same run.
//! Each figure is printed next to its tolerance; any breach is named and exits 1.
//!
//! A folder of loose `raw_NN.bin` + `times_NN.bin` scans (real sensor timing, not a sequence)
//! gets the deskew checks instead, with a relative motion given to both (`--motion`).

mod compare;
mod driver;
mod map_stages;
mod report;
mod scans;
mod sequence;
mod stage_kit;
mod stages;

pub use report::{Report, TableStyle};

use crate::args::CommonArgs;
use crate::reference::ReferenceArgs;
use anyhow::{bail, Context, Result};
use clap::ValueEnum;
use kiss_odom_drive::settings::{Scalar, Settings};
use kiss_odom_io::{self as io, Format, FrameRange, SensorKind};
use nalgebra::Isometry3;
use std::io::Write;
use std::path::PathBuf;

/// `kiss-odom-dev crosscheck` arguments.
#[derive(Debug, clap::Args)]
#[command(
    mut_arg("config", |a| a.help(crate::reference::CONFIG_HELP_WITH_REFERENCE)),
    mut_arg("threads", |a| a.help(crate::reference::THREADS_HELP_WITH_REFERENCE)),
    mut_arg("set", |a| a.help(
        "Any setting by its key in the settings file, repeatable; the end-to-end run's \
         `runtime.scalar=f32` also runs the f64 build and reports against both (stage checks \
         always use f64 and exact storage)"
    )),
)]
pub struct CrosscheckArgs {
    /// A sequence (KITTI `sequences/XX`, generic folder, bag, MCAP: anything `run` reads), or
    /// a folder of `raw_NN.bin` (f32 x y z) + `times_NN.bin` (f32 s) scans for the deskew
    /// checks (then `--frames` picks scans by position).
    pub dataset: PathBuf,
    /// Also write every figure (and per-frame differences) as JSON to this file.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Run only these checks (default: both; scans have stage checks only). Stage checks
    /// always use the f64 build with exact map storage (their tolerances are f64 ones).
    #[arg(long, value_enum)]
    pub only: Option<Only>,
    /// Relative motion for deskewing loose scans: 12 or 16 row-major numbers (default 0.5 m
    /// forward, 0.1 rad yaw, 0.02 pitch, -0.01 roll).
    #[arg(long, allow_hyphen_values = true)]
    pub motion: Option<String>,
    /// Table style.
    #[arg(long, value_enum, default_value_t = TableStyle::Text)]
    pub table: TableStyle,
    /// No progress messages.
    #[arg(long, short)]
    pub quiet: bool,
    /// Input, pipeline and core options.
    #[command(flatten)]
    pub common: CommonArgs,
    /// Where the reference is.
    #[command(flatten, next_help_heading = "Reference")]
    pub reference: ReferenceArgs,
}

/// Which checks to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Only {
    /// Stage by stage on a few frames.
    Stages,
    /// Whole pipelines over every selected frame.
    EndToEnd,
}

fn settings_of(args: &CrosscheckArgs) -> Result<Settings> {
    let s = args.common.settings(Some(1))?;
    crate::reference::check_reference_compatible(&s)?;
    Ok(s)
}

fn parse_motion(text: &str) -> Result<Isometry3<f64>> {
    let v: Vec<f64> = text
        .replace(',', " ")
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()
        .context("--motion: not numbers")?;
    if v.len() != 12 && v.len() != 16 {
        bail!("--motion: expected 12 or 16 numbers, got {}", v.len());
    }
    let mut rows = [0.0; 12];
    rows.copy_from_slice(&v[..12]);
    let m = io::poses::matrix_from_rows(&rows);
    let r = m.fixed_view::<3, 3>(0, 0).into_owned();
    if (r.transpose() * r - nalgebra::Matrix3::identity()).norm() >= 1e-10 || r.determinant() <= 0.0
    {
        bail!("--motion: the rotation is not orthonormal to 1e-10 (give full precision)");
    }
    Ok(kiss_odom_io::pose::pose_of(&m))
}

/// Runs `kiss-odom-dev crosscheck`: prints the table to stdout, breaches to `err`; 1 on a breach.
pub fn execute(args: &CrosscheckArgs, err: &mut dyn Write) -> Result<i32> {
    if let Some(path) = &args.json {
        kiss_odom_io::write::remove_stale_file(path)?;
    }
    let settings = settings_of(args)?;
    if let Some(w) = settings.threads_warning() {
        writeln!(err, "warning: {w}")?;
    }
    if !args.dataset.exists() {
        bail!("{}: no such file or folder", args.dataset.display());
    }
    let script = args.reference.driver()?;
    let mut drv = driver::Driver::new(args.reference.python(), script.clone())?;
    let threads = settings.threads();
    let range = args.common.input.range();
    let mut report = Report::default();
    let mut json = serde_json::json!({
        "dataset": args.dataset.display().to_string(),
        "reference": drv.versions,
        "driver": script.display().to_string(),
        "threads": threads,
        "scalar": settings.runtime.scalar,
        "command": command_of(args),
    });
    report
        .notes
        .push(format!("reference: {}", drv.versions_line()));
    report
        .notes
        .push(format!("command: `{}`", command_of(args)));

    let scan_files = scans::find(&args.dataset);
    if !scan_files.is_empty() && !args.dataset.join("velodyne").is_dir() {
        let picked: Vec<_> = scan_files
            .iter()
            .enumerate()
            .filter(|(i, _)| range.contains(*i))
            .map(|(_, s)| s.clone())
            .collect();
        if picked.is_empty() {
            bail!("{}: no scans in range", args.dataset.display());
        }
        if args.only == Some(Only::EndToEnd) {
            bail!("loose scans are not a sequence: only the stage (deskew) checks apply");
        }
        let motion = match &args.motion {
            Some(m) => parse_motion(m)?,
            None => scans::default_motion(),
        };
        report.title = format!(
            "kiss-odom crosscheck: {} ({} scans with per-point times: deskew checks)",
            args.dataset.display(),
            picked.len()
        );
        progress(args, err, "reference and core stages on the scans")?;
        let min_range = settings.data.min_range;
        let crop = (
            if min_range != Settings::default().data.min_range {
                min_range
            } else {
                scans::DEFAULT_CROP.0
            },
            args.common
                .pipeline
                .max_range
                .unwrap_or(scans::DEFAULT_CROP.1),
        );
        report.sections = scans::scan_stages(&mut drv, &picked, &motion, crop, &settings)?;
        json["motion"] = serde_json::json!(driver::pose_arg(&motion));
    } else {
        sequence_checks(
            args,
            &settings,
            &mut drv,
            range,
            threads,
            err,
            &mut report,
            &mut json,
        )?;
    }

    // Through `print!` so that in-process callers (tests) capture it.
    let mut table = Vec::new();
    report.write_table(&mut table, args.table)?;
    print!("{}", String::from_utf8_lossy(&table));
    let code = report.verdict(err);
    if let Some(path) = &args.json {
        json["sections"] = serde_json::to_value(&report.sections)?;
        json["passed"] = serde_json::json!(code == 0);
        let text = serde_json::to_string_pretty(&json)? + "\n";
        kiss_odom_io::write::write(path, text.as_bytes())?;
    }
    Ok(code)
}

fn progress(args: &CrosscheckArgs, err: &mut dyn Write, what: &str) -> Result<()> {
    if !args.quiet {
        writeln!(err, "crosscheck: {what}...")?;
    }
    Ok(())
}

/// The command that reproduces this run (paths of Python, driver and JSON left out: they do
/// not change the figures).
pub fn command_of(args: &CrosscheckArgs) -> String {
    let mut c = format!("kiss-odom-dev crosscheck {}", args.dataset.display());
    let mut flag = |name: &str, value: Option<String>| {
        if let Some(v) = value {
            c.push_str(&format!(" --{name}"));
            if !v.is_empty() {
                c.push_str(&format!(" {v}"));
            }
        }
    };
    let (input, p, core) = (&args.common.input, &args.common.pipeline, &args.common.core);
    let lower = |v: &dyn std::fmt::Debug| format!("{v:?}").to_lowercase();
    flag("frames", input.frames.map(|r| r.to_string()));
    flag("threads", core.threads.map(|t| t.to_string()));
    flag(
        "format",
        (input.format != Format::Auto).then(|| lower(&input.format)),
    );
    flag("topic", input.topic.clone());
    let sensor = &input.sensor;
    flag(
        "sensor",
        (sensor.sensor != SensorKind::Auto)
            .then(|| sensor.sensor.to_possible_value())
            .flatten()
            .map(|v| v.get_name().to_string()),
    );
    flag(
        "calibration",
        sensor.calibration.as_ref().map(|m| m.display().to_string()),
    );
    flag(
        "only",
        args.only.map(|o| match o {
            Only::Stages => "stages".to_string(),
            Only::EndToEnd => "end-to-end".to_string(),
        }),
    );
    flag("motion", args.motion.as_ref().map(|m| format!("'{m}'")));
    flag("config", p.config.as_ref().map(|c| c.display().to_string()));
    for a in &p.set {
        flag("set", Some(a.clone()));
    }
    flag("max-range", p.max_range.map(|v| v.to_string()));
    c
}

#[allow(clippy::too_many_arguments)]
fn sequence_checks(
    args: &CrosscheckArgs,
    settings: &Settings,
    drv: &mut driver::Driver,
    range: FrameRange,
    threads: usize,
    err: &mut dyn Write,
    report: &mut Report,
    json: &mut serde_json::Value,
) -> Result<()> {
    let format = match args.common.input.format {
        Format::Auto => io::open::detect(&args.dataset)?,
        f => f,
    };
    let opts = args
        .common
        .open_options(settings.capacities()?.scan_points, &settings.input);
    let mut dataset = io::open(&args.dataset, format, &opts)?;
    progress(args, err, "reading frames")?;
    let frames = sequence::preload(&mut dataset, range, err)?;
    let n = frames.len();
    let first = frames[0].index;
    report.title = format!(
        "kiss-odom crosscheck: {} ({}, frames {}..{}, {} thread(s), {})",
        args.dataset.display(),
        format!("{format:?}").to_lowercase(),
        first,
        first + n,
        threads,
        match settings.runtime.scalar {
            Scalar::F64 => "f64",
            Scalar::F32 => "f32 and f64",
        }
    );
    let deskew_note = if frames.iter().any(|f| f.stamps.is_some()) {
        if settings.data.deskew {
            "per-point times: deskew on"
        } else {
            "per-point times: deskew off"
        }
    } else {
        "no per-point times"
    };
    let threads_note = if threads > 1 {
        format!("{threads} threads each (the reference is then nondeterministic at rounding level)")
    } else {
        "1 thread each (both deterministic)".into()
    };
    report.notes.push(format!(
        "settings: max range {} m, min range {} m, voxel {} m, {deskew_note}; {threads_note}",
        settings.data.max_range,
        settings.data.min_range,
        settings.voxel_size()
    ));
    let gt = sequence::ground_truth(&dataset.info, &frames);
    let run_e2e = args.only != Some(Only::Stages);
    let run_stages = args.only != Some(Only::EndToEnd);
    let input = sequence::ref_input(drv, &args.dataset, format, range, &frames)?;

    // The reference first: stage checks use its poses and sigmas.
    let ref_frames = if run_e2e {
        n
    } else {
        stage_kit::frames_needed(n)
    };
    progress(
        args,
        err,
        &format!("reference pipeline over {ref_frames} frames"),
    )?;
    let input = match (&input, run_e2e) {
        (sequence::RefInput::Direct { path, format, .. }, false) => sequence::RefInput::Direct {
            path: path.clone(),
            format,
            frames: format!("{}:{}", first, first + ref_frames),
        },
        _ => input,
    };
    let reference = if let sequence::RefInput::Exported(_) = input {
        let full = sequence::run_reference(drv, &input, settings, threads, n)?;
        truncate(full, ref_frames)
    } else {
        sequence::run_reference(drv, &input, settings, threads, ref_frames)?
    };

    if run_e2e {
        progress(args, err, &format!("kiss-odom f64 over {n} frames"))?;
        let ours64 = sequence::run_ours(&frames, settings, Scalar::F64)?;
        let (sec, fig) = sequence::compare_f64(&ours64, &reference, gt.as_deref(), threads)?;
        report.sections.push(sec);
        let mut figures = vec![fig];
        if settings.runtime.scalar == Scalar::F32 {
            progress(args, err, &format!("kiss-odom f32 over {n} frames"))?;
            let ours32 = sequence::run_ours(&frames, settings, Scalar::F32)?;
            let (sec, figs) =
                sequence::compare_f32(&ours32, &ours64, &reference, gt.as_deref(), threads)?;
            report.sections.push(sec);
            figures.extend(figs);
        }
        json["end_to_end"] = serde_json::to_value(&figures)?;
        json["hz"] = serde_json::json!({
            "reference": reference.hz(),
            "kiss_odom_f64": ours64.hz(),
        });
    }
    if run_stages {
        progress(args, err, "stage checks")?;
        let label = |k: usize| format!("frame {}", frames[k].index);
        let inp = stage_kit::SequenceInput {
            frames: &frames,
            ref_poses: &reference.poses,
            ref_sigmas: &reference.sigmas,
            settings,
        };
        let mut secs = stages::sequence_stages(drv, &inp, &label)?;
        secs.append(&mut report.sections);
        report.sections = secs;
    }
    Ok(())
}

fn truncate(mut t: sequence::Trajectory, n: usize) -> sequence::Trajectory {
    t.poses.truncate(n);
    t.sigmas.truncate(n);
    t.seconds.truncate(n);
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Wrap {
        #[command(flatten)]
        args: CrosscheckArgs,
    }

    fn parse(argv: &[&str]) -> CrosscheckArgs {
        Wrap::try_parse_from(std::iter::once("x").chain(argv.iter().copied()))
            .unwrap()
            .args
    }

    #[test]
    fn the_printed_command_repeats_the_run() {
        let argv = [
            "data/seq",
            "--frames",
            "3..",
            "--threads",
            "2",
            "--set",
            "runtime.scalar=f32",
            "--only",
            "stages",
            "--json",
            "out.json",
        ];
        assert_eq!(
            command_of(&parse(&argv)),
            "kiss-odom-dev crosscheck data/seq --frames 3.. --threads 2 --only stages --set \
             runtime.scalar=f32"
        );
        assert_eq!(
            command_of(&parse(&["d"])),
            "kiss-odom-dev crosscheck d",
            "defaults are left out"
        );
    }

    #[test]
    fn a_motion_must_be_a_rigid_transform_in_full_precision() {
        let m = parse_motion("1 0 0 0.5 0 1 0 0 0 0 1 0").unwrap();
        assert_eq!(m.translation.vector.x, 0.5);
        assert!(parse_motion("1 0 0 0 0 1 0 0 0 0 1").is_err());
        assert!(parse_motion("1 0 0 0 0 0.9999 0 0 0 0 1 0").is_err());
        assert!(parse_motion("-1 0 0 0 0 1 0 0 0 0 1 0").is_err());
    }
}
