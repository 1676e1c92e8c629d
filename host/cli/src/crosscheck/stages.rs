//! Stage checks: each of the core's stage APIs against the matching reference entry point,
//! fed identical inputs taken from a few frames of the dataset.
//!
//! Every stage gets the reference's own output of the stage before it, so a disagreement is
//! attributed to the stage that made it: preprocessing (crop, and deskew when the frames have
//! per-point times) of raw frames; both downsampling passes of the reference's preprocessed
//! frame; the local map after updates at the reference's poses, correspondences and a full
//! registration against the reference's own map ([`super::map_stages`]); the adaptive
//! threshold over the model deviations of the reference's run.

use super::compare::{order_difference, set_difference};
use super::driver::{arg, pose_arg, read_f64s, read_points, Driver};
use super::map_stages::map_and_registration;
use super::report::{Row, Section};
use super::stage_kit::{
    delta_before, downsample, downsample_cmd, model_deviations, points_row, s, stage_frames,
    SequenceInput, TOL_PREPROCESS_M, TOL_SIGMA_REL,
};
use anyhow::{Context, Result};
use kiss_odom_core::stages::{preprocess, AdaptiveThreshold};
use kiss_odom_core::Config;
use nalgebra::Isometry3;
use std::path::PathBuf;

/// One picked frame and the reference's files for it.
struct Pick {
    k: usize,
    stamps: Option<Vec<f64>>,
    motion: Isometry3<f64>,
    pre: PathBuf,
    merge: PathBuf,
    source: PathBuf,
}

/// Runs the stage checks of a sequence; `label(k)` names frame `k` for the table.
pub fn sequence_stages(
    driver: &mut Driver,
    inp: &SequenceInput,
    label: &dyn Fn(usize) -> String,
) -> Result<Vec<Section>> {
    let cfg = inp.settings.core_config::<f64>()?;
    let (picks, pair) = stage_frames(inp.frames.len());
    // One batch of the reference: each picked frame's stages, then the threshold.
    let mut cmds = Vec::new();
    let mut picked = Vec::new();
    for &k in &picks {
        let (pick, stage_cmds) = frame_commands(driver, inp, &cfg, k)?;
        cmds.extend(stage_cmds);
        picked.push(pick);
    }
    let deviations = model_deviations(inp.ref_poses);
    let (threshold_cmd, sigmas) = threshold_command(driver, &cfg, &deviations)?;
    cmds.push(threshold_cmd);
    driver.batch(&cmds).context("reference stages")?;

    let (pre, down, ref_sources) = front_stages(inp, &cfg, &picked, label)?;
    let mut sections = vec![pre, down];
    if let Some((a, b)) = pair {
        let source_b = ref_sources
            .into_iter()
            .find(|(k, _)| *k == b)
            .map(|(_, s)| s)
            .unwrap_or_default();
        sections.push(map_and_registration(
            driver, inp, &cfg, a, b, &source_b, label,
        )?);
    }
    sections.push(threshold(&cfg, &deviations, &read_f64s(&sigmas)?));
    Ok(sections)
}

/// The reference's commands for frame `k`: preprocessing, then both downsampling passes.
fn frame_commands(
    driver: &mut Driver,
    inp: &SequenceInput,
    cfg: &Config<f64>,
    k: usize,
) -> Result<(Pick, Vec<Vec<String>>)> {
    let f = &inp.frames[k];
    let points = driver.write_points(&format!("frame{k}.f64"), &f.points)?;
    let stamps = f.stamps.clone().filter(|_| cfg.deskew);
    let motion = delta_before(inp.ref_poses, k);
    let pick = Pick {
        k,
        motion,
        pre: driver.file(&format!("pre{k}.f64")),
        merge: driver.file(&format!("merge{k}.f64")),
        source: driver.file(&format!("source{k}.f64")),
        stamps: None,
    };
    let mut c = vec![
        "preprocess".into(),
        "--points".into(),
        arg(&points)?,
        "--motion".into(),
        pose_arg(&motion),
        "--min-range".into(),
        s(cfg.min_range),
        "--max-range".into(),
        s(cfg.max_range),
        if cfg.deskew {
            "--deskew"
        } else {
            "--no-deskew"
        }
        .into(),
        "--out".into(),
        arg(&pick.pre)?,
    ];
    if let Some(st) = &stamps {
        c.push("--timestamps".into());
        c.push(arg(&driver.write_f64s(&format!("stamps{k}.f64"), st)?)?);
    }
    let cmds = vec![
        c,
        downsample_cmd(&pick.pre, cfg.voxel_size * cfg.alpha, &pick.merge)?,
        downsample_cmd(&pick.merge, cfg.voxel_size * cfg.beta, &pick.source)?,
    ];
    Ok((Pick { stamps, ..pick }, cmds))
}

/// The reference's threshold over the model deviations, and the file its sigmas go to.
fn threshold_command(
    driver: &mut Driver,
    cfg: &Config<f64>,
    deviations: &[Isometry3<f64>],
) -> Result<(Vec<String>, PathBuf)> {
    let values: Vec<f64> = deviations
        .iter()
        .flat_map(|d| {
            let m = d.to_homogeneous();
            (0..16).map(move |i| m[(i / 4, i % 4)])
        })
        .collect();
    let input = driver.write_f64s("deviations.f64", &values)?;
    let out = driver.file("sigmas.f64");
    let cmd = vec![
        "threshold".into(),
        "--deviations".into(),
        arg(&input)?,
        "--initial-threshold".into(),
        s(cfg.initial_threshold),
        "--min-motion".into(),
        s(cfg.min_motion_threshold),
        "--max-range".into(),
        s(cfg.max_range),
        "--out".into(),
        arg(&out)?,
    ];
    Ok((cmd, out))
}

/// Preprocessing and both downsampling passes of every picked frame against the reference's;
/// also gives the reference's registration clouds.
#[allow(clippy::type_complexity)]
fn front_stages(
    inp: &SequenceInput,
    cfg: &Config<f64>,
    picked: &[Pick],
    label: &dyn Fn(usize) -> String,
) -> Result<(Section, Section, Vec<(usize, Vec<[f64; 3]>)>)> {
    let (alpha_v, beta_v) = (cfg.voxel_size * cfg.alpha, cfg.voxel_size * cfg.beta);
    let mut pre_sec = Section::new("stage checks: preprocessing (f64 build)");
    let mut ds_sec = Section::new("stage checks: voxel downsampling (f64 build)");
    let mut ref_sources = Vec::new();
    for p in picked {
        let f = &inp.frames[p.k];
        let want = read_points(&p.pre)?;
        let mut out = vec![[0.0; 3]; f.points.len()];
        let r = preprocess(
            &f.points,
            p.stamps.as_deref(),
            &p.motion,
            cfg.min_range,
            cfg.max_range,
            cfg.deskew,
            &mut out,
        );
        let what = format!(
            "{}crop {}..{} m, {}",
            if r.deskewed { "deskew + " } else { "" },
            cfg.min_range,
            cfg.max_range,
            label(p.k)
        );
        pre_sec.push(points_row(
            &what,
            &out[..r.kept.min(out.len())],
            &want,
            TOL_PREPROCESS_M,
        ));

        let merge_ref = read_points(&p.merge)?;
        let source_ref = read_points(&p.source)?;
        let merge_ours = downsample(&want, alpha_v)?;
        let source_ours = downsample(&merge_ref, beta_v)?;
        let passes = format!("{alpha_v} m then {beta_v} m, {}", label(p.k));
        let differ =
            set_difference(&merge_ours, &merge_ref) + set_difference(&source_ours, &source_ref);
        ds_sec.push(Row::none_differ(
            format!("{passes}: same points"),
            differ,
            merge_ref.len() + source_ref.len(),
            "points",
        ));
        let order =
            order_difference(&merge_ours, &merge_ref) + order_difference(&source_ours, &source_ref);
        ds_sec.push(Row::report(
            format!("{passes}: same order"),
            if order == 0 {
                format!(
                    "identical ({} + {} points), as the core claims",
                    merge_ref.len(),
                    source_ref.len()
                )
            } else {
                format!("{order} positions differ: the core's order claim does not hold")
            },
        ));
        ref_sources.push((p.k, source_ref));
    }
    Ok((pre_sec, ds_sec, ref_sources))
}

/// The adaptive threshold over the reference run's model deviations against its sigmas.
fn threshold(cfg: &Config<f64>, deviations: &[Isometry3<f64>], want: &[f64]) -> Section {
    let mut th = AdaptiveThreshold::new(
        cfg.initial_threshold,
        cfg.min_motion_threshold,
        cfg.max_range,
    );
    let mut ours = vec![th.sigma()];
    for d in deviations {
        th.update(d);
        ours.push(th.sigma());
    }
    let mut sec = Section::new("stage checks: adaptive threshold (f64 build)");
    let what = format!(
        "sigma over the reference run's {} model deviations ({} counted), relative",
        deviations.len(),
        th.samples() - 1
    );
    if ours.len() == want.len() {
        let worst = ours
            .iter()
            .zip(want)
            .map(|(a, b)| ((a - b) / b).abs())
            .fold(0.0, f64::max);
        sec.push(Row::bound(what, worst, TOL_SIGMA_REL, ""));
    } else {
        sec.push(Row::broken(
            what,
            format!("{} vs {} values", ours.len(), want.len()),
            "same sequence",
        ));
    }
    sec
}
