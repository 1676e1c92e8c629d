//! The public datasets' own layouts, end to end: `simulate --layout X` writes a short sequence
//! in dataset X's layout, and
//!
//! - kiss-icp 1.3.0's own dataloader for X (`tests/reference/dump_layout.py`, the Python in
//!   `KISS_ODOM_PYTHON`; nuScenes' needs nuscenes-devkit and Newer College's pyntcloud, which
//!   need numpy below 2, so those two take `KISS_ODOM_NUMPY1_PYTHON` when it is set) and ours
//!   read the same points (bit for bit), the
//!   same per-point times and the same ground truth; without the Python, or a loader's own
//!   dependency in it, the layout prints SKIP;
//! - `kiss-odom run --format X` gives the poses and error figures kiss-icp's pipeline gives
//!   on the loader;
//! - `auto` recognises every layout by its folders, and bad input (a ground truth with rows
//!   missing, a MulRan folder without `global_pose.csv`, an NCLT scan cut mid-point, files
//!   that disagree in count, two layouts in one folder) is refused or reported naming the
//!   file. These need no Python.

use crate::common::{run, RunExt};
use kiss_odom_io::layouts;
use kiss_odom_io::{open, Format, Item, OpenOptions};
use nalgebra::Matrix4;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Per-point times computed in float64 from the same values (MulRan's and Newer College's
/// grid, HeLiPR's scaling) must agree exactly; times from `atan2` may differ by the last bit
/// of numpy's vectorised `arctan2` (float32 for Boreas, float64 for KITTI raw).
const STAMPS_TOL: f64 = 0.0;
const STAMPS_F32_TOL: f64 = 2.0 * f32::EPSILON as f64;
const STAMPS_F64_TOL: f64 = 4.0 * f64::EPSILON;
/// Ground truth entries.
const GT_TOL: f64 = 1e-9;
/// nuScenes' loader re-bases its float32 poses in float32 arithmetic (see
/// `kiss_odom_io::layouts::nuscenes`): one float32 step at the simulated poses' 1.2 km from
/// the map's origin.
const GT_NUSCENES_TOL: f64 = 1.2e-4;
/// `run`'s poses against kiss-icp's pipeline on the same loader's frames.
const POSE_TOL_M: f64 = 1e-6;
/// Points are compared bit for bit, but for KITTI raw's vertical-angle correction, which
/// kiss-icp computes in C++ (Eigen) and kiss-odom in Rust: within 1e-12 m, as the KITTI
/// reader's own cross-check (`readers.rs`) allows.
const KITTI_CORRECTION_TOL: f64 = 1e-12;
/// ATE (m) and ARE (rad) against kiss-icp's figures.
const METRICS_TOL: (f64, f64) = (1e-6, 1e-6);
/// nuScenes' ground truth differs from the loader's by up to [`GT_NUSCENES_TOL`], which moves
/// ATE by as much; ARE on these sequences' first metre of nearly straight driving is barely
/// determined (about 1 rad, see `Metrics::are_rad`), and that moves it by up to 0.03 rad.
const METRICS_NUSCENES_TOL: (f64, f64) = (1e-4, 0.05);

/// One layout case: the simulator's `--layout`, our `--format`, kiss-icp's loader, the path
/// under the simulated folder to open and the `--sequence`.
struct Case {
    layout: &'static str,
    format: Format,
    loader: &'static str,
    sub: &'static str,
    sequence: Option<&'static str>,
    points_tol: f64,
    stamps_tol: f64,
    gt_tol: f64,
    metrics_tol: (f64, f64),
}

const fn case(
    layout: &'static str,
    format: Format,
    loader: &'static str,
    sub: &'static str,
    sequence: Option<&'static str>,
) -> Case {
    Case {
        layout,
        format,
        loader,
        sub,
        sequence,
        points_tol: 0.0,
        stamps_tol: STAMPS_TOL,
        gt_tol: GT_TOL,
        metrics_tol: METRICS_TOL,
    }
}

const CASES: [Case; 11] = [
    case("mulran", Format::Mulran, "mulran", "", None),
    case("nclt", Format::Nclt, "nclt", "2012-01-08", None),
    case("ncd", Format::Ncd, "ncd", "", None),
    case("helipr", Format::Helipr, "helipr", "", Some("Ouster")),
    case("helipr", Format::Helipr, "helipr", "", Some("Velodyne")),
    case("helipr", Format::Helipr, "helipr", "", Some("Avia")),
    case("helipr", Format::Helipr, "helipr", "", Some("Aeva")),
    Case {
        stamps_tol: STAMPS_F32_TOL,
        ..case("boreas", Format::Boreas, "boreas", "", None)
    },
    Case {
        gt_tol: GT_NUSCENES_TOL,
        metrics_tol: METRICS_NUSCENES_TOL,
        ..case("nuscenes", Format::Nuscenes, "nuscenes", "", Some("61"))
    },
    case("apollo", Format::Apollo, "apollo", "", None),
    Case {
        points_tol: KITTI_CORRECTION_TOL,
        stamps_tol: STAMPS_F64_TOL,
        ..case("kitti-raw", Format::KittiRaw, "kitti_raw", "", Some("00"))
    },
];

/// `simulate --layout LAYOUT` into `dir/LAYOUT` (once per layout), short and sparse.
fn simulated(dir: &Path, layout: &str) -> PathBuf {
    let out = dir.join(layout);
    if !out.join("sim.toml").is_file() {
        let grid = matches!(layout, "mulran" | "ncd");
        let frames = if grid { "4" } else { "6" };
        // `fast`: 20-30 m/s with turns, so that the alignment behind ATE and ARE is well
        // determined in a few frames.
        let mut args = vec![
            "--layout",
            layout,
            "--frames",
            frames,
            "--seed",
            "3",
            "--profile",
            "fast",
        ];
        if !grid {
            args.extend(["--beams", "16", "--columns", "512"]);
        }
        kiss_odom_tests::simulate(&out, &args);
    }
    out
}

fn options(sequence: Option<&str>) -> OpenOptions {
    OpenOptions {
        sequence: sequence.map(String::from),
        ..OpenOptions::default()
    }
}

fn f64s(path: &Path) -> Vec<f64> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

/// The Python for `loader`, or why there is none.
fn python(loader: &str) -> Result<String, String> {
    let vars: &[&str] = if matches!(loader, "nuscenes" | "ncd") {
        &["KISS_ODOM_NUMPY1_PYTHON", "KISS_ODOM_PYTHON"]
    } else {
        &["KISS_ODOM_PYTHON"]
    };
    vars.iter()
        .find_map(|v| std::env::var(v).ok())
        .ok_or_else(|| {
            format!(
                "{} is not set (a Python with kiss-icp 1.3.0)",
                vars.join(" or ")
            )
        })
}

/// What kiss-icp's loader read, dumped to `out`; `Err(reason)` to skip.
fn dump(case: &Case, data: &Path, out: &Path, pipeline: bool) -> Result<(), String> {
    let py = python(case.loader)?;
    let script = kiss_odom_tests::repo().join("tests/reference/dump_layout.py");
    let mut cmd = Command::new(&py);
    cmd.arg(script)
        .args(["--loader", case.loader, "--data"])
        .arg(data)
        .arg("--out")
        .arg(out);
    if let Some(s) = case.sequence {
        cmd.args(["--sequence", s]);
    }
    if pipeline {
        cmd.arg("--pipeline");
    }
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
        case.loader,
        o.status,
        String::from_utf8_lossy(&o.stderr)
    );
    Ok(())
}

fn name(case: &Case) -> String {
    match case.sequence {
        Some(s) => format!("{} {s}", case.layout),
        None => case.layout.to_string(),
    }
}

/// Our reading of `data` against the loader's dump in `dumped`: (coordinates differing in
/// any bit, worst coordinate, worst time, worst ground-truth entry).
fn compare(case: &Case, data: &Path, dumped: &Path) -> (usize, f64, f64, f64) {
    let info: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dumped.join("info.json")).unwrap()).unwrap();
    let n = info["frames"].as_u64().unwrap() as usize;
    let opts = options(case.sequence);
    let mut ds = open(data, case.format, &opts).unwrap_or_else(|e| panic!("{}: {e:#}", name(case)));
    let mut frames = 0;
    let (mut differing, mut worst_p, mut worst_t) = (0usize, 0.0f64, 0.0f64);
    while let Some(item) = ds.frames.next_item().unwrap() {
        let Item::Frame(f) = item else {
            panic!("{}: skipped {item:?}", name(case))
        };
        let i = f.index;
        let theirs = f64s(&dumped.join(format!("points_{i}.f64")));
        assert_eq!(
            theirs.len(),
            3 * f.points.len(),
            "{} frame {i}: points",
            name(case)
        );
        for (a, b) in f.points.iter().flatten().zip(&theirs) {
            differing += usize::from(a.to_bits() != b.to_bits());
            worst_p = worst_p.max((a - b).abs());
        }
        let stamps = f64s(&dumped.join(format!("stamps_{i}.f64")));
        match &f.stamps {
            None => assert!(
                stamps.is_empty(),
                "{} frame {i}: the loader has times",
                name(case)
            ),
            Some(ours) => {
                assert_eq!(ours.len(), stamps.len(), "{} frame {i}: times", name(case));
                for (a, b) in ours.iter().zip(&stamps) {
                    worst_t = worst_t.max((a - b).abs());
                }
            }
        }
        frames += 1;
    }
    assert_eq!(frames, n, "{}: frames", name(case));
    let layout = layouts::layout(data, case.format, &opts).unwrap();
    let gt = f64s(&dumped.join("gt.f64"));
    assert_eq!(
        gt.len(),
        16 * layout.truth.matrices.len(),
        "{}: poses",
        name(case)
    );
    let worst_gt = layout
        .truth
        .matrices
        .iter()
        .zip(gt.chunks_exact(16))
        .map(|(m, g)| (m - Matrix4::from_row_slice(g)).amax())
        .fold(0.0, f64::max);
    (differing, worst_p, worst_t, worst_gt)
}

#[test]
fn every_layout_reads_as_kiss_icps_own_loader_reads_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut compared = 0;
    for case in &CASES {
        if let Err(why) = python(case.loader) {
            println!("SKIP: {}: {why}", name(case));
            continue;
        }
        let root = simulated(dir.path(), case.layout);
        let data = root.join(case.sub);
        let dumped = dir
            .path()
            .join(format!("dump-{}-{:?}", case.layout, case.sequence));
        if let Err(why) = dump(case, &data, &dumped, false) {
            println!("SKIP: {}: {why}", name(case));
            continue;
        }
        let (differing, worst_p, worst_t, worst_gt) = compare(case, &data, &dumped);
        println!(
            "{}: {differing} coordinates differ in any bit, worst {worst_p:.3e} m (tol {:.0e}); \
             per-point times worst {worst_t:.3e} (tol {:.1e}); ground truth worst entry \
             {worst_gt:.3e} (tol {:.1e})",
            name(case),
            case.points_tol,
            case.stamps_tol,
            case.gt_tol
        );
        assert!(worst_p <= case.points_tol, "{}: points", name(case));
        if case.points_tol == 0.0 {
            assert_eq!(differing, 0, "{}: points", name(case));
        }
        assert!(worst_t <= case.stamps_tol, "{}: times", name(case));
        assert!(worst_gt <= case.gt_tol, "{}: ground truth", name(case));
        compared += 1;
    }
    println!("{compared} of {} layouts compared", CASES.len());
}

/// kiss-icp's figure `desc` from its pipeline's metrics.
fn figure(pipeline: &serde_json::Value, desc: &str) -> f64 {
    pipeline["metrics"][desc].as_f64().unwrap_or(f64::NAN)
}

#[test]
fn run_on_every_layout_gives_kiss_icps_poses_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    for case in CASES.iter().filter(|c| c.sequence != Some("Velodyne")) {
        if !matches!(
            case.sequence,
            None | Some("Ouster") | Some("61") | Some("00")
        ) {
            continue;
        }
        if let Err(why) = python(case.loader) {
            println!("SKIP: {}: {why}", name(case));
            continue;
        }
        let root = simulated(dir.path(), case.layout);
        let data = root.join(case.sub);
        let dumped = dir.path().join(format!("pipe-{}", case.layout));
        if let Err(why) = dump(case, &data, &dumped, true) {
            println!("SKIP: {}: {why}", name(case));
            continue;
        }
        let pipeline: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dumped.join("pipeline.json")).unwrap())
                .unwrap();
        let mut args = vec!["--format", layouts::name(case.format)];
        if let Some(s) = case.sequence {
            args.extend(["--sequence", s]);
        }
        let out = dir.path().join(format!("run-{}", case.layout));
        let r = run(&data, &out, &args);
        assert_eq!(r.code, 0, "{}: {}", name(case), r.stderr);
        let ours = r.poses();
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
        assert_eq!(ours.len(), theirs.len(), "{}: poses", name(case));
        let worst = ours
            .iter()
            .zip(&theirs)
            .map(|(a, b)| (a - b).amax())
            .fold(0.0, f64::max);
        let (ate, are) = (r.number("metrics.ate_m"), r.number("metrics.are_rad"));
        let (ref_ate, ref_are) = (
            figure(&pipeline, "Absolute Trajectory Error (ATE)"),
            figure(&pipeline, "Absolute Rotational Error (ARE)"),
        );
        println!(
            "{}: poses worst entry {worst:.3e} m (tol {POSE_TOL_M:.0e}); ATE ours {ate:.6} m, \
             kiss-icp {ref_ate:.6} m (tol {:.0e}); ARE ours {are:.6} rad, kiss-icp \
             {ref_are:.6} rad (tol {:.0e}); KITTI errors ours {} % {} deg/m, kiss-icp {} % {} \
             deg/m (NaN: no 100 m segment)",
            name(case),
            case.metrics_tol.0,
            case.metrics_tol.1,
            r.number("metrics.kitti_t_err_pct"),
            r.number("metrics.kitti_r_err_deg_per_m"),
            figure(&pipeline, "Average Translation Error"),
            figure(&pipeline, "Average Rotational Error"),
        );
        assert!(worst <= POSE_TOL_M, "{}: poses", name(case));
        let (ate_tol, are_tol) = case.metrics_tol;
        assert!((ate - ref_ate).abs() <= ate_tol, "{}: ATE", name(case));
        assert!((are - ref_are).abs() <= are_tol, "{}: ARE", name(case));
    }
}

#[test]
fn auto_recognises_every_layout_by_its_folders() {
    let dir = tempfile::tempdir().unwrap();
    for case in CASES
        .iter()
        .filter(|c| !matches!(c.sequence, Some("Velodyne" | "Avia" | "Aeva")))
    {
        let data = simulated(dir.path(), case.layout).join(case.sub);
        let found = kiss_odom_io::open::detect(&data).unwrap();
        assert_eq!(found, case.format, "{}", data.display());
        let ds = open(&data, Format::Auto, &options(case.sequence)).unwrap();
        let gt = ds.info.ground_truth.as_ref().expect("ground truth");
        assert_eq!(Some(gt.len()), ds.frames.len_hint(), "{}", name(case));
        assert!(
            ds.info.warnings.is_empty(),
            "{}: {:?}",
            name(case),
            ds.info.warnings
        );
    }
}

#[test]
fn auto_refuses_a_folder_with_the_structure_of_two_layouts() {
    let dir = tempfile::tempdir().unwrap();
    let root = simulated(dir.path(), "boreas");
    std::fs::create_dir(root.join("Ouster")).unwrap();
    let e = format!("{:#}", kiss_odom_io::open::detect(&root).unwrap_err());
    assert!(
        e.contains("mulran") && e.contains("boreas") && e.contains("--format"),
        "{e}"
    );
    // Named, it opens.
    assert!(open(&root, Format::Boreas, &OpenOptions::default()).is_ok());
}

#[test]
fn a_mulran_folder_without_global_pose_csv_is_refused_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let root = simulated(dir.path(), "mulran");
    std::fs::remove_file(root.join("global_pose.csv")).unwrap();
    for format in [Format::Mulran, Format::Auto] {
        let e = format!(
            "{:#}",
            open(&root, format, &OpenOptions::default()).err().unwrap()
        );
        assert!(e.contains("global_pose.csv: no such file"), "{e}");
    }
}

#[test]
fn mulran_pose_rows_missing_around_a_scan_are_reported_with_the_gap() {
    let dir = tempfile::tempdir().unwrap();
    let root = simulated(dir.path(), "mulran");
    let csv = root.join("global_pose.csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    // Two rows a scan, 0.05 s apart: without rows 2..7 (0.2 to 0.4 s), the scan at 0.3 s is
    // 0.15 s from its nearest rows, the others 0.05 s.
    let kept: Vec<&str> = text
        .lines()
        .enumerate()
        .filter(|(i, _)| !(2..7).contains(i))
        .map(|(_, l)| l)
        .collect();
    std::fs::write(&csv, kept.join("\n")).unwrap();
    let ds = open(&root, Format::Mulran, &OpenOptions::default()).unwrap();
    let w = ds.info.warnings.join("\n");
    assert!(
        w.contains("global_pose.csv") && w.contains("1 scan(s) are more than 0.1 s"),
        "{w}"
    );
}

#[test]
fn a_ground_truth_with_a_row_missing_is_reported_and_the_rest_scored() {
    let dir = tempfile::tempdir().unwrap();
    let root = simulated(dir.path(), "boreas");
    let csv = root.join("applanix/lidar_poses.csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    std::fs::write(&csv, lines[..lines.len() - 1].join("\n")).unwrap();
    let ds = open(&root, Format::Boreas, &OpenOptions::default()).unwrap();
    let w = ds.info.warnings.join("\n");
    assert!(w.contains("lidar_poses.csv has 5 poses for 6 scans"), "{w}");
    let r = run(&root, &dir.path().join("out"), &["--format", "boreas"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stderr.contains("5 poses for 6 scans"), "{}", r.stderr);
    assert!(
        r.number("metrics.ate_m").is_finite(),
        "scored on the 5 frames"
    );
}

#[test]
fn a_csv_ground_truth_with_a_short_row_is_refused_naming_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let root = simulated(dir.path(), "ncd");
    let csv = root.join("ground_truth/registered_poses.csv");
    let mut text = std::fs::read_to_string(&csv).unwrap();
    text.push_str("1583836592,0,1,2,3\n");
    std::fs::write(&csv, text).unwrap();
    let e = format!(
        "{:#}",
        open(&root, Format::Ncd, &OpenOptions::default())
            .err()
            .unwrap()
    );
    assert!(
        e.contains("registered_poses.csv") && e.contains("line 6: 5 columns"),
        "{e}"
    );
}

#[test]
fn an_nclt_scan_cut_mid_point_is_skipped_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let root = simulated(dir.path(), "nclt").join("2012-01-08");
    let scans = layouts::layout(&root, Format::Nclt, &OpenOptions::default())
        .unwrap()
        .scans;
    let cut = &scans[2].path;
    let mut bytes = std::fs::read(cut).unwrap();
    bytes.truncate(bytes.len() - 3);
    std::fs::write(cut, bytes).unwrap();
    let mut ds = open(&root, Format::Nclt, &OpenOptions::default()).unwrap();
    let mut skipped = Vec::new();
    while let Some(item) = ds.frames.next_item().unwrap() {
        if let Item::Skipped { index, reason, .. } = item {
            skipped.push((index, reason));
        }
    }
    assert_eq!(skipped.len(), 1, "{skipped:?}");
    assert_eq!(skipped[0].0, 2);
    let reason = &skipped[0].1;
    assert!(
        reason.contains(&cut.display().to_string()) && reason.contains("multiple of 8"),
        "{reason}"
    );
}

#[test]
fn scans_and_poses_that_disagree_in_count_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let root = simulated(dir.path(), "apollo");
    std::fs::remove_file(root.join("pcds/6.pcd")).unwrap();
    let ds = open(&root, Format::Apollo, &OpenOptions::default()).unwrap();
    let w = ds.info.warnings.join("\n");
    assert!(
        w.contains("gt_poses.txt has 6 poses for 5 scans") && w.contains("last 1"),
        "{w}"
    );
    let root = simulated(dir.path(), "helipr");
    std::fs::write(root.join("LiDAR_GT/global_Avia_gt.txt"), "").unwrap();
    let e = format!(
        "{:#}",
        open(&root, Format::Helipr, &options(Some("avia")))
            .err()
            .unwrap()
    );
    assert!(
        e.contains("global_Avia_gt.txt") && e.contains("no rows"),
        "{e}"
    );
    let e = format!(
        "{:#}",
        open(&root, Format::Helipr, &OpenOptions::default())
            .err()
            .unwrap()
    );
    assert!(
        e.contains("several sensors") && e.contains("--sequence"),
        "{e}"
    );
}
