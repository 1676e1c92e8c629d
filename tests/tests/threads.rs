//! Thread count does not change results: `kiss-odom run` with 1, 2 and 4 worker threads writes
//! byte-identical `poses_kitti.txt` on a real KITTI sequence and on a short simulated one (with
//! per-point timestamps, so deskewing is exercised too). The core fixes the chunking and the
//! reduction order of the linear system, so the pool only decides who computes which chunk.
//!
//! KITTI data: `KISS_ODOM_KITTI_MINI` (default `../shared/data/kitti-mini` beside the
//! repository).

use std::ffi::OsString;
use std::path::{Path, PathBuf};

fn kitti_mini() -> PathBuf {
    std::env::var_os("KISS_ODOM_KITTI_MINI")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/kitti-mini")
        })
}

/// Runs the `kiss-odom` command in-process; panics with its stderr on failure.
fn kiss_odom(args: &[&OsString]) {
    let mut argv: Vec<OsString> = vec!["kiss-odom".into()];
    argv.extend(args.iter().map(|a| (*a).clone()));
    let mut err = Vec::new();
    let code = kiss_odom::cli::main_with(argv.clone(), &mut err);
    assert_eq!(
        code,
        0,
        "{argv:?} failed: {}",
        String::from_utf8_lossy(&err)
    );
}

/// `poses_kitti.txt` of `kiss-odom run DATASET --threads N [extra]`, for N in 1, 2 and 4.
fn poses_per_thread_count(dataset: &Path, extra: &[&str], out: &Path) -> Vec<(usize, Vec<u8>)> {
    poses_for_threads(dataset, extra, out, &[1, 2, 4])
}

/// The same for each thread count of `threads`.
fn poses_for_threads(
    dataset: &Path,
    extra: &[&str],
    out: &Path,
    threads: &[usize],
) -> Vec<(usize, Vec<u8>)> {
    threads
        .iter()
        .map(|&n| {
            let dir = out.join(format!("threads-{n}{}", extra.join("")));
            let mut args: Vec<OsString> = vec![
                "run".into(),
                dataset.into(),
                "--out".into(),
                dir.clone().into(),
                "--threads".into(),
                n.to_string().into(),
                "--quiet".into(),
            ];
            args.extend(extra.iter().map(OsString::from));
            kiss_odom(&args.iter().collect::<Vec<_>>());
            let poses = std::fs::read(dir.join("poses_kitti.txt")).unwrap();
            (n, poses)
        })
        .collect()
}

fn assert_identical(what: &str, runs: &[(usize, Vec<u8>)], frames: usize) {
    let (_, first) = &runs[0];
    assert_eq!(
        first.iter().filter(|&&b| b == b'\n').count(),
        frames,
        "{what}: one pose per frame"
    );
    for (n, poses) in &runs[1..] {
        let diff = first
            .split(|&b| b == b'\n')
            .zip(poses.split(|&b| b == b'\n'))
            .position(|(a, b)| a != b);
        assert!(
            poses == first,
            "{what}: poses with {n} threads differ from 1 thread (first differing frame: \
             {diff:?})"
        );
    }
    println!(
        "{what}: {} frames, poses byte-identical for threads {:?}",
        frames,
        runs.iter().map(|r| r.0).collect::<Vec<_>>()
    );
}

#[test]
fn kitti_poses_are_bit_identical_for_1_2_and_4_threads() {
    let seq = kitti_mini().join("sequences/05");
    assert!(
        seq.join("velodyne").is_dir(),
        "{}: kitti-mini not found (set KISS_ODOM_KITTI_MINI)",
        seq.display()
    );
    let tmp = tempfile::tempdir().unwrap();
    let runs = poses_per_thread_count(&seq, &["--frames", "0..6"], tmp.path());
    assert_identical("kitti-mini 05", &runs, 6);
}

#[test]
fn simulated_poses_are_bit_identical_for_1_2_and_4_threads() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("urban");
    let sim: Vec<OsString> = [
        "simulate",
        "--out",
        data.to_str().unwrap(),
        "--frames",
        "8",
        "--seed",
        "11",
        "--profile",
        "urban",
        "--beams",
        "32",
        "--columns",
        "512",
    ]
    .iter()
    .map(OsString::from)
    .collect();
    kiss_odom(&sim.iter().collect::<Vec<_>>());
    let runs = poses_per_thread_count(&data, &[], tmp.path());
    assert_identical("simulated urban", &runs, 8);
    // The accurate preset deskews a scan twice where its motion changed: as deterministic.
    let runs = poses_per_thread_count(&data, &["--preset", "accurate"], tmp.path());
    assert_identical("simulated urban, accurate preset", &runs, 8);
}

#[test]
fn the_accurate_preset_is_bit_identical_for_1_2_and_3_threads_and_counts_its_plane_terms() {
    let seq = kitti_mini().join("sequences/01");
    let tmp = tempfile::tempdir().unwrap();
    let extra = ["--frames", "0..5", "--preset", "accurate"];
    let runs = poses_for_threads(&seq, &extra, tmp.path(), &[1, 2, 3]);
    assert_identical("kitti-mini 01, accurate preset", &runs, 5);
    let default = poses_for_threads(&seq, &["--frames", "0..5"], tmp.path(), &[1]);
    assert_ne!(
        default[0].1, runs[0].1,
        "the preset's poses are not the default's"
    );
    // frames.csv: every frame after the first registered with point-to-plane terms.
    let csv = std::fs::read_to_string(
        tmp.path()
            .join(format!("threads-1{}/frames.csv", extra.join(""))),
    )
    .unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (planar, all) = (col("plane_correspondences"), col("correspondences"));
    let counts: Vec<(u64, u64)> = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[planar].parse().unwrap(), f[all].parse().unwrap())
        })
        .collect();
    println!("accurate preset, kitti-mini 01: (point-to-plane, all) correspondences {counts:?}");
    assert_eq!(counts[0].0, 0, "the first frame has no map");
    assert!(counts[1..].iter().all(|&(p, a)| p > 0 && p <= a));
}
