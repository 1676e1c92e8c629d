//! What the commands never replace: a file in an output folder that no earlier run of ours
//! wrote (or that was changed since) stays as it is, and the command refuses to start, naming
//! it; a file the user named (`--save-map`, `--save-cloud`, `--rerun`) is written, but never
//! two outputs to one file; `simulate --overwrite` replaces only a data set `simulate` wrote,
//! and checks all of it before it removes anything. Every case is refused before any frame
//! is read, so these tests are quick.

use crate::common;

use common::*;
use kiss_odom_tests::{kitti_copy, simulate};
use std::ffi::OsString;
use std::path::{Path, PathBuf};

fn sample() -> PathBuf {
    repo().join("fixtures/kitti-05-reduced")
}

/// Every file under `dir` (relative path and bytes), sorted: what must not change.
fn tree(dir: &Path) -> Vec<(String, Vec<u8>)> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<(String, Vec<u8>)>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(root, &path, out);
            } else {
                let name = path.strip_prefix(root).unwrap().display().to_string();
                out.push((name, std::fs::read(&path).unwrap()));
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

fn names(t: &[(String, Vec<u8>)]) -> Vec<&str> {
    t.iter().map(|(n, _)| n.as_str()).collect()
}

fn args(list: &[&dyn AsRef<std::ffi::OsStr>]) -> Vec<OsString> {
    list.iter().map(|a| a.as_ref().to_owned()).collect()
}

/// `kiss-odom ARGS` in process, expected to fail with exit 1 naming `file`; prints the error.
fn refused_naming(list: &[&dyn AsRef<std::ffi::OsStr>], file: &Path) -> String {
    let (code, stderr) = kiss_odom(args(list));
    let error = stderr
        .lines()
        .find(|l| l.starts_with("error: "))
        .unwrap_or_default()
        .to_string();
    assert_eq!(code, 1, "exit status; stderr:\n{stderr}");
    assert!(
        error.contains(&file.display().to_string()),
        "the error names {}: {stderr}",
        file.display()
    );
    println!("{error}");
    error
}

/// Runs `command`, which must be refused (exit 1) with an error containing `named`, and leave
/// `folder` as it was.
fn refused_leaving(folder: &Path, command: Vec<OsString>, named: &str) {
    let before = tree(folder);
    let (code, stderr) = kiss_odom(command);
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains(named), "{named:?} in {stderr}");
    println!("{}", stderr.trim());
    assert_eq!(tree(folder), before, "nothing removed");
}

/// A small sensor: each simulated frame takes milliseconds.
const SMALL: [&str; 4] = ["--beams", "8", "--columns", "128"];

#[test]
fn convert_replaces_no_file_already_in_its_output_folder() {
    let dir = tempfile::tempdir().unwrap();
    // A recording whose conversion writes all four: frames, per-point stamps, times, IMU.
    let sim = dir.path().join("sim");
    simulate(
        &sim,
        &[&SMALL[..], &["--frames", "2", "--imu-rate", "100"]].concat(),
    );
    for name in ["imu.csv", "times.txt", "timestamps/000000.bin"] {
        let out = dir.path().join(format!("out-{}", name.replace('/', "-")));
        let file = out.join(name);
        std::fs::create_dir_all(file.parent().unwrap()).unwrap();
        std::fs::write(&file, "the user's own").unwrap();
        let before = tree(&out);
        refused_naming(&[&"convert", &sim, &"--out", &out, &"--quiet"], &file);
        assert_eq!(tree(&out), before, "{name}: the folder is as it was");
    }
    // An empty frame folder, or none, is a new conversion: all four written.
    let out = dir.path().join("fresh");
    std::fs::create_dir_all(out.join("velodyne")).unwrap();
    let (code, stderr) = kiss_odom(args(&[&"convert", &sim, &"--out", &out, &"--quiet"]));
    assert_eq!(code, 0, "{stderr}");
    let written = tree(&out);
    assert_eq!(
        names(&written),
        [
            "imu.csv",
            "times.txt",
            "timestamps/000000.bin",
            "timestamps/000001.bin",
            "velodyne/000000.bin",
            "velodyne/000001.bin"
        ]
    );
}

#[test]
fn simulate_overwrite_checks_everything_before_it_removes_anything() {
    let dir = tempfile::tempdir().unwrap();
    let sim = dir.path().join("sim");
    simulate(&sim, &[&SMALL[..], &["--frames", "3"]].concat());
    let again = |out: &Path| {
        let mut a: Vec<OsString> = vec!["simulate".into(), "--out".into(), out.into()];
        a.extend(
            SMALL
                .iter()
                .chain(&["--frames", "2", "--overwrite"])
                .map(OsString::from),
        );
        a
    };

    // A file in the frame folder that is not a frame: refused, the old data set whole.
    let notes = sim.join("velodyne/notes.txt");
    std::fs::write(&notes, "keep").unwrap();
    refused_leaving(&sim, again(&sim), &notes.display().to_string());
    std::fs::remove_file(&notes).unwrap();

    // A file of a name simulate writes that this data set's sim.toml does not list.
    let imu = sim.join("imu.csv");
    std::fs::write(&imu, "the user's own").unwrap();
    refused_leaving(&sim, again(&sim), &imu.display().to_string());
    std::fs::remove_file(&imu).unwrap();

    // A data set simulate did not write (KITTI's): refused whole.
    let kitti = kitti_copy(dir.path(), "kitti");
    refused_leaving(&kitti, again(&kitti), "sim.toml");

    // A layout's folder simulate did not write: refused, the folder kept.
    let mulran = dir.path().join("mulran");
    let scan = mulran.join("Ouster/1000.bin");
    std::fs::create_dir_all(scan.parent().unwrap()).unwrap();
    std::fs::write(&scan, "a real scan").unwrap();
    let before = tree(&mulran);
    let (code, stderr) = kiss_odom(args(&[
        &"simulate",
        &"--out",
        &mulran,
        &"--layout",
        &"mulran",
        &"--beams",
        &"8",
        &"--columns",
        &"128",
        &"--frames",
        &"2",
        &"--overwrite",
    ]));
    assert_eq!(code, 1, "{stderr}");
    println!("{}", stderr.trim());
    assert_eq!(tree(&mulran), before, "nothing removed");

    // Its own data set, checked, is replaced whole: no frame of the longer one stays.
    let (code, stderr) = kiss_odom(again(&sim));
    assert_eq!(code, 0, "{stderr}");
    let after = tree(&sim);
    assert_eq!(
        names(&after),
        [
            "poses.txt",
            "sim.toml",
            "times.txt",
            "timestamps/000000.bin",
            "timestamps/000001.bin",
            "velodyne/000000.bin",
            "velodyne/000001.bin"
        ]
    );
}

#[test]
fn save_map_and_save_cloud_on_one_file_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let map = dir.path().join("map.ply");
    std::fs::write(&map, "the user's own").unwrap();
    // The same file under two spellings.
    let other = dir.path().join("sub/../map.ply");
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    for (a, b) in [(&map, &map), (&map, &other)] {
        let line = refused_naming(
            &[
                &"run",
                &sample(),
                &"--out",
                &out,
                &"--quiet",
                &"--frames",
                &"0..2",
                &"--save-map",
                a,
                &"--save-cloud",
                b,
            ],
            a,
        );
        assert!(
            line.contains("--save-map") && line.contains("--save-cloud"),
            "{line}"
        );
        assert_eq!(std::fs::read(&map).unwrap(), b"the user's own");
        assert!(!out.exists(), "a refused run writes nothing");
    }
}

#[test]
fn run_replaces_no_file_in_out_that_it_did_not_write() {
    let dir = tempfile::tempdir().unwrap();
    let quick = ["--frames", "0..2"];

    // A hand-written config.toml in --out, and the data set's own when --out is the data set.
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let config = out.join("config.toml");
    std::fs::write(&config, "# mine\n[data]\nmax_range = 50.0\n").unwrap();
    let hand_written = tree(&out);
    let r = run(&sample(), &out, &quick);
    r.failed_naming(&config);
    println!("{}", r.errors()[0]);
    assert_eq!(tree(&out), hand_written, "nothing written or removed");
    // Given as --config too, it is read, and still not replaced.
    let r = run(
        &sample(),
        &out,
        &["--frames", "0..2", "--config", config.to_str().unwrap()],
    );
    r.failed_naming(&config);
    assert_eq!(tree(&out), hand_written, "nothing written or removed");

    let kitti = kitti_copy(dir.path(), "kitti");
    std::fs::write(kitti.join("config.toml"), "[data]\nmax_range = 80.0\n").unwrap();
    let dataset = tree(&kitti);
    run(&kitti, &kitti, &quick).failed_naming(&kitti.join("config.toml"));
    assert_eq!(tree(&kitti), dataset, "the data set is as it was");

    // Every other output name, the user's: refused naming it.
    std::fs::remove_file(&config).unwrap();
    for name in kiss_odom::run::OUTPUTS {
        let file = out.join(name);
        std::fs::write(&file, "the user's own").unwrap();
        run(&sample(), &out, &quick).failed_naming(&file);
        assert_eq!(std::fs::read(&file).unwrap(), b"the user's own", "{name}");
        assert_eq!(std::fs::read_dir(&out).unwrap().count(), 1, "{name}");
        std::fs::remove_file(&file).unwrap();
    }

    // A run's own outputs are replaced by the next run; one changed since is not.
    run(&sample(), &out, &quick).succeeded_with_frames(2);
    run(&sample(), &out, &quick).succeeded_with_frames(2);
    let poses = out.join("poses_kitti.txt");
    let mut edited = std::fs::read(&poses).unwrap();
    edited.extend_from_slice(b"1 0 0 0 0 1 0 0 0 0 1 0\n");
    std::fs::write(&poses, &edited).unwrap();
    let before = tree(&out);
    run(&sample(), &out, &quick).failed_naming(&poses);
    assert_eq!(tree(&out), before, "nothing written or removed");
}

#[test]
fn live_and_listen_poses_replace_no_file_they_did_not_write() {
    let dir = tempfile::tempdir().unwrap();
    for (command, name) in [
        ("live", "config.toml"),
        ("listen-poses", "frames.csv"),
        ("listen-poses", "summary.json"),
    ] {
        let out = dir.path().join(format!("{command}-{name}"));
        std::fs::create_dir(&out).unwrap();
        let file = out.join(name);
        std::fs::write(&file, "the user's own").unwrap();
        let list: Vec<&dyn AsRef<std::ffi::OsStr>> = match command {
            "live" => vec![
                &"live",
                &"--udp",
                &"127.0.0.1:0",
                &"--idle-timeout",
                &"0.2",
                &"--quiet",
                &"--out",
                &out,
            ],
            _ => vec![
                &"listen-poses",
                &"--bind",
                &"127.0.0.1:0",
                &"--idle",
                &"0.2",
                &"--quiet",
                &"--out",
                &out,
            ],
        };
        refused_naming(&list, &file);
        assert_eq!(
            std::fs::read(&file).unwrap(),
            b"the user's own",
            "{command}"
        );
        assert_eq!(std::fs::read_dir(&out).unwrap().count(), 1, "{command}");
    }
}
