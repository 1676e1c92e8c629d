//! `kiss-odom map build` end to end: a simulated drive and its ground truth become a map file
//! that opens, has the run's default voxel size and holds every point of the first scan within
//! a voxel's diagonal; poses that do not match the frames are refused naming both counts.

use crate::common::kiss_odom;
use kiss_odom_core::prior_map::TileMap;
use kiss_odom_io::folders::bin;
use std::collections::HashSet;
use std::ffi::OsString;
use std::path::Path;

fn map_build(input: &Path, poses: &Path, out: &Path) -> (i32, String) {
    let args: Vec<OsString> = vec![
        "map".into(),
        "build".into(),
        input.into(),
        "--poses".into(),
        poses.into(),
        "--out".into(),
        out.into(),
    ];
    kiss_odom(args)
}

#[test]
fn a_simulated_drive_and_its_ground_truth_make_a_map_at_the_runs_voxel_size() {
    let tmp = tempfile::tempdir().unwrap();
    let sim = tmp.path().join("sim");
    kiss_odom_tests::simulate(
        &sim,
        &["--profile", "urban", "--seed", "3", "--frames", "20"],
    );
    let out = tmp.path().join("map.komap");
    let (code, err) = map_build(&sim, &sim.join("poses.txt"), &out);
    assert_eq!(code, 0, "{err}");
    let bytes = std::fs::read(&out).unwrap();
    let map = TileMap::open(&bytes).unwrap();
    let h = map.header();
    // The run's default: max_range 100 m / 100.
    assert_eq!(
        (h.voxel_size, h.tile_size, h.points_per_voxel),
        (1.0, 50.0, 5)
    );
    assert_eq!(h.frame_name(), "map");
    assert!(map.len() > 1, "a 100 m range spans tiles of 50 m");
    let mut voxels = HashSet::new();
    for t in 0..map.len() {
        for p in map.tile(t).unwrap().points() {
            voxels.insert(p.map(|c| c.floor() as i64));
        }
    }
    // The first pose is the identity (poses.txt is relative to the first) and the first
    // frame is not deskewed (no motion before it): its points are in the map frame as read.
    let scan = bin::parse(&std::fs::read(sim.join("velodyne/000000.bin")).unwrap()).unwrap();
    let missing = scan
        .iter()
        .filter(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() < 99.0)
        .filter(|p| !voxels.contains(&p.map(|c| c.floor() as i64)))
        .count();
    println!(
        "{missing} of {} first-scan points in no stored voxel",
        scan.len()
    );
    assert_eq!(missing, 0);
    // A second build gives the same bytes.
    let again = tmp.path().join("again.komap");
    assert_eq!(map_build(&sim, &sim.join("poses.txt"), &again).0, 0);
    assert!(std::fs::read(&again).unwrap() == bytes);
}

#[test]
fn poses_one_short_of_the_frames_are_refused_naming_both_counts() {
    let tmp = tempfile::tempdir().unwrap();
    let sim = tmp.path().join("sim");
    kiss_odom_tests::simulate(
        &sim,
        &["--profile", "urban", "--seed", "3", "--frames", "5"],
    );
    let text = std::fs::read_to_string(sim.join("poses.txt")).unwrap();
    let short = tmp.path().join("short.txt");
    let lines: Vec<&str> = text.lines().collect();
    std::fs::write(&short, lines[..lines.len() - 1].join("\n")).unwrap();
    let out = tmp.path().join("map.komap");
    let (code, err) = map_build(&sim, &short, &out);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("4 poses for 5 frames"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(!out.exists(), "nothing written");
}
