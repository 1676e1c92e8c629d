//! `kiss-odom run --map` end to end: a map built from a simulated drive's ground truth
//! localizes the revisit (the same scene driven the other way, objects moved) within a few
//! centimetres of its ground truth in the map frame, where odometry alone drifts; a map that
//! cannot be used refuses the run naming why; a damaged tile is skipped with a warning.

use crate::common::kiss_odom;
use kiss_odom_core::prior_map::{TileMap, HEADER_LEN, INDEX_ENTRY_LEN};
use kiss_odom_tests::Run;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

const FRAMES: &str = "60";

/// A first run, its revisit and the map of the first run: the folder, the revisit, the map.
fn site(tmp: &Path) -> (PathBuf, PathBuf) {
    let (a, b) = (tmp.join("a"), tmp.join("b"));
    let args = ["--profile", "urban", "--seed", "5", "--frames", FRAMES];
    kiss_odom_tests::simulate(&a, &args);
    kiss_odom_tests::simulate(&b, &[&args[..], &["--revisit"]].concat());
    let map = tmp.join("site.komap");
    let build: Vec<OsString> = ["map", "build"]
        .iter()
        .map(OsString::from)
        .chain([
            a.clone().into(),
            "--poses".into(),
            a.join("poses.txt").into(),
        ])
        .chain(["--out".into(), map.clone().into()])
        .collect();
    let (code, err) = kiss_odom(build);
    assert_eq!(code, 0, "{err}");
    (b, map)
}

fn run(data: &Path, out: &Path, extra: &[&str]) -> Run {
    kiss_odom_tests::run(data, out, &[&["--threads", "1"], extra].concat())
}

fn positions(path: &Path) -> Vec<[f64; 3]> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [v[3], v[7], v[11]]
        })
        .collect()
}

#[test]
fn a_revisit_is_localized_in_the_first_runs_map_in_the_map_frame() {
    let tmp = tempfile::tempdir().unwrap();
    let (b, map) = site(tmp.path());
    let start = std::fs::read_to_string(b.join("initial_pose.txt")).unwrap();
    let out = tmp.path().join("loc");
    let map = map.to_str().unwrap();
    let r = run(&b, &out, &["--map", map, "--initial-pose", start.trim()]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let truth = positions(&b.join("poses.txt"));
    let est = positions(&out.join("poses_kitti.txt"));
    let states = r.column("localization");
    assert_eq!((est.len(), states.len()), (truth.len(), truth.len()));
    let err: Vec<f64> = est
        .iter()
        .zip(&truth)
        .map(|(e, t)| {
            ((e[0] - t[0]).powi(2) + (e[1] - t[1]).powi(2) + (e[2] - t[2]).powi(2)).sqrt()
        })
        .collect();
    let worst = err.iter().cloned().fold(0.0, f64::max);
    let localized = states.iter().filter(|s| *s == "localized").count();
    println!(
        "worst map-frame error {worst:.3} m (limit 0.5), {localized} of {} localized",
        states.len()
    );
    assert!(worst < 0.5);
    assert!(localized >= states.len() - 3, "{states:?}");
    assert!(states
        .iter()
        .all(|s| ["localized", "degraded", "lost"].contains(&s.as_str())));
    assert_eq!(r.number("localization.localized"), localized as f64);
    assert!(r.number("localization.held_points") > 1000.0);
    // Odometry alone starts at the identity: its poses are not in the map frame at all.
    let odo = run(&b, &tmp.path().join("odo"), &[]);
    assert_eq!(odo.code, 0, "{}", odo.stderr);
    let first = positions(&tmp.path().join("odo/poses_kitti.txt"))[0];
    assert!(first.iter().all(|v| v.abs() < 1e-9));
    assert!(odo.column("localization").iter().all(String::is_empty));
}

#[test]
fn a_map_that_cannot_be_used_refuses_the_run_naming_why_and_a_damaged_tile_is_skipped() {
    let tmp = tempfile::tempdir().unwrap();
    let (b, map) = site(tmp.path());
    let start = std::fs::read_to_string(b.join("initial_pose.txt")).unwrap();
    let bytes = std::fs::read(&map).unwrap();
    let with = |name: &str, data: &[u8], extra: &[&str]| {
        let path = tmp.path().join(name);
        std::fs::write(&path, data).unwrap();
        let mut args = vec![
            "--map",
            path.to_str().unwrap(),
            "--initial-pose",
            start.trim(),
        ];
        args.extend(extra);
        let r = run(&b, &tmp.path().join(format!("out-{name}")), &args);
        (r.code, r.stderr.replace('\n', " "))
    };
    let (code, err) = with("short.komap", &bytes[..bytes.len() - 1], &[]);
    assert!(code == 1 && err.contains("truncated"), "{err}");
    let (code, err) = with("ok.komap", &bytes, &["--set", "mapping.voxel_size=0.5"]);
    assert!(code == 1 && err.contains("voxel size"), "{err}");
    let (code, err) = with("ok2.komap", &bytes, &["--set", "output.map_frame=site"]);
    assert!(code == 1 && err.contains("frame"), "{err}");
    let mut header = bytes.clone();
    header[20] ^= 1;
    let (code, err) = with("header.komap", &header, &[]);
    assert!(code == 1 && err.contains("header"), "{err}");
    let r = run(
        &b,
        &tmp.path().join("no-pose"),
        &["--map", map.to_str().unwrap()],
    );
    assert!(
        r.code == 1 && r.stderr.contains("--initial-pose"),
        "{}",
        r.stderr
    );
    // One tile's record damaged: the run goes on, warned once.
    let file = TileMap::open(&bytes).unwrap();
    let records = HEADER_LEN + file.len() * INDEX_ENTRY_LEN;
    let mut tile = bytes.clone();
    tile[records + 30] ^= 1;
    let (code, err) = with("tile.komap", &tile, &[]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(err.matches("damaged tile").count(), 1, "{err}");
}
