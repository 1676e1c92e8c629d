//! Stage checks around a pair of frames `(a, b)` in motion: the local map after updates at
//! the reference's poses, the correspondences of frame `b` in the reference's own map, and full
//! registrations of `b` from identical map, scan and guess (from the prediction and from a
//! perturbed one).

use super::compare::{bits, heap_map, map_points, matched_distance, HeapMap};
use super::driver::{arg, pose_arg, read_json, read_points, Driver};
use super::report::{sci, Row, Section};
use super::stage_kit::{
    delta_before, downsample, map_cmd, matrix_of, perturbation, s, SequenceInput, MAP_FRAMES,
    TOL_MAP_M, TOL_REGISTRATION,
};
use anyhow::{Context, Result};
use kiss_odom_core::stages::{align_points_to_map, preprocess, work_words, IcpParams};
use kiss_odom_core::{Config, Point, Sequential};
use kiss_odom_io::pose::{pose_difference, pose_of};
use nalgebra::Isometry3;
use std::path::PathBuf;

/// A registration run: what it starts from, its guess and sigma, the reference's output file.
struct Registration {
    what: &'static str,
    guess: Isometry3<f64>,
    sigma: f64,
    out: PathBuf,
}

/// Map update, correspondences and registration around the frame pair `(a, b)`.
pub fn map_and_registration(
    driver: &mut Driver,
    inp: &SequenceInput,
    cfg: &Config<f64>,
    a: usize,
    b: usize,
    source_b: &[[f64; 3]],
    label: &dyn Fn(usize) -> String,
) -> Result<Section> {
    let first = (a + 1).saturating_sub(MAP_FRAMES);
    let (merges, map_cmd, dump) = map_command(driver, inp, cfg, first, a)?;
    let sigma = inp.ref_sigmas[b];
    let guess = inp.ref_poses[a] * delta_before(inp.ref_poses, b);
    let queries: Vec<[f64; 3]> = source_b
        .iter()
        .map(|p| {
            let q = guess * Point::from(*p);
            [q.x, q.y, q.z]
        })
        .collect();
    let (corr_cmd, pairs, pairs_map) = correspondence_command(driver, cfg, &dump, &queries, sigma)?;
    let runs = [
        ("from the prediction", guess, sigma),
        (
            "from a perturbed prediction",
            perturbation() * guess,
            cfg.initial_threshold,
        ),
    ];
    let (reg_cmds, registrations) = registration_commands(driver, cfg, &dump, source_b, &runs)?;
    let mut cmds = vec![map_cmd, corr_cmd];
    cmds.extend(reg_cmds);
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
    let ref_map = read_points(&dump)?;
    sec.push(map_row(cfg, &merges, &ref_map, &maps)?);
    // Correspondences and registrations against the reference's map, rebuilt from its dump.
    let mut map =
        heap_map(cfg, ref_map.len()).map_err(|e| anyhow::anyhow!("cannot build a map: {e}"))?;
    let added = map
        .add_points(ref_map.iter().map(|p| Point::from(*p)))
        .added;
    let what = format!(
        "correspondences of {} (tau = 3 sigma = {:.3} m) in the map of {maps}",
        label(b),
        3.0 * sigma
    );
    if added != ref_map.len() {
        sec.push(Row::broken(
            what,
            format!("map rebuilt with {added} of {} points", ref_map.len()),
            "identical pairs",
        ));
    } else {
        let corr = (&pairs, &pairs_map);
        sec.rows.extend(correspondence_rows(
            &map,
            &queries,
            corr,
            3.0 * sigma,
            what,
        )?);
    }
    for r in &registrations {
        sec.rows
            .extend(registration_rows(cfg, &map, source_b, r, &label(b))?);
    }
    Ok(sec)
}

/// The map frames' merge clouds, made by our stages (checked on some frames already) so that
/// both sides get the same files, and the reference's command that updates a map with them.
#[allow(clippy::type_complexity)]
fn map_command(
    driver: &mut Driver,
    inp: &SequenceInput,
    cfg: &Config<f64>,
    first: usize,
    a: usize,
) -> Result<(Vec<(Vec<[f64; 3]>, Isometry3<f64>)>, Vec<String>, PathBuf)> {
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
        let merge = downsample(&pre[..r.kept], cfg.voxel_size * cfg.alpha)?;
        let file = driver.write_points(&format!("mapmerge{w}.f64"), &merge)?;
        cmd.extend(["--update".into(), arg(&file)?, pose_arg(&inp.ref_poses[w])]);
        merges.push((merge, inp.ref_poses[w]));
    }
    let dump = driver.file("map.f64");
    cmd.extend(["--out".into(), arg(&dump)?]);
    Ok((merges, cmd, dump))
}

/// The reference's correspondences of `queries` in its map `dump`, and their two output files.
fn correspondence_command(
    driver: &mut Driver,
    cfg: &Config<f64>,
    dump: &std::path::Path,
    queries: &[[f64; 3]],
    sigma: f64,
) -> Result<(Vec<String>, PathBuf, PathBuf)> {
    let qfile = driver.write_points("queries.f64", queries)?;
    let pairs = driver.file("pairs.json");
    let pairs_map = driver.file("pairs_map.f64");
    let mut corr = map_cmd(cfg, "correspondences");
    corr.extend([
        "--map-points".into(),
        arg(dump)?,
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
    Ok((corr, pairs, pairs_map))
}

/// The reference's registrations of `source` in its map `dump`, one per run.
fn registration_commands(
    driver: &mut Driver,
    cfg: &Config<f64>,
    dump: &std::path::Path,
    source: &[[f64; 3]],
    runs: &[(&'static str, Isometry3<f64>, f64)],
) -> Result<(Vec<Vec<String>>, Vec<Registration>)> {
    let sfile = driver.write_points("source_b.f64", source)?;
    let mut cmds = Vec::new();
    let mut registrations = Vec::new();
    for (i, &(what, guess, sigma)) in runs.iter().enumerate() {
        let out = driver.file(&format!("register{i}.json"));
        let mut c = map_cmd(cfg, "register");
        c.extend([
            "--map-points".into(),
            arg(dump)?,
            "--points".into(),
            arg(&sfile)?,
            "--initial-guess".into(),
            pose_arg(&guess),
            "--sigma".into(),
            s(sigma),
            "--max-iterations".into(),
            cfg.max_iterations.to_string(),
            "--convergence".into(),
            s(cfg.convergence_criterion),
            "--out".into(),
            arg(&out)?,
        ]);
        cmds.push(c);
        registrations.push(Registration {
            what,
            guess,
            sigma,
            out,
        });
    }
    Ok((cmds, registrations))
}

/// Our map after the same updates (add, then prune) at the reference's poses, against its dump.
fn map_row(
    cfg: &Config<f64>,
    merges: &[(Vec<[f64; 3]>, Isometry3<f64>)],
    ref_map: &[[f64; 3]],
    maps: &str,
) -> Result<Row> {
    let total: usize = merges.iter().map(|(m, _)| m.len()).sum();
    let mut map = heap_map(cfg, total).map_err(|e| anyhow::anyhow!("cannot build a map: {e}"))?;
    let mut full = 0;
    for (m, pose) in merges {
        let st = map.update(m, pose);
        full += st.dropped_points + st.dropped_voxels;
    }
    let ours = map_points(&map);
    let what = format!("map after updates with {maps} at the reference poses");
    Ok(
        match matched_distance(&ours, ref_map, 1e-3).filter(|_| full == 0) {
            Some(d) => Row::check(
                what,
                d,
                TOL_MAP_M,
                format!("{} points, worst {} m", ref_map.len(), sci(d)),
                format!("same points, <= {} m", sci(TOL_MAP_M)),
            ),
            None => Row::broken(
                what,
                format!("{} vs {} points", ours.len(), ref_map.len()),
                "same points",
            ),
        },
    )
}

/// Our correspondences of `queries` within `tau` against the reference's pairs (`files`: its
/// pairs and the map points they index), and the reference's own validation.
fn correspondence_rows(
    map: &HeapMap,
    queries: &[[f64; 3]],
    (pairs, pairs_map): (&PathBuf, &PathBuf),
    tau: f64,
    what: String,
) -> Result<Vec<Row>> {
    let pj = read_json(pairs)?;
    let cloud = read_points(pairs_map)?;
    let index: Vec<i64> = pj["index"]
        .as_array()
        .map(|v| v.iter().map(|x| x.as_i64().unwrap_or(-2)).collect())
        .unwrap_or_default();
    if index.len() != queries.len() {
        return Ok(vec![Row::broken(
            what,
            format!("{} pairs for {} queries", index.len(), queries.len()),
            "identical pairs",
        )]);
    }
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
    let v = &pj["validation"];
    let num = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    Ok(vec![
        Row::none_differ(
            format!("{what}, {pairs_n} pairs"),
            differ,
            queries.len(),
            "queries",
        ),
        Row::report(
            "reference pairs (a port of GetClosestNeighbor) validated against the C++",
            format!(
                "one GN step agrees to {} m / {} rad; any single-pair change moves it >= {}",
                sci(num("translation_disagreement_m")),
                sci(num("rotation_disagreement_rad")),
                sci(num("smallest_single_pair_change"))
            ),
        ),
    ])
}

/// Our registration of `source` from the run's guess against the reference's.
fn registration_rows(
    cfg: &Config<f64>,
    map: &HeapMap,
    source: &[[f64; 3]],
    r: &Registration,
    frame: &str,
) -> Result<Vec<Row>> {
    let params = IcpParams {
        convergence_criterion: cfg.convergence_criterion,
        max_iterations: cfg.max_iterations,
        budget: None,
        planes: false,
        prior: None,
        stop_on_cycle: false,
    };
    let want = pose_of(&matrix_of(&read_json(&r.out)?["pose"])?);
    let mut work = vec![0u64; work_words::<f64>(source.len(), false)];
    let al = align_points_to_map(
        &Sequential,
        source,
        &mut work,
        &map.view(),
        &r.guess,
        cfg.max_correspondence_factor * r.sigma,
        cfg.kernel_scale * r.sigma,
        &params,
    );
    let (dt, dr) = pose_difference(&want, &al.pose);
    let name = format!(
        "registration of {frame} {}, sigma {:.4} m ({} iterations, {} pairs)",
        r.what, r.sigma, al.iterations, al.correspondences
    );
    Ok(vec![
        Row::bound(format!("{name}: translation"), dt, TOL_REGISTRATION, "m"),
        Row::bound(format!("{name}: rotation"), dr, TOL_REGISTRATION, "rad"),
    ])
}
