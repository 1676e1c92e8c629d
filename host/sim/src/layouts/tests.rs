//! Each layout writer against the reader of its layout in `kiss-odom-io`: a short simulated
//! drive (a small ray grid, entered moving and turning) written in the layout and read back
//! gives the simulated points (as the layout stores them), their capture times where the
//! layout keeps them, and the simulator's ground truth in the loader's convention. Writer and
//! reader share no code; the tolerances are what the layout's storage costs.

use super::{helipr, nclt, world, write, Layout};
use crate::simulation::{SimParams, Simulation};
use crate::Profile;
use kiss_odom_io::layouts::{self, ScanPoints};
use kiss_odom_io::{Format, OpenOptions};
use nalgebra::Matrix4;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

const FRAMES: u64 = 3;

/// Three sweeps of 8 x 128 rays, 8 s into the urban drive under seed 0 (its first turn).
fn simulation() -> Simulation {
    let mut p = SimParams::new(Profile::Urban, 0, FRAMES);
    p.lead_in = 8.0;
    p.sensor.beams = 8;
    p.sensor.columns = 128;
    Simulation::new(p).expect("valid parameters")
}

/// `sim` written in `layout` into a fresh folder.
fn written(sim: &Simulation, layout: Layout) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let outcome = write(sim, layout, dir.path(), false, "", &|| false, &mut |_| {}).unwrap();
    assert!(outcome.complete, "{layout:?}: {outcome:?}");
    assert_eq!(outcome.frames, FRAMES, "{layout:?}");
    dir
}

/// What the reader of `format` reads from `root`: every scan and the ground truth.
fn read(root: &Path, format: Format, sequence: Option<&str>) -> (Vec<ScanPoints>, Truth) {
    let opts = OpenOptions {
        sequence: sequence.map(String::from),
        ..OpenOptions::default()
    };
    let layout = layouts::layout(root, format, &opts).unwrap_or_else(|e| panic!("{e:#}"));
    assert!(layout.warnings.is_empty(), "{:?}", layout.warnings);
    let scans = layout
        .scans
        .iter()
        .map(|s| (layout.read)(&s.path, usize::MAX).unwrap_or_else(|e| panic!("{e:#}")))
        .collect();
    (scans, layout.truth.matrices)
}

type Truth = Vec<Matrix4<f64>>;

/// The simulator's ground truth of every frame, `pre * L_k`.
fn truth(sim: &Simulation, pre: &Matrix4<f64>) -> Truth {
    (0..FRAMES)
        .map(|k| pre * sim.ground_truth(k).to_homogeneous())
        .collect()
}

/// Largest entry difference between two sequences of poses of the same length.
fn worst_pose(ours: &Truth, read: &Truth) -> f64 {
    assert_eq!(ours.len(), read.len(), "poses");
    ours.iter()
        .zip(read)
        .map(|(a, b)| (a - b).amax())
        .fold(0.0, f64::max)
}

fn widened(p: &[f32; 4]) -> [f64; 3] {
    [p[0], p[1], p[2]].map(f64::from)
}

/// The points of every frame as read equal the simulated ones, in order, within `tol` (m),
/// but for the last `dropped` of each (a loader that leaves the last record out).
fn same_points(sim: &Simulation, scans: &[ScanPoints], tol: f64, dropped: usize) {
    assert_eq!(scans.len() as u64, FRAMES, "scans");
    let mut worst = 0.0f64;
    for (k, scan) in scans.iter().enumerate() {
        let frame = sim.frame(k as u64);
        let expected = frame.points.len() - dropped;
        assert_eq!(scan.points.len(), expected, "frame {k}: points");
        for (a, b) in scan.points.iter().zip(&frame.points) {
            let b = widened(b);
            for i in 0..3 {
                worst = worst.max((a[i] - b[i]).abs());
            }
        }
    }
    println!("points: worst coordinate {worst:.3e} m (tolerance {tol:.1e})");
    assert!(
        worst <= tol,
        "points differ by {worst:e} m (tolerance {tol:e})"
    );
}

fn check_truth(name: &str, expected: &Truth, read: &Truth, tol: f64) {
    let worst = worst_pose(expected, read);
    println!("{name}: ground truth worst entry {worst:.3e} (tolerance {tol:.1e})");
    assert!(
        worst <= tol,
        "{name}: ground truth differs by {worst:e} (tolerance {tol:e})"
    );
}

#[test]
fn apollo_reads_back_the_points_and_the_lidar_poses() {
    let sim = simulation();
    let dir = written(&sim, Layout::Apollo);
    let (scans, gt) = read(dir.path(), Format::Apollo, None);
    same_points(&sim, &scans, 0.0, 0);
    assert!(scans.iter().all(|s| s.stamps.is_none()));
    check_truth("apollo", &truth(&sim, &Matrix4::identity()), &gt, 1e-9);
}

#[test]
fn nuscenes_reads_back_the_points_and_the_float32_lidar_poses() {
    let sim = simulation();
    let dir = written(&sim, Layout::Nuscenes);
    let (scans, gt) = read(dir.path(), Format::Nuscenes, Some("61"));
    same_points(&sim, &scans, 0.0, 0);
    assert!(scans.iter().all(|s| s.stamps.is_none()));
    // The global poses are stored as float32 about 1.4 km from the map's origin (a float32
    // step there is 1.2e-4 m) and re-based in float32.
    check_truth("nuscenes", &truth(&sim, &Matrix4::identity()), &gt, 3e-4);
}

#[test]
fn boreas_reads_back_the_points_and_the_float32_lidar_poses() {
    let sim = simulation();
    let dir = written(&sim, Layout::Boreas);
    let (scans, gt) = read(dir.path(), Format::Boreas, None);
    same_points(&sim, &scans, 0.0, 0);
    // Its loader's times come from each point's azimuth, not from the file: in [0, 1].
    for s in &scans {
        let t = s.stamps.as_ref().expect("times");
        assert!(t.iter().all(|t| (0.0..=1.0).contains(t)));
    }
    // Re-based in float64, stored as float32: a float32 step of a pose a few metres out.
    check_truth("boreas", &truth(&sim, &Matrix4::identity()), &gt, 1e-6);
}

#[test]
fn helipr_reads_back_every_sensors_points_times_and_global_poses() {
    let sim = simulation();
    let dir = written(&sim, Layout::Helipr);
    for sensor in helipr::SENSORS {
        let (scans, gt) = read(dir.path(), Format::Helipr, Some(sensor));
        // The loader reads records while a whole one is left after the one it reads: the
        // last is left out.
        same_points(&sim, &scans, 0.0, 1);
        for (k, s) in scans.iter().enumerate() {
            let read = s.stamps.as_ref().expect("times");
            // Each record holds its time since the sweep's first point, in ns (the
            // Velodyne's in float32 seconds); the loader scales them to [0, 1].
            let stamps = &sim.frame(k as u64).stamps[..read.len()];
            let lo = stamps.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = stamps.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let worst = read
                .iter()
                .zip(stamps)
                .map(|(r, t)| (r - (t - lo) / (hi - lo)).abs())
                .fold(0.0, f64::max);
            // 1 ns, or half a float32 step of 0.1 s, of a 0.1 s sweep.
            println!("{sensor} frame {k}: times worst {worst:.3e} (tolerance 1e-7)");
            assert!(
                worst <= 1e-7,
                "{sensor} frame {k}: times differ by {worst:e}"
            );
        }
        // Not re-based: the world frame.
        check_truth(sensor, &truth(&sim, &world()), &gt, 1e-9);
    }
}

#[test]
fn kitti_raw_reads_back_the_points_through_the_correction_and_the_lidar_poses() {
    let sim = simulation();
    let dir = written(&sim, Layout::KittiRaw);
    let (scans, gt) = read(dir.path(), Format::KittiRaw, Some("00"));
    // The tilted points are stored as float32: half a float32 step at up to 100 m.
    same_points(&sim, &scans, 1e-5, 0);
    check_truth("kitti-raw", &truth(&sim, &Matrix4::identity()), &gt, 1e-8);
}

#[test]
fn nclt_reads_back_the_quantised_points_and_the_global_poses() {
    let sim = simulation();
    let dir = written(&sim, Layout::Nclt);
    let root: PathBuf = dir.path().join(nclt::DATE);
    let (scans, gt) = read(&root, Format::Nclt, None);
    assert_eq!(scans.len() as u64, FRAMES, "scans");
    let (mut worst, mut wrapped) = (0.0f64, 0);
    for (k, scan) in scans.iter().enumerate() {
        let frame = sim.frame(k as u64);
        assert_eq!(scan.points.len(), frame.points.len(), "frame {k}: points");
        for (a, b) in scan.points.iter().zip(&frame.points) {
            for (i, sign) in [1.0, -1.0, -1.0].into_iter().enumerate() {
                // Stored as `(sign v + 100) / 0.005` in 16 bits, which the loader reads as
                // signed: from 32768 on, 327.68 m away.
                let v = f64::from(b[i]);
                let wraps = ((sign * v + 100.0) / 0.005).round() >= 32768.0;
                let expected = if wraps { v - sign * 327.68 } else { v };
                wrapped += usize::from(wraps);
                worst = worst.max((a[i] - expected).abs());
            }
        }
    }
    // 5 mm steps: half of one, and float32 rounding of the scaled value.
    println!("points: worst coordinate {worst:.3e} m (tolerance 2.51e-3), {wrapped} wrapped");
    assert!(worst <= 0.0025 + 1e-5, "points differ by {worst:e} m");
    assert!(
        wrapped > 0,
        "no coordinate beyond 63.8 m: the wrap is not exercised"
    );
    // Not re-based: the world frame, stored as float32 1.4 km from its origin.
    check_truth("nclt", &truth(&sim, &world()), &gt, 2e-4);
}

/// The simulated points of frame `k` by their bits, with their capture times as fractions
/// of the sweep.
fn by_bits(sim: &Simulation, k: u64) -> HashMap<[u32; 3], f64> {
    let frame = sim.frame(k);
    let p = sim.params();
    let rate = p.sensor.rate_hz;
    let start = p.start_time + k as f64 / rate;
    frame
        .points
        .iter()
        .zip(&frame.stamps)
        .map(|(p, t)| ([p[0], p[1], p[2]].map(f32::to_bits), (t - start) * rate))
        .collect()
}

/// A 64 x 1024 grid read back: its returns are the simulated points (each once), its other
/// cells empty, and each return's time (its column's, as the loader gives it) is within half
/// a column of the point's capture.
fn same_grid(sim: &Simulation, scans: &[ScanPoints]) {
    assert_eq!(scans.len() as u64, FRAMES, "scans");
    for (k, scan) in scans.iter().enumerate() {
        let mut left = by_bits(sim, k as u64);
        assert_eq!(scan.points.len(), 64 * 1024, "frame {k}: a whole grid");
        let stamps = scan.stamps.as_ref().expect("the grid's times");
        for (p, s) in scan.points.iter().zip(stamps) {
            if *p == [0.0; 3] {
                continue;
            }
            let bits = p.map(|v| (v as f32).to_bits());
            let t = left
                .remove(&bits)
                .unwrap_or_else(|| panic!("frame {k}: {p:?} is not a simulated point"));
            assert!(
                (s - t).abs() <= 0.5 / 1024.0 + 1e-9,
                "frame {k}: time {s} for a point captured at {t} of the sweep"
            );
        }
        assert!(left.is_empty(), "frame {k}: {} points missing", left.len());
    }
}

#[test]
fn mulran_reads_back_the_ouster_grid_and_the_lidar_poses() {
    let sim = simulation();
    let dir = written(&sim, Layout::Mulran);
    let (scans, gt) = read(dir.path(), Format::Mulran, None);
    same_grid(&sim, &scans);
    check_truth("mulran", &truth(&sim, &Matrix4::identity()), &gt, 1e-9);
}

#[test]
fn ncd_reads_back_the_ouster_grid_and_the_lidar_poses() {
    let sim = simulation();
    let dir = written(&sim, Layout::Ncd);
    let (scans, gt) = read(dir.path(), Format::Ncd, None);
    same_grid(&sim, &scans);
    // The CSV holds `W L T_CL^-1` as a quaternion, and the loader's `T_CL` (float32 entries)
    // is not quite a rotation: the quaternion leaves out its float32 rounding (6e-8).
    check_truth("ncd", &truth(&sim, &Matrix4::identity()), &gt, 1e-7);
}
