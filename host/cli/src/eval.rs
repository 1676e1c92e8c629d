//! `kiss-odom eval`: an estimated trajectory scored against ground truth, as a table or JSON.

use anyhow::{Context, Result};
use kiss_odom_io::metrics::{evaluate, Metrics};
use kiss_odom_io::poses::read_kitti;
use std::io::Write;
use std::path::{Path, PathBuf};

/// `kiss-odom eval` arguments.
#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    /// Estimated trajectory (KITTI 3x4 per line).
    pub estimate: PathBuf,
    /// Ground truth (KITTI 3x4 per line, same frame as the estimate).
    pub ground_truth: PathBuf,
    /// Print the metrics as JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Runs `kiss-odom eval`, printing to stdout.
pub fn execute(args: &EvalArgs) -> Result<i32> {
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    execute_to(args, &mut out)
}

/// Runs `kiss-odom eval`, printing the table (or JSON) to `out`.
pub fn execute_to(args: &EvalArgs, out: &mut dyn Write) -> Result<i32> {
    let est = read_kitti(&args.estimate)?;
    let gt = read_kitti(&args.ground_truth)?;
    let m = evaluate(&est, &gt).with_context(|| {
        format!(
            "{} against {}",
            args.estimate.display(),
            args.ground_truth.display()
        )
    })?;
    // JSON has no inf or NaN (serde writes null): say so instead of printing a blank.
    if let Some((name, value)) = m.non_finite() {
        anyhow::bail!(
            "{} against {}: {name} is {value}: the poses are too far apart for the error to be \
             computed in f64 (check the units and that both files are trajectories)",
            args.estimate.display(),
            args.ground_truth.display()
        );
    }
    if args.json {
        writeln!(out, "{}", serde_json::to_string_pretty(&m)?)?;
    } else {
        write_table(out, &m, &args.estimate, &args.ground_truth)?;
    }
    Ok(0)
}

/// Writes the metrics as a two-column table.
pub fn write_table(out: &mut dyn Write, m: &Metrics, est: &Path, gt: &Path) -> Result<()> {
    let kitti = |v: Option<f64>, unit: &str| match v {
        Some(v) => format!("{v:.4} {unit}"),
        None => "n/a (ground truth shorter than 100 m)".to_string(),
    };
    writeln!(out, "estimate:     {}", est.display())?;
    writeln!(out, "ground truth: {}", gt.display())?;
    let rows = [
        ("frames", format!("{}", m.frames)),
        (
            "KITTI relative translation error",
            kitti(m.kitti_t_err_pct, "%"),
        ),
        (
            "KITTI relative rotation error",
            kitti(m.kitti_r_err_deg_per_m, "deg/m"),
        ),
        ("ATE (RMSE, rigid alignment)", format!("{:.4} m", m.ate_m)),
        (
            "ARE (RMSE, rigid alignment)",
            format!("{:.6} rad", m.are_rad),
        ),
        ("final position error", format!("{:.4} m", m.final_error_m)),
        ("per-frame RPE mean", format!("{:.4} m", m.rpe_m_mean)),
        ("per-frame RPE max", format!("{:.4} m", m.rpe_m_max)),
        (
            "per-frame rotational RPE mean",
            format!("{:.6} rad", m.rpe_rad_mean),
        ),
    ];
    for (name, value) in rows {
        writeln!(out, "  {name:<34} {value}")?;
    }
    Ok(())
}
