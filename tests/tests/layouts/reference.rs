//! kiss-icp 1.3.0's own dataloaders against ours on the shared drive. For each layout one
//! Python process (`tests/reference/dump_layout.py`, the Python in `KISS_ODOM_PYTHON`; the
//! nuScenes and Newer College loaders take `KISS_ODOM_NUMPY1_PYTHON` when it is set, a numpy
//! below 2 with nuscenes-devkit and pyntcloud) dumps what the loader read from every sequence
//! and runs kiss-icp's pipeline on the first. Where a loader's reading library cannot be used
//! (open3d, pyntcloud under numpy 2, nuscenes-devkit), the script puts a stand-in in its
//! place and the comparison says so: the loader's own code still orders the scans, builds the
//! times and the ground truth, and the points are read by the stand-in.

use super::{folder, index, name, options, simulated, FRAMES, LAYOUTS};
use crate::common::{run, RunExt};
use kiss_odom_io::layouts::rotation::{rebase_f32, Products};
use kiss_odom_io::layouts::{self, nuscenes};
use kiss_odom_io::{open, Format, Item};
use nalgebra::Matrix4;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// Per-point times computed in float64 from the same values (MulRan's and Newer College's
/// grid, HeLiPR's scaling) must agree exactly; times from `atan2` may differ by the last bit
/// of numpy's vectorised `arctan2` (float32 for Boreas, float64 for KITTI raw).
const STAMPS_F32_TOL: f64 = 2.0 * f32::EPSILON as f64;
const STAMPS_F64_TOL: f64 = 4.0 * f64::EPSILON;
/// Points are compared bit for bit, but for KITTI raw's vertical-angle correction, which
/// kiss-icp computes in C++ (Eigen) and kiss-odom in Rust: within 1e-12 m, as the KITTI
/// reader's own cross-check (`readers.rs`) allows.
const KITTI_CORRECTION_TOL: f64 = 1e-12;
/// Ground truth entries, computed in float64 by both.
const GT_TOL: f64 = 1e-9;
/// KITTI raw's, from pykitti's Mercator projection: its northing is about 4.1e6 m, where a
/// float64 step is 9.3e-10 m; four of them.
const GT_KITTI_RAW_TOL: f64 = 4.0 * 9.32e-10;
/// nuScenes' float32 re-basing where kiss-icp's BLAS rounds each product (its SSE kernels)
/// and ours fuses them: a few float32 steps at the poses' 1.4 km from the map's origin.
const GT_NUSCENES_SEPARATE_TOL: f64 = 5e-4;
/// `run`'s poses against kiss-icp's pipeline on the same loader's frames.
const POSE_TOL_M: f64 = 1e-6;
/// ATE (m) and ARE (rad) against kiss-icp's figures, on the same ground truth.
const METRICS_TOL: (f64, f64) = (1e-6, 1e-6);
/// The same where the nuScenes ground truths differ by up to [`GT_NUSCENES_SEPARATE_TOL`].
const METRICS_NUSCENES_SEPARATE_TOL: (f64, f64) = (2e-5, 2e-5);

/// kiss-icp's name of the loader for `layout`.
fn loader(layout: &str) -> &str {
    match layout {
        "kitti-raw" => "kitti_raw",
        other => other,
    }
}

/// The Python for `layout`'s loader, or why there is none.
fn python(layout: &str) -> Result<String, String> {
    let vars: &[&str] = if matches!(layout, "nuscenes" | "ncd") {
        &["KISS_ODOM_NUMPY1_PYTHON", "KISS_ODOM_PYTHON"]
    } else {
        &["KISS_ODOM_PYTHON"]
    };
    vars.iter()
        .find_map(|v| std::env::var(v).ok())
        .ok_or_else(|| format!("{} is not set (a Python with kiss-icp 1.3.0)", vars[0]))
}

/// What the loader of one layout read, and the Python it ran in.
struct Reference {
    dir: PathBuf,
    info: serde_json::Value,
}

impl Reference {
    /// The folder of `sequence`'s dump.
    fn of(&self, sequence: Option<&str>) -> PathBuf {
        self.dir.join(sequence.unwrap_or("default"))
    }

    /// `" (the loader read its points with a stand-in for open3d)"`, or nothing.
    fn stand_ins(&self) -> String {
        let used: Vec<&str> = self.info["stand_ins"]
            .as_array()
            .map(|a| a.iter().filter_map(|v| v.as_str()).collect())
            .unwrap_or_default();
        match used.as_slice() {
            [] => String::new(),
            names => format!(" (with a stand-in for {})", names.join(", ")),
        }
    }

    /// How the loader's numpy rounds float32 matrix products.
    fn products(&self) -> Products {
        match self.info["float32_products"].as_str() {
            Some("fused") => Products::Fused,
            _ => Products::Separate,
        }
    }
}

/// `dump_layout.py` on the simulated `layout`, once per process; `Err(reason)` to skip.
fn reference(layout: &str) -> &'static Result<Reference, String> {
    static DONE: [OnceLock<Result<Reference, String>>; 8] = [const { OnceLock::new() }; 8];
    DONE[index(layout)].get_or_init(|| {
        let py = python(layout)?;
        let (sub, sequences) = folder(layout);
        let dir = simulated(layout).with_extension("kiss-icp");
        let script = kiss_odom_tests::repo().join("tests/reference/dump_layout.py");
        let mut cmd = Command::new(&py);
        cmd.arg(script)
            .args(["--loader", loader(layout), "--pipeline", "--data"])
            .arg(simulated(layout).join(sub))
            .arg("--out")
            .arg(&dir);
        for s in sequences.iter().flatten() {
            cmd.args(["--sequence", s]);
        }
        // HeLiPR's other three LiDARs hold the same sweeps in other records (read point by
        // point in Python): two frames each show their decoding.
        cmd.args(["--other-frames", "2"]);
        let o = cmd
            .output()
            .map_err(|e| format!("cannot start {py}: {e}"))?;
        let stdout = String::from_utf8_lossy(&o.stdout);
        if o.status.code() == Some(3) {
            return Err(stdout.trim().trim_start_matches("SKIP: ").to_string());
        }
        assert!(
            o.status.success(),
            "{py} dump_layout.py {}: {}\n{stdout}\n{}",
            loader(layout),
            o.status,
            String::from_utf8_lossy(&o.stderr)
        );
        let info = std::fs::read_to_string(dir.join("info.json")).unwrap();
        let info = serde_json::from_str(&info).unwrap();
        Ok(Reference { dir, info })
    })
}

fn f64s(path: &Path) -> Vec<f64> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

fn matrices(path: &Path) -> Vec<Matrix4<f64>> {
    f64s(path)
        .chunks_exact(16)
        .map(Matrix4::from_row_slice)
        .collect()
}

/// Largest entry difference and entries differing in any bit, poses in pairs.
fn pose_gap(ours: &[Matrix4<f64>], theirs: &[Matrix4<f64>]) -> (f64, usize) {
    assert_eq!(ours.len(), theirs.len(), "poses");
    let pairs = ours.iter().zip(theirs).flat_map(|(a, b)| a.iter().zip(b));
    pairs.fold((0.0, 0), |(worst, n), (a, b)| {
        (
            worst.max((a - b).abs()),
            n + usize::from(a.to_bits() != b.to_bits()),
        )
    })
}

/// Our reading of `data` against the loader's dump in `dumped`, of its first `dumped` of
/// `frames` frames: (coordinates differing in any bit, worst coordinate, worst time). The
/// dump's point files go once compared.
fn compare_points(
    data: &Path,
    format: Format,
    seq: Option<&str>,
    dumped: &Path,
    (frames, compared): (u64, u64),
) -> (usize, f64, f64) {
    let mut ds = open(data, format, &options(seq)).unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(
        ds.frames.len_hint(),
        Some(frames as usize),
        "the loader's length"
    );
    let (mut read, mut differing, mut worst_p, mut worst_t) = (0, 0usize, 0.0f64, 0.0f64);
    while read < compared {
        let item = ds.frames.next_item().unwrap().expect("a frame");
        let Item::Frame(f) = item else {
            panic!("{}: skipped {item:?}", data.display())
        };
        let i = f.index;
        let points = dumped.join(format!("points_{i}.f64"));
        let theirs = f64s(&points);
        assert_eq!(theirs.len(), 3 * f.points.len(), "frame {i}: points");
        for (a, b) in f.points.iter().flatten().zip(&theirs) {
            differing += usize::from(a.to_bits() != b.to_bits());
            worst_p = worst_p.max((a - b).abs());
        }
        let stamps = dumped.join(format!("stamps_{i}.f64"));
        let theirs = f64s(&stamps);
        match &f.stamps {
            None => assert!(theirs.is_empty(), "frame {i}: the loader has times"),
            Some(ours) => {
                assert_eq!(ours.len(), theirs.len(), "frame {i}: times");
                for (a, b) in ours.iter().zip(&theirs) {
                    worst_t = worst_t.max((a - b).abs());
                }
            }
        }
        let _ = std::fs::remove_file(points);
        let _ = std::fs::remove_file(stamps);
        read += 1;
    }
    (differing, worst_p, worst_t)
}

/// Points (m) and times within which a layout's must agree.
fn points_and_stamps_tol(layout: &str) -> (f64, f64) {
    match layout {
        "boreas" => (0.0, STAMPS_F32_TOL),
        "kitti-raw" => (KITTI_CORRECTION_TOL, STAMPS_F64_TOL),
        _ => (0.0, 0.0),
    }
}

/// Our ground truth against the loader's: nuScenes' to the bit as re-based with the loader's
/// BLAS's rounding, and the reader's own (fused) within what the rounding makes; the others
/// within [`GT_TOL`].
fn compare_truth(layout: &str, data: &Path, format: Format, seq: Option<&str>, r: &Reference) {
    let ours = layouts::layout(data, format, &options(seq))
        .unwrap()
        .truth
        .matrices;
    let theirs = matrices(&r.of(seq).join("gt.f64"));
    let (worst, differing) = pose_gap(&ours, &theirs);
    let label = name(layout, seq);
    if format != Format::Nuscenes {
        let tol = match format {
            Format::KittiRaw => GT_KITTI_RAW_TOL,
            _ => GT_TOL,
        };
        println!("{label}: ground truth worst entry {worst:.3e} (tol {tol:.1e})");
        assert!(worst <= tol, "{label}: ground truth");
        return;
    }
    let products = r.products();
    let global = nuscenes::global_poses(data, seq, products).unwrap();
    let as_loader = rebase_f32(&global, products, "first").unwrap();
    let (_, loader_differing) = pose_gap(&as_loader, &theirs);
    let tol = match products {
        Products::Fused => 0.0,
        Products::Separate => GT_NUSCENES_SEPARATE_TOL,
    };
    println!(
        "{label}: the loader's numpy sums matrix products {products:?}; re-based so, {} of \
         {} ground-truth entries differ in any bit (tol 0); the reader's (fused): {differing} \
         differ, worst {worst:.3e} (tol {tol:.0e})",
        loader_differing,
        16 * theirs.len()
    );
    assert_eq!(
        loader_differing, 0,
        "{label}: ground truth as the loader re-bases it"
    );
    assert!(worst <= tol, "{label}: ground truth");
}

#[test]
fn every_layout_reads_as_kiss_icps_own_loader_reads_it() {
    if let Err(why) = python("mulran") {
        println!("SKIP: {why}");
        return;
    }
    let mut compared = 0;
    for (layout, format) in LAYOUTS {
        let r = match reference(layout) {
            Ok(r) => r,
            Err(why) => {
                println!("SKIP: {layout}: {why}");
                continue;
            }
        };
        let (sub, sequences) = folder(layout);
        let data = simulated(layout).join(sub);
        let (points_tol, stamps_tol) = points_and_stamps_tol(layout);
        for &seq in sequences {
            let counts = &r.info["sequences"][seq.unwrap_or("default")];
            let frames = counts["frames"].as_u64().unwrap();
            let dumped = counts["dumped"].as_u64().unwrap();
            assert_eq!(
                frames,
                FRAMES as u64,
                "{}: the loader's length",
                name(layout, seq)
            );
            let (differing, worst_p, worst_t) =
                compare_points(&data, format, seq, &r.of(seq), (frames, dumped));
            let label = name(layout, seq);
            println!(
                "{label}{}: {dumped} of {frames} frames: {differing} coordinates differ in any \
                 bit, worst {worst_p:.3e} m (tol {points_tol:.0e}); per-point times worst \
                 {worst_t:.3e} (tol {stamps_tol:.1e})",
                r.stand_ins()
            );
            assert!(worst_p <= points_tol, "{label}: points");
            if points_tol == 0.0 {
                assert_eq!(differing, 0, "{label}: points");
            }
            assert!(worst_t <= stamps_tol, "{label}: times");
            compare_truth(layout, &data, format, seq, r);
            compared += 1;
        }
    }
    let all: usize = LAYOUTS.iter().map(|(l, _)| folder(l).1.len()).sum();
    println!("{compared} of {all} sequences compared");
}

/// Length (m) and turn (degrees, first to last) of a trajectory.
fn drive(poses: &[Matrix4<f64>]) -> (f64, f64) {
    let t = |m: &Matrix4<f64>| m.fixed_view::<3, 1>(0, 3).into_owned();
    let length = poses.windows(2).map(|w| (t(&w[1]) - t(&w[0])).norm()).sum();
    let (a, b) = (poses[0], poses[poses.len() - 1]);
    let r = a.fixed_view::<3, 3>(0, 0).transpose() * b.fixed_view::<3, 3>(0, 0);
    let cos = ((r.trace() - 1.0) / 2.0).clamp(-1.0, 1.0);
    (length, cos.acos().to_degrees())
}

/// kiss-icp's figure `desc` from its pipeline's metrics.
fn figure(pipeline: &serde_json::Value, desc: &str) -> f64 {
    pipeline["metrics"][desc].as_f64().unwrap_or(f64::NAN)
}

#[test]
fn run_on_every_layout_gives_kiss_icps_poses_and_errors() {
    if let Err(why) = python("mulran") {
        println!("SKIP: {why}");
        return;
    }
    // The test above starts from the first layout, this one from the last: two test threads
    // simulate and wait for Python on different layouts.
    for (layout, format) in LAYOUTS.into_iter().rev() {
        let r = match reference(layout) {
            Ok(r) => r,
            Err(why) => {
                println!("SKIP: {layout}: {why}");
                continue;
            }
        };
        let (sub, sequences) = folder(layout);
        let data = simulated(layout).join(sub);
        let seq = sequences[0];
        let label = name(layout, seq);
        let dumped = r.of(seq);
        let pipeline: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dumped.join("pipeline.json")).unwrap())
                .unwrap();
        let mut args = vec!["--format", layouts::name(format)];
        if let Some(s) = seq {
            args.extend(["--sequence", s]);
        }
        let out = simulated(layout).with_extension("run");
        let run = run(&data, &out, &args);
        assert_eq!(run.code, 0, "{label}: {}", run.stderr);
        let theirs: Vec<Matrix4<f64>> = pipeline["poses"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| {
                let v: Vec<f64> = p
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap())
                    .collect();
                Matrix4::from_row_slice(&v)
            })
            .collect();
        let (worst, _) = pose_gap(&run.poses(), &theirs);
        let (ate, are) = (run.number("metrics.ate_m"), run.number("metrics.are_rad"));
        let (ref_ate, ref_are) = (
            figure(&pipeline, "Absolute Trajectory Error (ATE)"),
            figure(&pipeline, "Absolute Rotational Error (ARE)"),
        );
        let (ate_tol, are_tol) = match (format, r.products()) {
            (Format::Nuscenes, Products::Separate) => METRICS_NUSCENES_SEPARATE_TOL,
            _ => METRICS_TOL,
        };
        let (length, turn) = drive(&matrices(&dumped.join("gt.f64")));
        println!(
            "{label}{}: {length:.1} m driven, turning {turn:.1} deg; poses worst entry \
             {worst:.3e} m (tol {POSE_TOL_M:.0e}); ATE ours {ate:.6} m, kiss-icp {ref_ate:.6} m \
             (tol {ate_tol:.0e}); ARE ours {are:.6} rad, kiss-icp {ref_are:.6} rad (tol \
             {are_tol:.0e}); KITTI errors ours {} % {} deg/m, kiss-icp {} % {} deg/m (NaN: \
             no 100 m segment)",
            r.stand_ins(),
            run.number("metrics.kitti_t_err_pct"),
            run.number("metrics.kitti_r_err_deg_per_m"),
            figure(&pipeline, "Average Translation Error"),
            figure(&pipeline, "Average Rotational Error"),
        );
        assert!(worst <= POSE_TOL_M, "{label}: poses");
        assert!((ate - ref_ate).abs() <= ate_tol, "{label}: ATE");
        assert!((are - ref_are).abs() <= are_tol, "{label}: ARE");
    }
}
