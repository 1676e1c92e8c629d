//! `kiss-odom size`: the smallest fixed capacities that held a run, and the bytes of state they
//! take on each kind of target, so a team can size its firmware from its own recordings.
//!
//! A host run grows its storage as the recording needs (see `kiss_odom_drive::growth`), so its
//! high-water marks (`summary.json`) are what the recording asked of each buffer. Fixed at
//! those capacities, with the same settings, the same frames drop and evict nothing; the
//! targets differ only in the scalar and map storage their builds use.

use anyhow::{bail, Context, Result};
use kiss_odom_core::{Capacities, Exact, Odometry, PointCodec, Quantized, Real};
use serde_json::Value;
use std::io::Write;
use std::path::PathBuf;

/// `kiss-odom size` arguments.
#[derive(Debug, clap::Args)]
pub struct SizeArgs {
    /// A `run` output folder (its `summary.json` is read).
    pub run: PathBuf,
    /// The target to size for [default: every kind].
    #[arg(long, value_enum)]
    pub target: Option<Target>,
}

/// Kinds of target, by the build the firmware uses on them (`embedded/RESULTS.md`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Target {
    /// Cortex-M4F or M7 (single-precision FPU): f32, quantized map points.
    M7,
    /// Cortex-A53 class: f64, exact map points (the reference's bits).
    A53,
    /// RV32IMAC (no FPU): f32, quantized map points.
    Rv32,
}

impl Target {
    const ALL: [Target; 3] = [Target::M7, Target::A53, Target::Rv32];

    fn name(self) -> &'static str {
        match self {
            Target::M7 => "m7 (f32, quantized)",
            Target::A53 => "a53 (f64, exact)",
            Target::Rv32 => "rv32 (f32, quantized)",
        }
    }

    /// Bytes of state with `caps` in this target's build (the arena and the `Odometry` value
    /// as this host lays it out; a 32-bit target's value is a few hundred bytes smaller).
    fn bytes(self, caps: &Capacities) -> usize {
        match self {
            Target::M7 | Target::Rv32 => bytes::<f32, Quantized>(caps),
            Target::A53 => bytes::<f64, Exact>(caps),
        }
    }
}

fn bytes<T: Real, P: PointCodec<T>>(caps: &Capacities) -> usize {
    caps.arena_words::<T, P>() * 8 + core::mem::size_of::<Odometry<T, P>>()
}

/// Runs `kiss-odom size`, printing to stdout.
pub fn execute(args: &SizeArgs, err: &mut dyn Write) -> Result<i32> {
    let stdout = std::io::stdout();
    execute_to(args, &mut stdout.lock(), err)
}

/// Runs `kiss-odom size`, printing the capacities to `out` and warnings to `err`.
pub fn execute_to(args: &SizeArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<i32> {
    let path = args.run.join("summary.json");
    let text = std::fs::read_to_string(&path).with_context(|| {
        format!(
            "{}: cannot read (give a `run` output folder)",
            path.display()
        )
    })?;
    let summary: Value =
        serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
    let caps = held(&summary).with_context(|| format!("{}", path.display()))?;
    let degraded = &summary["degraded_frames"];
    let lost: u64 = ["evicted", "capacity", "scan_truncated"]
        .iter()
        .filter_map(|f| degraded[f].as_u64())
        .sum();
    if lost > 0 {
        writeln!(
            err,
            "warning: {}: the run dropped or evicted in {lost} frames, so these capacities are \
             what its full buffers held, not what the recording needs: run it again without \
             fixed capacities (and a larger runtime.memory_limit if it was reached)",
            path.display()
        )?;
    }
    writeln!(
        out,
        "# The smallest fixed capacities that held {}, with its settings (its config.toml):",
        args.run.display()
    )?;
    writeln!(out, "[capacities]")?;
    for (name, value) in [
        ("scan_points", caps.scan_points),
        ("merge_points", caps.merge_points),
        ("source_points", caps.source_points),
        ("map_voxels", caps.map_voxels),
        ("map_points", caps.map_points),
    ] {
        writeln!(out, "{name} = {value}")?;
    }
    let targets = args.target.map_or(Target::ALL.to_vec(), |t| vec![t]);
    for t in targets {
        let b = t.bytes(&caps);
        writeln!(
            out,
            "# {}: {b} bytes of state ({:.1} KiB)",
            t.name(),
            b as f64 / 1024.0
        )?;
    }
    Ok(0)
}

/// The capacities at a summary's high-water marks (each at least 1).
fn held(summary: &Value) -> Result<Capacities> {
    let hw = &summary["high_water"];
    let mark = |name: &str| -> Result<usize> {
        let v = hw[name].get(0).unwrap_or(&hw[name]);
        match v.as_u64() {
            Some(n) => Ok((n as usize).max(1)),
            None => bail!("no high_water.{name} (a summary.json of an older run?)"),
        }
    };
    let caps = Capacities {
        scan_points: mark("scan_points")?,
        merge_points: mark("merge_points")?,
        source_points: mark("source_points")?,
        map_voxels: mark("map_voxels")?,
        map_points: mark("map_point_slots")?,
        plane_terms: summary["input"]["plane_terms"].as_bool().unwrap_or(false),
    };
    caps.validate()
        .map_err(|e| anyhow::anyhow!("high-water marks out of range: {e}"))?;
    Ok(caps)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capacities_come_from_the_marks_and_a_lossy_run_is_warned_about() {
        let dir = tempfile::tempdir().unwrap();
        let summary = serde_json::json!({
            "high_water": {
                "scan_points": [1200, 262144],
                "merge_points": [300, 262144],
                "source_points": [90, 1000],
                "map_voxels": [4000, 8000],
                "map_point_slots": [0, 100],
            },
            "degraded_frames": {"evicted": 2},
            "input": {"plane_terms": false},
        });
        std::fs::write(dir.path().join("summary.json"), summary.to_string()).unwrap();
        let args = SizeArgs {
            run: dir.path().into(),
            target: Some(Target::M7),
        };
        let (mut out, mut err) = (Vec::new(), Vec::new());
        assert_eq!(execute_to(&args, &mut out, &mut err).unwrap(), 0);
        let (out, err) = (
            String::from_utf8(out).unwrap(),
            String::from_utf8(err).unwrap(),
        );
        assert!(out.contains("scan_points = 1200\n") && out.contains("map_voxels = 4000\n"));
        assert!(
            out.contains("map_points = 1\n"),
            "an empty map still needs a slot: {out}"
        );
        let caps = held(&summary).unwrap();
        assert!(
            out.contains(&format!("{} bytes", Target::M7.bytes(&caps))),
            "{out}"
        );
        assert!(!out.contains("a53"), "{out}");
        assert!(err.contains("evicted in 2 frames"), "{err}");
        let e = execute_to(
            &SizeArgs {
                run: dir.path().join("none"),
                target: None,
            },
            &mut Vec::new(),
            &mut Vec::new(),
        );
        assert!(format!("{:#}", e.unwrap_err()).contains("summary.json"));
    }
}
