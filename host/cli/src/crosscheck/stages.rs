//! Stage checks: each of the core's stage APIs against the matching reference entry point,
//! fed identical inputs taken from a few frames of the dataset.
//!
//! Every stage gets the reference's own output of the stage before it, so a disagreement is
//! attributed to the stage that made it: preprocessing (crop, and deskew when the frames have
//! per-point times) of raw frames; both downsampling passes of the reference's preprocessed
//! frame; the local map after updates at the reference's poses; correspondences and a full
//! registration against the reference's own map; the adaptive threshold over the model
//! deviations of the reference's run.

use super::compare::{
    bits, heap_map, map_points, matched_distance, max_point_difference, order_difference,
    set_difference,
};
use super::driver::{arg, pose_arg, read_f64s, read_json, read_points, Driver};
use super::report::{sci, Row, Section};
use anyhow::{Context, Result};
use kiss_odom_core::stages::{
    align_points_to_map, preprocess, scratch_words_for, voxel_downsample, work_words,
    AdaptiveThreshold, IcpParams,
};
use kiss_odom_core::{Config, Point, Sequential};
use kiss_odom_drive::settings::Settings;
use kiss_odom_io::pose::{pose_difference, pose_of};
use kiss_odom_io::Frame;
use nalgebra::{Isometry3, Matrix4, Translation3, UnitQuaternion, Vector3};
use std::path::PathBuf;

/// Tolerance of cropping and deskewing with synthetic or no timing (m).
pub const TOL_PREPROCESS_M: f64 = 1e-9;
/// Tolerance of deskewing real sensor timing (m).
pub const TOL_REAL_DESKEW_M: f64 = 1e-6;
/// Tolerance of one registration from identical inputs (m and rad).
pub const TOL_REGISTRATION: f64 = 1e-6;
/// Tolerance of the adaptive threshold's sigma, relative, per frame.
pub const TOL_SIGMA_REL: f64 = 1e-9;
/// Tolerance of map point coordinates (each side transforms the points itself) (m).
pub const TOL_MAP_M: f64 = 1e-9;
/// Frames of map history the map, correspondence and registration checks use.
const MAP_FRAMES: usize = 5;
/// The perturbation of the second registration: a few cm and 0.5 degree off the prediction.
fn perturbation() -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(0.04, -0.03, 0.02),
        UnitQuaternion::from_axis_angle(
            &nalgebra::Unit::new_normalize(Vector3::new(0.3, -0.5, 0.8)),
            0.5f64.to_radians(),
        ),
    )
}

/// What the stage checks of a sequence start from.
pub struct SequenceInput<'a> {
    /// The selected frames, preloaded (sensor frame, KITTI-corrected where that applies).
    pub frames: &'a [Frame],
    /// The reference's poses for (at least) the first frames.
    pub ref_poses: &'a [Isometry3<f64>],
    /// The reference's sigma before each frame.
    pub ref_sigmas: &'a [f64],
    /// Settings shared by both implementations.
    pub settings: &'a Settings,
}

/// The reference's constant-velocity model before frame `k`: the last relative motion.
fn delta_before(poses: &[Isometry3<f64>], k: usize) -> Isometry3<f64> {
    if k < 2 {
        Isometry3::identity()
    } else {
        poses[k - 2].inverse() * poses[k - 1]
    }
}

/// The model deviation of every frame of a run, from its poses (the first is the identity).
pub fn model_deviations(poses: &[Isometry3<f64>]) -> Vec<Isometry3<f64>> {
    (0..poses.len())
        .map(|k| {
            if k == 0 {
                Isometry3::identity()
            } else {
                let prediction = poses[k - 1] * delta_before(poses, k);
                prediction.inverse() * poses[k]
            }
        })
        .collect()
}

fn s(v: f64) -> String {
    format!("{v:?}")
}

/// Which stage frames: the first, and a pair `(b - 1, b)` with `b` the middle frame of the
/// run, but at least frame 9 (or the last): in motion, with a few frames of map behind it.
pub fn stage_frames(n: usize) -> (Vec<usize>, Option<(usize, usize)>) {
    if n == 0 {
        return (vec![], None);
    }
    let b = (n - 1).min(9).max(n / 2);
    if b == 0 {
        return (vec![0], None);
    }
    let mut picks = vec![0, b - 1, b];
    picks.dedup();
    (picks, Some((b - 1, b)))
}

/// Frames the stage checks need reference poses for.
pub fn frames_needed(n: usize) -> usize {
    stage_frames(n).0.last().map_or(0, |b| b + 1)
}

/// Runs the stage checks of a sequence; `label(k)` names frame `k` for the table.
pub fn sequence_stages(
    driver: &mut Driver,
    inp: &SequenceInput,
    label: &dyn Fn(usize) -> String,
) -> Result<Vec<Section>> {
    let cfg = inp.settings.core_config::<f64>()?;
    let (picks, pair) = stage_frames(inp.frames.len());
    let alpha_v = cfg.voxel_size * cfg.alpha;
    let beta_v = cfg.voxel_size * cfg.beta;

    // Batch 1: preprocessing and both downsampling passes of each picked frame, the threshold.
    struct Pick {
        k: usize,
        stamps: Option<Vec<f64>>,
        motion: Isometry3<f64>,
        pre: PathBuf,
        merge: PathBuf,
        source: PathBuf,
    }
    let mut cmds: Vec<Vec<String>> = Vec::new();
    let mut pk = Vec::new();
    for &k in &picks {
        let f = &inp.frames[k];
        let points = driver.write_points(&format!("frame{k}.f64"), &f.points)?;
        let stamps = f.stamps.clone().filter(|_| cfg.deskew);
        let motion = delta_before(inp.ref_poses, k);
        let pre = driver.file(&format!("pre{k}.f64"));
        let merge = driver.file(&format!("merge{k}.f64"));
        let source = driver.file(&format!("source{k}.f64"));
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
            arg(&pre)?,
        ];
        if let Some(st) = &stamps {
            c.push("--timestamps".into());
            c.push(arg(&driver.write_f64s(&format!("stamps{k}.f64"), st)?)?);
        }
        cmds.push(c);
        cmds.push(downsample_cmd(&pre, alpha_v, &merge)?);
        cmds.push(downsample_cmd(&merge, beta_v, &source)?);
        pk.push(Pick {
            k,
            stamps,
            motion,
            pre,
            merge,
            source,
        });
    }
    let deviations = model_deviations(inp.ref_poses);
    let dev_values: Vec<f64> = deviations
        .iter()
        .flat_map(|d| {
            let m = d.to_homogeneous();
            (0..16).map(move |i| m[(i / 4, i % 4)])
        })
        .collect();
    let dev_file = driver.write_f64s("deviations.f64", &dev_values)?;
    let sig_file = driver.file("sigmas.f64");
    cmds.push(vec![
        "threshold".into(),
        "--deviations".into(),
        arg(&dev_file)?,
        "--initial-threshold".into(),
        s(cfg.initial_threshold),
        "--min-motion".into(),
        s(cfg.min_motion_threshold),
        "--max-range".into(),
        s(cfg.max_range),
        "--out".into(),
        arg(&sig_file)?,
    ]);
    driver.batch(&cmds).context("reference stages")?;

    let mut pre_sec = Section::new("stage checks: preprocessing (f64 build)");
    let mut ds_sec = Section::new("stage checks: voxel downsampling (f64 build)");
    let mut ref_sources = Vec::new();
    for p in &pk {
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
        let what = if r.deskewed {
            format!(
                "deskew + crop {}..{} m, {}",
                cfg.min_range,
                cfg.max_range,
                label(p.k)
            )
        } else {
            format!(
                "crop {}..{} m, {}",
                cfg.min_range,
                cfg.max_range,
                label(p.k)
            )
        };
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
        let differ =
            set_difference(&merge_ours, &merge_ref) + set_difference(&source_ours, &source_ref);
        ds_sec.push(Row::none_differ(
            format!("{alpha_v} m then {beta_v} m, {}: same points", label(p.k)),
            differ,
            merge_ref.len() + source_ref.len(),
            "points",
        ));
        let order =
            order_difference(&merge_ours, &merge_ref) + order_difference(&source_ours, &source_ref);
        ds_sec.push(Row::report(
            format!("{alpha_v} m then {beta_v} m, {}: same order", label(p.k)),
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

    let mut sections = vec![pre_sec, ds_sec];
    if let Some((a, b)) = pair {
        let source_b = ref_sources
            .iter()
            .find(|(k, _)| *k == b)
            .map(|(_, s)| s.clone())
            .unwrap_or_default();
        sections.push(map_and_registration(
            driver, inp, &cfg, a, b, &source_b, label,
        )?);
    }

    // The threshold over the reference run's deviations.
    let want = read_f64s(&sig_file)?;
    let mut th = AdaptiveThreshold::new(
        cfg.initial_threshold,
        cfg.min_motion_threshold,
        cfg.max_range,
    );
    let mut ours = vec![th.sigma()];
    for d in &deviations {
        th.update(d);
        ours.push(th.sigma());
    }
    let mut th_sec = Section::new("stage checks: adaptive threshold (f64 build)");
    let what = format!(
        "sigma over the reference run's {} model deviations ({} counted), relative",
        deviations.len(),
        th.samples() - 1
    );
    if ours.len() == want.len() {
        let worst = ours
            .iter()
            .zip(&want)
            .map(|(a, b)| ((a - b) / b).abs())
            .fold(0.0, f64::max);
        th_sec.push(Row::bound(what, worst, TOL_SIGMA_REL, ""));
    } else {
        th_sec.push(Row::broken(
            what,
            format!("{} vs {} values", ours.len(), want.len()),
            "same sequence",
        ));
    }
    sections.push(th_sec);
    Ok(sections)
}

/// Map update, correspondences and registration around the frame pair `(a, b)`.
fn map_and_registration(
    driver: &mut Driver,
    inp: &SequenceInput,
    cfg: &Config<f64>,
    a: usize,
    b: usize,
    source_b: &[[f64; 3]],
    label: &dyn Fn(usize) -> String,
) -> Result<Section> {
    let alpha_v = cfg.voxel_size * cfg.alpha;
    let first = (a + 1).saturating_sub(MAP_FRAMES);
    // The merge clouds of the map frames, made by our stages (checked above on some frames);
    // both sides get the same files.
    let mut merges = Vec::new();
    let mut cmd = map_cmd(cfg, "map");
    for w in first..=a {
        let f = &inp.frames[w];
        let stamps = f.stamps.as_deref().filter(|_| cfg.deskew);
        let mut pre = vec![[0.0; 3]; f.points.len()];
        let r = preprocess(
            &f.points,
            stamps,
            &delta_before(inp.ref_poses, w),
            cfg.min_range,
            cfg.max_range,
            cfg.deskew,
            &mut pre,
        );
        let merge = downsample(&pre[..r.kept], alpha_v)?;
        let file = driver.write_points(&format!("mapmerge{w}.f64"), &merge)?;
        cmd.extend(["--update".into(), arg(&file)?, pose_arg(&inp.ref_poses[w])]);
        merges.push((merge, inp.ref_poses[w]));
    }
    let dump = driver.file("map.f64");
    cmd.extend(["--out".into(), arg(&dump)?]);

    let sigma = inp.ref_sigmas[b];
    let guess = inp.ref_poses[a] * delta_before(inp.ref_poses, b);
    let queries: Vec<[f64; 3]> = source_b
        .iter()
        .map(|p| {
            let q = guess * Point::from(*p);
            [q.x, q.y, q.z]
        })
        .collect();
    let qfile = driver.write_points("queries.f64", &queries)?;
    let sfile = driver.write_points("source_b.f64", source_b)?;
    let pairs = driver.file("pairs.json");
    let pairs_map = driver.file("pairs_map.f64");
    let mut corr = map_cmd(cfg, "correspondences");
    corr.extend([
        "--map-points".into(),
        arg(&dump)?,
        "--queries".into(),
        arg(&qfile)?,
        "--max-corr-distance".into(),
        s(3.0 * sigma),
        "--kernel".into(),
        s(sigma),
        "--out".into(),
        arg(&pairs)?,
        "--out-map".into(),
        arg(&pairs_map)?,
    ]);
    let perturbed = perturbation() * guess;
    let runs = [
        ("from the prediction", guess, sigma),
        (
            "from a perturbed prediction",
            perturbed,
            cfg.initial_threshold,
        ),
    ];
    let mut cmds = vec![cmd, corr];
    let mut reg_files = Vec::new();
    for (i, (_, g, sg)) in runs.iter().enumerate() {
        let out = driver.file(&format!("register{i}.json"));
        let mut c = map_cmd(cfg, "register");
        c.extend([
            "--map-points".into(),
            arg(&dump)?,
            "--points".into(),
            arg(&sfile)?,
            "--initial-guess".into(),
            pose_arg(g),
            "--sigma".into(),
            s(*sg),
            "--max-iterations".into(),
            cfg.max_iterations.to_string(),
            "--convergence".into(),
            s(cfg.convergence_criterion),
            "--out".into(),
            arg(&out)?,
        ]);
        cmds.push(c);
        reg_files.push(out);
    }
    driver
        .batch(&cmds)
        .context("reference map, correspondences and registration")?;

    let mut sec =
        Section::new("stage checks: local map, correspondences, registration (f64 build)");
    let maps = if first == a {
        label(a)
    } else {
        format!("{} to {}", label(first), label(a))
    };

    // Map: updates (add, then prune) at the reference's poses.
    let ref_map = read_points(&dump)?;
    let total: usize = merges.iter().map(|(m, _)| m.len()).sum();
    let mut map = heap_map(cfg, total).map_err(|e| anyhow::anyhow!("cannot build a map: {e}"))?;
    let mut full = 0;
    for (m, pose) in &merges {
        let st = map.update(m, pose);
        full += st.dropped_points + st.dropped_voxels;
    }
    let ours = map_points(&map);
    let what = format!("map after updates with {maps} at the reference poses");
    match matched_distance(&ours, &ref_map, 1e-3).filter(|_| full == 0) {
        Some(d) => sec.push(Row::check(
            what,
            d,
            TOL_MAP_M,
            format!("{} points, worst {} m", ref_map.len(), sci(d)),
            format!("same points, <= {} m", sci(TOL_MAP_M)),
        )),
        None => sec.push(Row::broken(
            what,
            format!("{} vs {} points", ours.len(), ref_map.len()),
            "same points",
        )),
    }

    // Correspondences against the reference's map, rebuilt from its dump on both sides.
    let mut map =
        heap_map(cfg, ref_map.len()).map_err(|e| anyhow::anyhow!("cannot build a map: {e}"))?;
    let st = map.add_points(ref_map.iter().map(|p| Point::from(*p)));
    let rebuilt = st.added == ref_map.len();
    let pj = read_json(&pairs)?;
    let cloud = read_points(&pairs_map)?;
    let index: Vec<i64> = pj["index"]
        .as_array()
        .map(|v| v.iter().map(|x| x.as_i64().unwrap_or(-2)).collect())
        .unwrap_or_default();
    let tau = 3.0 * sigma;
    let what = format!(
        "correspondences of {} (tau = 3 sigma = {:.3} m) in the map of {maps}",
        label(b),
        tau
    );
    if !rebuilt || index.len() != queries.len() {
        sec.push(Row::broken(
            what,
            format!(
                "map rebuilt with {} of {} points; {} pairs for {} queries",
                st.added,
                ref_map.len(),
                index.len(),
                queries.len()
            ),
            "identical pairs",
        ));
    } else {
        let mut differ = 0;
        let mut pairs_n = 0;
        for (q, &w) in queries.iter().zip(&index) {
            let got = map.closest_neighbor(&Point::from(*q), tau);
            let same = match (got, w) {
                (None, -1) => true,
                (Some((p, _)), w) if w >= 0 => cloud
                    .get(w as usize)
                    .is_some_and(|t| bits(t) == bits(&[p.x, p.y, p.z])),
                _ => false,
            };
            pairs_n += usize::from(w >= 0);
            differ += usize::from(!same);
        }
        sec.push(Row::none_differ(
            format!("{what}, {pairs_n} pairs"),
            differ,
            queries.len(),
            "queries",
        ));
        let v = &pj["validation"];
        let num = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
        sec.push(Row::report(
            "reference pairs (a port of GetClosestNeighbor) validated against the C++",
            format!(
                "one GN step agrees to {} m / {} rad; any single-pair change moves it >= {}",
                sci(num("translation_disagreement_m")),
                sci(num("rotation_disagreement_rad")),
                sci(num("smallest_single_pair_change"))
            ),
        ));
    }

    // Full registrations from identical map, scan and guess.
    let params = IcpParams {
        convergence_criterion: cfg.convergence_criterion,
        max_iterations: cfg.max_iterations,
        budget: None,
        hold: None,
        planes: false,
        prior: None,
    };
    for ((what, g, sg), file) in runs.iter().zip(&reg_files) {
        let want = pose_of(&matrix_of(&read_json(file)?["pose"])?);
        let mut work = vec![0u64; work_words::<f64>(source_b.len(), false)];
        let al = align_points_to_map(
            &Sequential,
            source_b,
            &mut work,
            &map.view(),
            g,
            cfg.max_correspondence_factor * sg,
            cfg.kernel_scale * sg,
            &params,
        );
        let (dt, dr) = pose_difference(&want, &al.pose);
        let name = format!(
            "registration of {} {what}, sigma {:.4} m ({} iterations, {} pairs)",
            label(b),
            sg,
            al.iterations,
            al.correspondences
        );
        sec.push(Row::bound(
            format!("{name}: translation"),
            dt,
            TOL_REGISTRATION,
            "m",
        ));
        sec.push(Row::bound(
            format!("{name}: rotation"),
            dr,
            TOL_REGISTRATION,
            "rad",
        ));
    }
    Ok(sec)
}

fn matrix_of(v: &serde_json::Value) -> Result<Matrix4<f64>> {
    super::driver::matrix_from_json(v)
}

/// A map command with the map options of `cfg`.
fn map_cmd(cfg: &Config<f64>, command: &str) -> Vec<String> {
    vec![
        command.into(),
        "--voxel-size".into(),
        s(cfg.voxel_size),
        "--max-distance".into(),
        s(cfg.max_range),
        "--max-points-per-voxel".into(),
        cfg.max_points_per_voxel.to_string(),
    ]
}

/// `downsample --points IN --voxel V --out OUT`.
pub fn downsample_cmd(
    input: &std::path::Path,
    voxel: f64,
    out: &std::path::Path,
) -> Result<Vec<String>> {
    Ok(vec![
        "downsample".into(),
        "--points".into(),
        arg(input)?,
        "--voxel".into(),
        s(voxel),
        "--out".into(),
        arg(out)?,
    ])
}

/// Our voxel downsampling of `input`.
pub fn downsample(input: &[[f64; 3]], voxel: f64) -> Result<Vec<[f64; 3]>> {
    let mut out = vec![[0.0; 3]; input.len()];
    let mut scratch = vec![0u64; scratch_words_for(out.len())];
    let r = voxel_downsample(input, voxel, &mut out, &mut scratch)
        .ok_or_else(|| anyhow::anyhow!("downsampling scratch too small"))?;
    out.truncate(r.kept);
    Ok(out)
}

/// A row comparing two point lists position by position (same count required).
pub fn points_row(what: &str, ours: &[[f64; 3]], want: &[[f64; 3]], tol: f64) -> Row {
    if ours.len() != want.len() {
        return Row::broken(
            what,
            format!("{} vs {} points", ours.len(), want.len()),
            "same points",
        );
    }
    let d = max_point_difference(ours, want);
    Row::check(
        what,
        d,
        tol,
        format!("{} points, worst {} m", want.len(), sci(d)),
        format!("same points, <= {} m", sci(tol)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stage_frames_are_the_first_and_a_pair_in_motion() {
        assert_eq!(stage_frames(0), (vec![], None));
        assert_eq!(stage_frames(1), (vec![0], None));
        assert_eq!(stage_frames(2), (vec![0, 1], Some((0, 1))));
        assert_eq!(stage_frames(10), (vec![0, 8, 9], Some((8, 9))));
        assert_eq!(stage_frames(600), (vec![0, 299, 300], Some((299, 300))));
        assert_eq!(frames_needed(600), 301);
    }

    #[test]
    fn model_deviations_of_a_constant_velocity_run_vanish_after_the_second_frame() {
        let step = Isometry3::new(Vector3::new(1.0, 0.1, 0.0), Vector3::new(0.0, 0.0, 0.05));
        let mut poses = vec![Isometry3::identity()];
        for _ in 0..5 {
            let last = *poses.last().unwrap();
            poses.push(last * step);
        }
        let devs = model_deviations(&poses);
        assert_eq!(devs.len(), 6);
        // Frame 1 is predicted as standing still: its deviation is the whole step.
        assert!((devs[1].translation.vector - step.translation.vector).norm() < 1e-12);
        for d in &devs[2..] {
            assert!(d.translation.vector.norm() < 1e-12 && d.rotation.angle() < 1e-12);
        }
    }
}
