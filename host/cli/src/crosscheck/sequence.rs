//! End to end: both pipelines over the same preloaded frames, compared pose by pose, scored
//! against ground truth with the same metrics, and timed in the same run.

use super::compare::{slope, summary, Agreement};
use super::driver::{arg, read_json, Driver};
use super::report::{sci, Row, Section};
use super::stage_kit::{TOL_REGISTRATION, TOL_SIGMA_REL};
use anyhow::{bail, Context, Result};
use kiss_odom_core::{Flag, Status};
use kiss_odom_drive::settings::{Scalar, Settings};
use kiss_odom_drive::Step;
use kiss_odom_io::metrics::{evaluate, Metrics};
use kiss_odom_io::pose::pose_of;
use kiss_odom_io::FrameRange;
use kiss_odom_io::Selection;
use kiss_odom_io::{self as io, Format, Frame};
use nalgebra::Isometry3;
use std::path::{Path, PathBuf};

/// Largest per-frame position difference to the reference (m).
pub const TOL_TRANSLATION_M: f64 = 0.01;
/// Largest per-frame rotation difference to the reference (deg).
pub const TOL_ROTATION_DEG: f64 = 0.05;
/// Final error and ATE within this of the reference's (m).
pub const TOL_METRIC_M: f64 = 0.005;
/// KITTI relative translation error within this of the reference's (percentage points).
pub const TOL_KITTI_PP: f64 = 0.02;
/// The f32 build's KITTI relative translation error may exceed the reference's by this (pp).
pub const TOL_KITTI_F32_PP: f64 = 0.05;

/// One implementation's run.
#[derive(Clone, Debug, Default)]
pub struct Trajectory {
    /// Who: `kiss-odom f64`, `kiss-icp 1.3.0`.
    pub label: String,
    /// Pose per frame.
    pub poses: Vec<Isometry3<f64>>,
    /// Sigma before each frame.
    pub sigmas: Vec<f64>,
    /// Seconds in the frame call, per frame.
    pub seconds: Vec<f64>,
    /// Frames whose report says a buffer was full (not something the reference does).
    pub capacity_frames: usize,
    /// Frames without a usable point.
    pub empty_frames: usize,
    /// Status of each frame (`None` for an empty one; nothing for the reference).
    pub status: Vec<Option<Status>>,
    /// Dataset index of each frame.
    pub indices: Vec<usize>,
}

impl Trajectory {
    /// Frames per second of frame-call time.
    pub fn hz(&self) -> f64 {
        self.poses.len() as f64 / self.seconds.iter().sum::<f64>()
    }
}

/// Preloads the frames of a dataset in `range`; fails on a frame that cannot be read.
pub fn preload(
    dataset: &mut io::Dataset,
    range: FrameRange,
    err: &mut dyn std::io::Write,
) -> Result<Vec<Frame>> {
    let mut out = Vec::new();
    for item in Selection::new(dataset.frames.as_mut(), range) {
        match item? {
            io::Item::Skipped { reason, .. } => {
                bail!("{reason} (the cross-check needs every frame)")
            }
            io::Item::Frame(f) => {
                for w in &f.warnings {
                    writeln!(err, "warning: {w}")?;
                }
                out.push(f);
            }
        }
    }
    if out.is_empty() {
        bail!("no frames in range");
    }
    Ok(out)
}

/// Runs our pipeline in `scalar` over preloaded frames through the driver, which times only
/// the core's frame calls.
pub fn run_ours(frames: &[Frame], settings: &Settings, scalar: Scalar) -> Result<Trajectory> {
    let mut settings = settings.clone();
    settings.runtime.scalar = scalar;
    let mut driver = kiss_odom_drive::Driver::new(&settings)?;
    let preloaded = driver.preload(frames);
    let mut t = Trajectory {
        label: format!("kiss-odom {}", format!("{scalar:?}").to_lowercase()),
        ..Default::default()
    };
    for k in 0..preloaded.len() {
        let o = driver.register_preloaded(&preloaded, k)?;
        let status = o.status();
        t.capacity_frames += usize::from(status.is_some_and(|s| s.contains(Flag::Capacity)));
        t.empty_frames += usize::from(o.step == Step::Empty);
        t.status.push(status);
        t.indices.push(o.meta.index);
        t.seconds.push(o.latency.as_secs_f64());
        t.sigmas.push(o.sigma);
        t.poses.push(o.pose);
    }
    Ok(t)
}

/// How the driver should read the dataset.
pub enum RefInput {
    /// A path and format the driver reads itself (`kitti` or `generic` f32x4 `.bin`), with the
    /// Python slice of the frames.
    Direct {
        /// Dataset folder.
        path: PathBuf,
        /// `kitti` or `generic`.
        format: &'static str,
        /// `A:B`.
        frames: String,
    },
    /// Frames exported to a generic f64 layout (any other format).
    Exported(PathBuf),
}

/// Chooses how the driver reads the dataset; other formats are exported from the preloaded
/// frames (already corrected and selected).
pub fn ref_input(
    driver: &mut Driver,
    path: &Path,
    format: Format,
    range: FrameRange,
    frames: &[Frame],
) -> Result<RefInput> {
    let slice = format!(
        "{}:{}",
        range.start,
        range.end.map_or(String::new(), |e| e.to_string())
    );
    match format {
        Format::Kitti => Ok(RefInput::Direct {
            path: path.to_path_buf(),
            format: "kitti",
            frames: slice,
        }),
        Format::Bin => Ok(RefInput::Direct {
            path: path.to_path_buf(),
            format: "generic",
            frames: slice,
        }),
        _ => {
            let root = driver.file("frames");
            std::fs::create_dir_all(root.join("velodyne"))?;
            std::fs::create_dir_all(root.join("timestamps"))?;
            for (i, f) in frames.iter().enumerate() {
                let bytes: Vec<u8> = f
                    .points
                    .iter()
                    .flatten()
                    .flat_map(|v| v.to_le_bytes())
                    .collect();
                std::fs::write(root.join(format!("velodyne/{i:06}.bin")), bytes)?;
                if let Some(st) = &f.stamps {
                    let bytes: Vec<u8> = st.iter().flat_map(|v| v.to_le_bytes()).collect();
                    std::fs::write(root.join(format!("timestamps/{i:06}.bin")), bytes)?;
                }
            }
            Ok(RefInput::Exported(root))
        }
    }
}

/// Runs the reference pipeline (`driver.py pipeline`) over `n` frames.
pub fn run_reference(
    driver: &mut Driver,
    input: &RefInput,
    settings: &Settings,
    threads: usize,
    n: usize,
) -> Result<Trajectory> {
    let out = driver.file("ref_poses.txt");
    let side = driver.file("ref_side.json");
    let mut args: Vec<String> = vec!["pipeline".into()];
    match input {
        RefInput::Direct {
            path,
            format,
            frames,
        } => {
            args.extend([
                "--dataset".into(),
                arg(path)?,
                "--format".into(),
                (*format).into(),
                "--frames".into(),
                frames.clone(),
            ]);
        }
        RefInput::Exported(root) => {
            args.extend([
                "--dataset".into(),
                arg(root)?,
                "--format".into(),
                "generic".into(),
                "--bin-layout".into(),
                "f64x3".into(),
            ]);
        }
    }
    args.extend([
        "--max-range".into(),
        format!("{:?}", settings.data.max_range),
        "--min-range".into(),
        format!("{:?}", settings.data.min_range),
        "--voxel-size".into(),
        format!("{:?}", settings.voxel_size()),
        if settings.data.deskew {
            "--deskew"
        } else {
            "--no-deskew"
        }
        .into(),
        "--threads".into(),
        threads.to_string(),
        "--out".into(),
        arg(&out)?,
        "--side".into(),
        arg(&side)?,
    ]);
    driver.run(&args).context("reference pipeline")?;
    let matrices = io::poses::read_kitti_matrices(&out)?;
    let side = read_json(&side)?;
    let per_frame = side["per_frame"].as_array().cloned().unwrap_or_default();
    if matrices.len() != n || per_frame.len() != n {
        bail!(
            "the reference ran {} frames ({} side records), kiss-odom {n}: the two read the \
             dataset differently",
            matrices.len(),
            per_frame.len()
        );
    }
    let num = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
    Ok(Trajectory {
        label: format!(
            "kiss-icp {}",
            side["versions"]["kiss_icp"].as_str().unwrap_or("?")
        ),
        poses: matrices.iter().map(pose_of).collect(),
        sigmas: per_frame.iter().map(|f| num(&f["sigma"])).collect(),
        seconds: per_frame.iter().map(|f| num(&f["seconds"])).collect(),
        capacity_frames: 0,
        empty_frames: 0,
        status: Vec::new(),
        indices: Vec::new(),
    })
}

/// Ground truth for the preloaded frames, re-based to the first (as `run` does).
pub fn ground_truth(info: &io::DatasetInfo, frames: &[Frame]) -> Option<Vec<Isometry3<f64>>> {
    let indices: Vec<usize> = frames.iter().map(|f| f.index).collect();
    // Every frame needs one; a frame without ground truth leaves the metrics out.
    info.ground_truth_for(&indices).into_iter().collect()
}

/// Figures of one comparison, for the JSON file.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Figures {
    /// Who against whom.
    pub pair: String,
    /// Per-frame differences.
    pub agreement: Agreement,
    /// Metrics of the first trajectory against ground truth.
    pub metrics: Option<Metrics>,
    /// Metrics of the second.
    pub metrics_other: Option<Metrics>,
}

fn deg(rad: f64) -> f64 {
    rad.to_degrees()
}

fn per_frame_text(v: &[f64], unit: &str, scale: f64) -> String {
    let (max, mean, last) = summary(v);
    format!(
        "max {} {unit} (mean {}, last {})",
        sci(max * scale),
        sci(mean * scale),
        sci(last * scale)
    )
}

/// Difference every 100 frames and the linear trend, for long runs (at least 200 frames).
pub fn trend_rows(agree: &Agreement, sec: &mut Section) {
    let n = agree.translation_m.len();
    if n < 200 {
        return;
    }
    let at: Vec<String> = (100..n)
        .step_by(100)
        .map(|k| format!("{k}: {}", sci(agree.translation_m[k])))
        .collect();
    sec.push(Row::report(
        "translation difference at every 100th frame (m)",
        at.join(", "),
    ));
    let half = n / 2;
    let (m1, _, _) = summary(&agree.translation_m[..half]);
    let (m2, _, _) = summary(&agree.translation_m[half..]);
    sec.push(Row::report(
        "translation difference trend",
        format!(
            "linear fit slope {} m per 100 frames; max first half {} m, second half {} m",
            sci(slope(&agree.translation_m) * 100.0),
            sci(m1),
            sci(m2)
        ),
    ));
    let (smax, smean, _) = summary(&agree.step_translation_m);
    let (s1, _, _) = summary(&agree.step_translation_m[..half]);
    let (s2, _, _) = summary(&agree.step_translation_m[half..]);
    sec.push(Row::report(
        "frame-to-frame motion difference (m)",
        format!(
            "max {} (mean {}; max first half {}, second half {})",
            sci(smax),
            sci(smean),
            sci(s1),
            sci(s2)
        ),
    ));
}

fn metric_text(ours: f64, theirs: f64, unit: &str) -> String {
    format!(
        "{ours:.4} vs {theirs:.4} {unit} (diff {})",
        sci((ours - theirs).abs())
    )
}

/// The f64 build against the reference: every end-to-end check.
pub fn compare_f64(
    ours: &Trajectory,
    reference: &Trajectory,
    gt: Option<&[Isometry3<f64>]>,
    threads: usize,
) -> Result<(Section, Figures)> {
    let mut sec = Section::new(format!(
        "end to end: {} vs {} ({} frames)",
        ours.label,
        reference.label,
        ours.poses.len()
    ));
    let agree = Agreement::of(&ours.poses, &reference.poses);
    let (tmax, _, _) = summary(&agree.translation_m);
    let (rmax, _, _) = summary(&agree.rotation_rad);
    sec.push(Row::check(
        "per-frame translation difference",
        tmax,
        TOL_TRANSLATION_M,
        per_frame_text(&agree.translation_m, "m", 1.0),
        format!("max <= {} m", TOL_TRANSLATION_M),
    ));
    sec.push(Row::check(
        "per-frame rotation difference",
        deg(rmax),
        TOL_ROTATION_DEG,
        per_frame_text(&agree.rotation_rad, "deg", 180.0 / std::f64::consts::PI),
        format!("max <= {} deg", TOL_ROTATION_DEG),
    ));
    trend_rows(&agree, &mut sec);
    let agreeing = agree.agreeing_prefix(TOL_REGISTRATION, TOL_REGISTRATION);
    status_rows(ours, agreeing, &mut sec);
    let sig = ours.sigmas[..agreeing]
        .iter()
        .zip(&reference.sigmas)
        .map(|(a, b)| ((a - b) / b).abs())
        .fold(0.0, f64::max);
    sec.push(Row::check(
        format!(
            "sigma per frame while poses agree to {} m / rad ({} of {} frames), relative",
            sci(TOL_REGISTRATION),
            agreeing,
            ours.poses.len()
        ),
        sig,
        TOL_SIGMA_REL,
        sci(sig),
        format!("<= {}", sci(TOL_SIGMA_REL)),
    ));
    let (m_ours, m_ref) = match gt {
        Some(gt) => (
            Some(evaluate(&ours.poses, gt)?),
            Some(evaluate(&reference.poses, gt)?),
        ),
        None => (None, None),
    };
    if let (Some(a), Some(b)) = (&m_ours, &m_ref) {
        sec.push(Row::check(
            "final position error vs ground truth: ours vs reference",
            (a.final_error_m - b.final_error_m).abs(),
            TOL_METRIC_M,
            metric_text(a.final_error_m, b.final_error_m, "m"),
            format!("|diff| <= {TOL_METRIC_M} m"),
        ));
        sec.push(Row::check(
            "ATE vs ground truth: ours vs reference",
            (a.ate_m - b.ate_m).abs(),
            TOL_METRIC_M,
            metric_text(a.ate_m, b.ate_m, "m"),
            format!("|diff| <= {TOL_METRIC_M} m"),
        ));
        match (a.kitti_t_err_pct, b.kitti_t_err_pct) {
            (Some(x), Some(y)) => sec.push(Row::check(
                "KITTI relative translation error: ours vs reference",
                (x - y).abs(),
                TOL_KITTI_PP,
                metric_text(x, y, "%"),
                format!("|diff| <= {TOL_KITTI_PP} pp"),
            )),
            _ => sec.push(Row::report(
                "KITTI relative translation error",
                "n/a (no 100 m segment in the ground truth)".into(),
            )),
        }
        if let (Some(x), Some(y)) = (a.kitti_r_err_deg_per_m, b.kitti_r_err_deg_per_m) {
            sec.push(Row::report(
                "KITTI relative rotation error: ours vs reference",
                format!("{x:.6} vs {y:.6} deg/m"),
            ));
        }
        sec.push(Row::report(
            "per-frame RPE mean: ours vs reference",
            metric_text(a.rpe_m_mean, b.rpe_m_mean, "m"),
        ));
    } else {
        sec.push(Row::report(
            "metrics against ground truth",
            "n/a (no ground truth)".into(),
        ));
    }
    throughput_rows(&mut sec, ours, reference, threads);
    Ok((
        sec,
        Figures {
            pair: format!("{} vs {}", ours.label, reference.label),
            agreement: agree,
            metrics: m_ours,
            metrics_other: m_ref,
        },
    ))
}

/// Where the poses part, and which frames the core flagged: the first place to look when an
/// end-to-end check fails.
fn status_rows(ours: &Trajectory, agreeing: usize, sec: &mut Section) {
    if agreeing < ours.poses.len() {
        sec.push(Row::report(
            format!(
                "first frame where the poses differ by more than {} m or rad",
                sci(TOL_REGISTRATION)
            ),
            format!(
                "frame {} (kiss-odom status there: {})",
                ours.indices.get(agreeing).copied().unwrap_or(agreeing),
                match ours.status.get(agreeing) {
                    Some(Some(s)) => s.to_string(),
                    Some(None) => "empty".to_string(),
                    None => "?".to_string(),
                }
            ),
        ));
    }
    let mut flags = std::collections::BTreeMap::new();
    for flag in ours.status.iter().flatten().flat_map(|s| s.flags()) {
        *flags.entry(flag.name()).or_insert(0usize) += 1;
    }
    if !flags.is_empty() {
        let text: Vec<String> = flags.iter().map(|(f, n)| format!("{f}: {n}")).collect();
        sec.push(Row::report(
            format!("frames kiss-odom flagged ({})", ours.label),
            text.join(", "),
        ));
    }
}

fn throughput_rows(sec: &mut Section, ours: &Trajectory, reference: &Trajectory, threads: usize) {
    if ours.capacity_frames + ours.empty_frames > 0 {
        sec.push(Row::report(
            "frames with a full buffer / no usable point",
            format!("{} / {}", ours.capacity_frames, ours.empty_frames),
        ));
    }
    sec.push(Row::report(
        format!("throughput, {threads} thread(s), same run"),
        format!(
            "{}: {:.1} Hz, {}: {:.1} Hz (ratio {:.2})",
            ours.label,
            ours.hz(),
            reference.label,
            reference.hz(),
            ours.hz() / reference.hz()
        ),
    ));
}

/// The f32 build against the reference and the f64 build.
pub fn compare_f32(
    ours32: &Trajectory,
    ours64: &Trajectory,
    reference: &Trajectory,
    gt: Option<&[Isometry3<f64>]>,
    threads: usize,
) -> Result<(Section, Vec<Figures>)> {
    let mut sec = Section::new(format!(
        "end to end: {} vs {} and {} ({} frames)",
        ours32.label,
        reference.label,
        ours64.label,
        ours32.poses.len()
    ));
    let vs_ref = Agreement::of(&ours32.poses, &reference.poses);
    let vs_64 = Agreement::of(&ours32.poses, &ours64.poses);
    for (who, a) in [("reference", &vs_ref), ("f64 build", &vs_64)] {
        sec.push(Row::report(
            format!("per-frame translation difference to the {who}"),
            per_frame_text(&a.translation_m, "m", 1.0),
        ));
        sec.push(Row::report(
            format!("per-frame rotation difference to the {who}"),
            per_frame_text(&a.rotation_rad, "deg", 180.0 / std::f64::consts::PI),
        ));
    }
    trend_rows(&vs_ref, &mut sec);
    status_rows(ours32, ours32.poses.len(), &mut sec);
    let mut m32 = None;
    let mut mref = None;
    if let Some(gt) = gt {
        let a = evaluate(&ours32.poses, gt)?;
        let b = evaluate(&reference.poses, gt)?;
        let c = evaluate(&ours64.poses, gt)?;
        sec.push(Row::report(
            "final position error: f32 vs reference (f64 build)",
            format!(
                "{} ({:.4} m)",
                metric_text(a.final_error_m, b.final_error_m, "m"),
                c.final_error_m
            ),
        ));
        sec.push(Row::report(
            "ATE: f32 vs reference (f64 build)",
            format!("{} ({:.4} m)", metric_text(a.ate_m, b.ate_m, "m"), c.ate_m),
        ));
        match (a.kitti_t_err_pct, b.kitti_t_err_pct) {
            (Some(x), Some(y)) => sec.push(Row::check(
                "KITTI relative translation error: f32 minus reference",
                x - y,
                TOL_KITTI_F32_PP,
                format!(
                    "{x:.4} vs {y:.4} % ({:+.4} pp; f64 build {:.4} %)",
                    x - y,
                    c.kitti_t_err_pct.unwrap_or(f64::NAN)
                ),
                format!("<= +{TOL_KITTI_F32_PP} pp"),
            )),
            _ => sec.push(Row::report(
                "KITTI relative translation error",
                "n/a (no 100 m segment in the ground truth)".into(),
            )),
        }
        if let (Some(x), Some(y)) = (a.kitti_r_err_deg_per_m, b.kitti_r_err_deg_per_m) {
            sec.push(Row::report(
                "KITTI relative rotation error: f32 vs reference",
                format!("{x:.6} vs {y:.6} deg/m"),
            ));
        }
        m32 = Some(a);
        mref = Some(b);
    }
    throughput_rows(&mut sec, ours32, reference, threads);
    sec.push(Row::report(
        "throughput f32 vs f64 build, same run",
        format!(
            "{:.1} Hz vs {:.1} Hz (ratio {:.2})",
            ours32.hz(),
            ours64.hz(),
            ours32.hz() / ours64.hz()
        ),
    ));
    Ok((
        sec,
        vec![
            Figures {
                pair: format!("{} vs {}", ours32.label, reference.label),
                agreement: vs_ref,
                metrics: m32,
                metrics_other: mref,
            },
            Figures {
                pair: format!("{} vs {}", ours32.label, ours64.label),
                agreement: vs_64,
                metrics: None,
                metrics_other: None,
            },
        ],
    ))
}
