//! The rules of the run loop (README, "Failure behaviour"; issue 12), end to end through the
//! command line in-process: thread counts are capped, the reason a run stopped is never masked
//! by an output error, a run that registered nothing fails, a setting out of range is named,
//! no output of an earlier command survives beside a failed one, and `frames.csv` says where
//! each row came from and which flags the core set. Signals sent to a real process are in
//! `host/tests/interrupt.rs`.

mod common;

use common::*;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

fn sample() -> PathBuf {
    repo().join("fixtures/kitti-05-reduced")
}

/// The files a run writes that only exist when a frame was registered.
const POSE_OUTPUTS: [&str; 3] = ["poses_kitti.txt", "poses_tum.txt", "trajectory.png"];

fn assert_no_pose_outputs(r: &Run) {
    for name in POSE_OUTPUTS {
        assert!(
            !r.out.join(name).exists(),
            "{name} written for a run without poses; stderr:\n{}",
            r.stderr
        );
    }
}

fn assert_no_temporaries(dir: &Path) {
    let left = kiss_odom::output::temporaries_in(dir);
    assert!(left.is_empty(), "temporary files left: {left:?}");
}

#[test]
fn threads_above_the_machines_cores_are_capped_with_a_warning() {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let dir = tempfile::tempdir().unwrap();
    for asked in ["10000", "18446744073709551615"] {
        let out = dir.path().join(format!("out-{asked}"));
        let r = run(&sample(), &out, &["--frames", "0..2", "--threads", asked]);
        r.succeeded_with_frames(2);
        let w = r.warnings();
        assert_eq!(w.len(), 1, "stderr:\n{}", r.stderr);
        assert!(
            w[0].contains(asked) && w[0].contains(&format!("using {cores}")),
            "{}",
            w[0]
        );
        assert_eq!(r.summary()["input"]["threads"], cores, "threads used");
        assert_eq!(r.count("warnings"), 1);
    }
}

#[test]
fn a_run_without_poses_reports_its_own_reason_and_writes_no_pose_files() {
    let dir = tempfile::tempdir().unwrap();

    // An MCAP file cut inside its first message.
    let whole = std::fs::read(bag_fixture("ouster.mcap")).unwrap();
    let cut = dir.path().join("cut-first.mcap");
    std::fs::write(&cut, &whole[..ouster_payload_at(&whole, 0) + 40]).unwrap();
    let r = run(&cut, &dir.path().join("out-mcap"), &[]);
    let line = r.failed_naming(&cut);
    println!("{line}");
    assert!(line.contains("cut short"), "{line}");
    assert!(!line.contains("plot"), "{line}");
    assert_no_pose_outputs(&r);
    assert!(!r.out.join("frames.csv").exists(), "no empty frames.csv");
    let s = r.summary();
    assert_eq!(
        (s["frames"].as_u64(), s["interrupted"].as_bool()),
        (Some(0), Some(false))
    );
    assert!(
        s["stop_reason"].as_str().unwrap().contains("cut short"),
        "{s:#}"
    );

    // --strict with a bad first frame.
    let data = dir.path().join("data");
    let frames = bin_folder(&data, 3);
    let bad = frames.join("000000.bin");
    std::fs::write(&bad, &kitti_bytes(0)[..100]).unwrap();
    let r = run(&data, &dir.path().join("out-strict"), &["--strict"]);
    let line = r.failed_naming(&bad);
    assert!(
        line.contains("--strict") && !line.contains("plot"),
        "{line}"
    );
    assert_no_pose_outputs(&r);
    assert_eq!(r.count("frames"), 0);
}

#[test]
fn a_run_that_registers_no_frame_exits_1_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    // Every frame unreadable.
    let broken = dir.path().join("broken");
    let frames = velodyne(&broken);
    for k in 0..3 {
        std::fs::write(frames.join(format!("{k:06}.bin")), [0u8; 7]).unwrap();
    }
    // Every frame without a point within range (all at 500 m).
    let far = dir.path().join("far");
    let frames = velodyne(&far);
    let point: Vec<u8> = [500.0f32, 0.0, 0.0, 0.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    for k in 0..3 {
        std::fs::write(frames.join(format!("{k:06}.bin")), point.repeat(10)).unwrap();
    }
    for (data, kind) in [(&broken, "skipped_frames"), (&far, "empty_frames")] {
        let r = run(data, &dir.path().join(format!("out-{kind}")), &[]);
        let line = r.failed_naming(data);
        println!("{line}");
        assert!(line.contains("no frame could be registered"), "{line}");
        assert_eq!(r.count(kind), 3, "{kind}");
        assert_eq!(r.count("registered_frames"), 0);
        assert_eq!(
            r.rows().len(),
            3,
            "frames.csv still says what became of each"
        );
        assert_no_pose_outputs(&r);
    }
}

#[test]
fn a_setting_out_of_range_is_named_in_the_error() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("bad.toml");
    std::fs::write(&config, "[registration]\nkernel_scale = 0.0\n").unwrap();
    let cases: [(&[&str], &str); 4] = [
        (
            &["--config", config.to_str().unwrap()],
            "registration.kernel_scale = 0.0",
        ),
        (&["--voxel-size", "-1"], "mapping.voxel_size = -1.0"),
        (&["--min-range", "200"], "data.min_range = 200.0"),
        (&["--max-range", "0"], "data.max_range = 0.0"),
    ];
    for (flags, named) in cases {
        let r = run(&sample(), &dir.path().join("out"), flags);
        assert_eq!(r.code, 1, "{flags:?}");
        let errors = r.errors();
        assert_eq!(errors.len(), 1, "stderr:\n{}", r.stderr);
        assert!(errors[0].contains(named), "{flags:?}: {}", errors[0]);
        println!("{}", errors[0]);
    }
}

#[test]
fn a_failed_run_leaves_no_output_of_an_earlier_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    run(&sample(), &out, &["--frames", "0..3"]).succeeded_with_frames(3);
    for name in POSE_OUTPUTS {
        assert!(out.join(name).is_file(), "{name}");
    }
    // A temporary file a killed run could not clean up.
    std::fs::write(out.join(".kiss-odom-tmp-summary.json-x1y2z3"), "half").unwrap();

    // Another dataset, every frame unreadable, into the same folder.
    let broken = dir.path().join("broken");
    std::fs::write(velodyne(&broken).join("000000.bin"), [0u8; 7]).unwrap();
    let r = run(&broken, &out, &[]);
    assert_eq!(r.code, 1, "stderr:\n{}", r.stderr);
    assert_no_pose_outputs(&r);
    assert_no_temporaries(&out);
    let s = r.summary();
    assert_eq!(s["input"]["path"], broken.display().to_string(), "{s:#}");
    assert_eq!(r.rows().len(), 1, "this run's frames.csv");

    // A run refused before it starts removes them too.
    run(&sample(), &out, &["--frames", "0..2"]).succeeded_with_frames(2);
    let r = run(&dir.path().join("missing"), &out, &[]);
    assert_eq!(r.code, 1);
    for name in kiss_odom::run::OUTPUTS {
        assert!(
            !out.join(name).exists(),
            "{name} of the earlier run is left"
        );
    }
}

#[test]
fn json_outputs_of_bench_and_crosscheck_do_not_survive_a_failed_command() {
    let dir = tempfile::tempdir().unwrap();
    let missing: OsString = dir.path().join("missing").into();
    for command in ["bench", "crosscheck"] {
        let json = dir.path().join(format!("{command}.json"));
        std::fs::write(&json, "{\"passed\": true}").unwrap();
        let (code, stderr) = kiss_odom(vec![
            command.into(),
            missing.clone(),
            "--json".into(),
            json.clone().into(),
            "--python".into(),
            "/nonexistent/python".into(),
        ]);
        assert_eq!(code, 1, "{command}: {stderr}");
        assert!(!json.exists(), "{command}: the earlier JSON is left");
    }
}

#[test]
fn a_huge_voxel_marks_frames_degenerate_in_frames_csv_and_summary() {
    let dir = tempfile::tempdir().unwrap();
    let r = run(&sample(), &dir.path().join("out"), &["--voxel-size", "1e6"]);
    r.succeeded_with_frames(10);
    let rows = r.rows();
    for row in &rows {
        let degenerate = row.flags.iter().any(|f| f == "degenerate");
        assert_eq!(degenerate, row.index > 0, "{row:?}");
    }
    let s = r.summary();
    assert_eq!(s["degraded_frames"]["degenerate"], 9, "{s:#}");
}

#[test]
fn frames_csv_names_the_source_of_every_row() {
    let dir = tempfile::tempdir().unwrap();
    let r = run(&sample(), &dir.path().join("out"), &["--frames", "2..5"]);
    r.succeeded_with_frames_from(2, 3);
    for row in r.rows() {
        let file = sample().join(format!("velodyne/{:06}.bin", row.index));
        assert_eq!(row.source, file.display().to_string(), "{row:?}");
    }
    let bag = bag_fixture("ouster.bag");
    let r = run(&bag, &dir.path().join("out-bag"), &[]);
    r.succeeded_with_frames(4);
    let mut sources: Vec<String> = r.rows().into_iter().map(|row| row.source).collect();
    println!("{sources:?}");
    for s in &sources {
        assert!(
            s.starts_with(&bag.display().to_string()) && s.contains('@'),
            "{s}"
        );
    }
    sources.dedup();
    assert_eq!(sources.len(), 4, "one message each");
}

#[test]
fn a_simulate_killed_midway_leaves_no_data_set_and_its_staging_folder_goes_next_time() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sim");
    // What a SIGKILLed simulate leaves: a hidden staging folder with some frames.
    let staging = out.join(".kiss-odom-simulate-abc123");
    std::fs::create_dir_all(staging.join("velodyne")).unwrap();
    std::fs::write(staging.join("velodyne/000000.bin"), kitti_bytes(0)).unwrap();
    // `run` does not take it for a data set.
    let r = run(&out, &dir.path().join("out"), &[]);
    assert_eq!(r.code, 1, "stderr:\n{}", r.stderr);
    assert!(r.errors()[0].contains("no frames"), "{}", r.stderr);
    // The next simulate removes it and writes a whole data set.
    let small = ["--beams", "8", "--columns", "128", "--frames", "3"];
    let mut args: Vec<OsString> = vec!["simulate".into(), "--out".into(), out.clone().into()];
    args.extend(small.iter().map(OsString::from));
    let (code, stderr) = kiss_odom(args);
    assert_eq!(code, 0, "{stderr}");
    assert!(!staging.exists());
    let left: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(left.is_empty(), "{left:?}");
    assert_eq!(std::fs::read_dir(out.join("velodyne")).unwrap().count(), 3);
}

#[test]
fn kiss_icps_yaml_config_is_read_with_its_meaning() {
    let dir = tempfile::tempdir().unwrap();
    let yaml = dir.path().join("kiss.yaml");
    std::fs::write(
        &yaml,
        "out_dir: results\ndata:\n  max_range: 60.0\n  deskew: true\nmapping:\n  voxel_size: null\n  \
         max_points_per_voxel: 10\nregistration:\n  max_num_threads: 1\n",
    )
    .unwrap();
    let from_yaml = dir.path().join("yaml");
    let r = run(
        &sample(),
        &from_yaml,
        &["--frames", "0..4", "--config", yaml.to_str().unwrap()],
    );
    r.succeeded_with_frames(4);
    let toml = dir.path().join("same.toml");
    std::fs::write(
        &toml,
        "[data]\nmax_range = 60.0\n[mapping]\nvoxel_size = 0.6\nmax_points_per_voxel = 10\n\
         [runtime]\nthreads = 1\n",
    )
    .unwrap();
    let from_toml = dir.path().join("toml");
    let r = run(
        &sample(),
        &from_toml,
        &["--frames", "0..4", "--config", toml.to_str().unwrap()],
    );
    r.succeeded_with_frames(4);
    for name in ["poses_kitti.txt", "config.toml"] {
        assert_eq!(
            std::fs::read_to_string(from_yaml.join(name)).unwrap(),
            std::fs::read_to_string(from_toml.join(name)).unwrap(),
            "{name}"
        );
    }
    // A YAML file under another name says how it was read.
    let misnamed = dir.path().join("kiss.conf");
    std::fs::copy(&yaml, &misnamed).unwrap();
    let r = run(
        &sample(),
        &dir.path().join("out"),
        &["--config", misnamed.to_str().unwrap()],
    );
    let line = r.failed_naming(&misnamed);
    assert!(
        line.contains("read as TOML") && line.contains(".yaml"),
        "{line}"
    );
}

#[test]
fn nan_and_inf_settings_are_refused_naming_the_setting() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("nan.toml");
    std::fs::write(&config, "[data]\nmax_range = nan\n").unwrap();
    let cases: [(&[&str], &str); 3] = [
        (
            &["--config", config.to_str().unwrap()],
            "data.max_range = nan",
        ),
        (&["--plane-gate", "inf"], "registration.plane_gate = inf"),
        (&["--voxel-size", "NaN"], "mapping.voxel_size = nan"),
    ];
    for (flags, named) in cases {
        let r = run(&sample(), &dir.path().join("out"), flags);
        assert_eq!(r.code, 1, "{flags:?}");
        let errors = r.errors();
        println!("{}", errors[0]);
        assert!(
            errors[0].contains(named) && errors[0].contains("not a finite number"),
            "{flags:?}: {}",
            errors[0]
        );
        assert!(!errors[0].contains("null"), "{}", errors[0]);
    }
}
