//! Loose scans with per-point capture times (`raw_NN.bin` f32 x y z, `times_NN.bin` f32
//! seconds, as in `ncd-ouster-deskew`): not a sequence, so the check is deskewing real sensor
//! timing with a relative motion given to both implementations, then downsampling the result.

use super::compare::{order_difference, set_difference};
use super::driver::{arg, pose_arg, read_points, Driver};
use super::report::{Row, Section};
use super::stage_kit::{downsample, downsample_cmd, points_row, TOL_REAL_DESKEW_M};
use anyhow::{bail, Context, Result};
use kiss_odom_core::stages::preprocess;
use kiss_odom_drive::settings::Settings;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::path::{Path, PathBuf};

/// One scan: its number and the two files.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScanFiles {
    /// `NN` of the file names.
    pub number: String,
    /// `raw_NN.bin`.
    pub raw: PathBuf,
    /// `times_NN.bin`.
    pub times: PathBuf,
}

/// The `raw_NN.bin` + `times_NN.bin` pairs in `dir`, by number; empty if it has none (then it
/// is a sequence, not loose scans).
pub fn find(dir: &Path) -> Vec<ScanFiles> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut out: Vec<ScanFiles> = entries
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let name = e.file_name().into_string().ok()?;
            let number = name.strip_prefix("raw_")?.strip_suffix(".bin")?.to_string();
            let times = dir.join(format!("times_{number}.bin"));
            times.is_file().then(|| ScanFiles {
                number,
                raw: e.path(),
                times,
            })
        })
        .collect();
    out.sort_by(|a, b| kiss_odom_io::folders::listing::natural_cmp(&a.number, &b.number));
    out
}

/// The default relative motion: 0.5 m forward, 0.1 rad yaw, a little pitch and roll (the
/// motion the stage goldens use).
pub fn default_motion() -> Isometry3<f64> {
    let r = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.1)
        * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 0.02)
        * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), -0.01);
    Isometry3::from_parts(Translation3::new(0.5, 0.03, -0.02), r)
}

fn f32s(path: &Path) -> Result<Vec<f64>> {
    let bytes = std::fs::read(path).with_context(|| format!("{}", path.display()))?;
    if bytes.len() % 4 != 0 {
        bail!("{}: not a whole number of f32", path.display());
    }
    Ok(bytes
        .chunks_exact(4)
        .map(|c| f64::from(f32::from_le_bytes([c[0], c[1], c[2], c[3]])))
        .collect())
}

/// Reads one scan: points and times, both widened from f32 (exact).
pub fn read(scan: &ScanFiles) -> Result<(Vec<[f64; 3]>, Vec<f64>)> {
    let xyz = f32s(&scan.raw)?;
    if xyz.len() % 3 != 0 {
        bail!("{}: not a whole number of x y z points", scan.raw.display());
    }
    let points: Vec<[f64; 3]> = xyz.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let times = f32s(&scan.times)?;
    if times.len() != points.len() {
        bail!(
            "{}: {} times for {} points",
            scan.times.display(),
            times.len(),
            points.len()
        );
    }
    Ok((points, times))
}

/// The crop of the scans check unless ranges are given: one that removes points from a
/// handheld indoor/outdoor scan (the goldens' second crop), so it is tested.
pub const DEFAULT_CROP: (f64, f64) = (2.5, 30.0);

/// Deskew (no crop), deskew with the `crop` (min, max range), and both downsampling passes of
/// the reference's deskewed scan, for every scan.
pub fn scan_stages(
    driver: &mut Driver,
    scans: &[ScanFiles],
    motion: &Isometry3<f64>,
    crop: (f64, f64),
    settings: &Settings,
) -> Result<Vec<Section>> {
    let cfg = settings.core_config::<f64>()?;
    let alpha_v = cfg.voxel_size * cfg.alpha;
    let beta_v = cfg.voxel_size * cfg.beta;
    let mut cmds = Vec::new();
    let mut io = Vec::new();
    for sc in scans {
        let (points, times) = read(sc)?;
        let pf = driver.write_points(&format!("raw{}.f64", sc.number), &points)?;
        let tf = driver.write_f64s(&format!("times{}.f64", sc.number), &times)?;
        let deskewed = driver.file(&format!("deskewed{}.f64", sc.number));
        let cropped = driver.file(&format!("cropped{}.f64", sc.number));
        let merge = driver.file(&format!("merge{}.f64", sc.number));
        let source = driver.file(&format!("source{}.f64", sc.number));
        let common = [
            "--points".to_string(),
            arg(&pf)?,
            "--timestamps".into(),
            arg(&tf)?,
            "--motion".into(),
            pose_arg(motion),
        ];
        let mut c = vec!["deskew".to_string()];
        c.extend(common.iter().cloned());
        c.extend(["--out".into(), arg(&deskewed)?]);
        cmds.push(c);
        let mut c = vec!["preprocess".to_string()];
        c.extend(common.iter().cloned());
        c.extend([
            "--min-range".into(),
            format!("{:?}", crop.0),
            "--max-range".into(),
            format!("{:?}", crop.1),
            "--deskew".into(),
            "--out".into(),
            arg(&cropped)?,
        ]);
        cmds.push(c);
        cmds.push(downsample_cmd(&deskewed, alpha_v, &merge)?);
        cmds.push(downsample_cmd(&merge, beta_v, &source)?);
        io.push((sc, points, times, deskewed, cropped, merge, source));
    }
    driver.batch(&cmds).context("reference deskewing")?;

    let mut desk = Section::new(format!(
        "stage checks: deskewing real sensor timing (f64 build; relative motion {:.3} m, {:.3} rad)",
        motion.translation.vector.norm(),
        kiss_odom_core::stages::rotation_angle(&motion.rotation)
    ));
    let mut ds = Section::new("stage checks: voxel downsampling of the deskewed scans (f64 build)");
    for (sc, points, times, deskewed, cropped, merge, source) in io {
        let name = sc
            .raw
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        let mut out = vec![[0.0; 3]; points.len()];
        let r = preprocess(&points, Some(&times), motion, -1.0, 1e300, true, &mut out);
        if !r.deskewed {
            desk.push(Row::broken(
                format!("deskew {name}"),
                format!("timestamps not used: {:?}", r.stamp_problem),
                "deskewed",
            ));
            continue;
        }
        let want = read_points(&deskewed)?;
        desk.push(points_row(
            &format!("deskew {name} (no crop)"),
            &out[..r.kept.min(out.len())],
            &want,
            TOL_REAL_DESKEW_M,
        ));
        let r = preprocess(
            &points,
            Some(&times),
            motion,
            crop.0,
            crop.1,
            true,
            &mut out,
        );
        let want_c = read_points(&cropped)?;
        desk.push(points_row(
            &format!("deskew + crop {}..{} m {name}", crop.0, crop.1),
            &out[..r.kept.min(out.len())],
            &want_c,
            TOL_REAL_DESKEW_M,
        ));

        let merge_ref = read_points(&merge)?;
        let source_ref = read_points(&source)?;
        let merge_ours = downsample(&want, alpha_v)?;
        let source_ours = downsample(&merge_ref, beta_v)?;
        ds.push(Row::none_differ(
            format!("{alpha_v} m then {beta_v} m, {name}: same points"),
            set_difference(&merge_ours, &merge_ref) + set_difference(&source_ours, &source_ref),
            merge_ref.len() + source_ref.len(),
            "points",
        ));
        let order =
            order_difference(&merge_ours, &merge_ref) + order_difference(&source_ours, &source_ref);
        ds.push(Row::report(
            format!("{alpha_v} m then {beta_v} m, {name}: same order"),
            if order == 0 {
                "identical, as the core claims".into()
            } else {
                format!("{order} positions differ: the core's order claim does not hold")
            },
        ));
    }
    Ok(vec![desk, ds])
}
