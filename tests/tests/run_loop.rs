//! The rules of the run loop (the book's failure reference), end to end through the
//! command line in-process: thread counts are capped, the reason a run stopped is never masked
//! by an output error, a run that registered nothing fails, a setting out of range is named,
//! no output of an earlier command survives beside a failed one, and `frames.csv` says where
//! each row came from and which flags the core set. Signals sent to a real process are in
//! `tests/tests/signals.rs`.

use crate::common;

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
    let left = kiss_odom_io::write::temporaries_in(dir);
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
    let r = run(
        &data,
        &dir.path().join("out-strict"),
        &["--set", "output.strict=true"],
    );
    let line = r.failed_naming(&bad);
    assert!(
        line.contains("output.strict") && !line.contains("plot"),
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
        (
            &["--set", "mapping.voxel_size=-1"],
            "mapping.voxel_size = -1.0",
        ),
        (&["--set", "data.min_range=200"], "data.min_range = 200.0"),
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
    let r = run(
        &sample(),
        &dir.path().join("out"),
        &["--set", "mapping.voxel_size=1e6"],
    );
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

/// `kiss-odom-cli COMMAND INPUT --out OUT --quiet` as its own process, with writes past `kib`
/// KiB refused as on a full disk (`ulimit -f`, SIGXFSZ ignored so the write fails with EFBIG
/// instead of killing it).
fn with_file_limit(kib: u32, command: &str, input: &Path, out: &Path) -> std::process::Output {
    // `ulimit -f` counts 512-byte blocks in dash, 1024-byte blocks in bash: ask for KiB in
    // blocks of 512, so either shell allows at most `2 * kib` KiB.
    let blocks = (2 * kib).to_string();
    std::process::Command::new("sh")
        .args(["-c", "trap '' XFSZ; ulimit -f \"$0\"; exec \"$@\"", &blocks])
        .arg(env!("CARGO_BIN_EXE_kiss-odom-cli"))
        .arg(command)
        .arg(input)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .output()
        .unwrap()
}

#[test]
fn a_refused_argument_leaves_every_file_it_names_and_the_earlier_outputs_in_place() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    run(&sample(), &out, &["--frames", "0..2"]).succeeded_with_frames(2);
    let earlier = std::fs::read(out.join("summary.json")).unwrap();
    let notes = dir.path().join("notes.txt");
    let rrd = dir.path().join("old.rrd");
    let recording = dir.path().join("old.txt");
    for f in [&notes, &rrd, &recording] {
        std::fs::write(f, "keep me").unwrap();
    }
    let (notes_s, rrd_s, rec_s) = (
        notes.to_str().unwrap(),
        rrd.to_str().unwrap(),
        recording.to_str().unwrap(),
    );
    let mut cases: Vec<Vec<&str>> = vec![
        vec!["--save-map", notes_s],
        vec!["--save-cloud", notes_s],
        vec!["--save-cloud", "cloud.ply", "--set", "output.cloud_voxel=0"],
        vec!["--rerun", rec_s],
        vec!["--max-range", "0", "--save-map", notes_s],
    ];
    if !cfg!(feature = "rerun") {
        // This build cannot record: refused before the earlier recording goes.
        cases.push(vec!["--rerun", rrd_s]);
    }
    // An output over a frame of the run's own dataset (a folder of PLY frames).
    let frames = dir.path().join("ply");
    std::fs::create_dir(&frames).unwrap();
    for k in 0..3 {
        kiss_odom_io::folders::ply::write(
            &frames.join(format!("{k:06}.ply")),
            &kitti_points(k),
            None,
        )
        .unwrap();
    }
    let frame = frames.join("000002.ply");
    let frame_s = frame.to_str().unwrap().to_string();
    let map_over_input = ["--save-map", &frame_s];
    for flags in &cases {
        let r = run(&sample(), &out, flags);
        assert_eq!(r.code, 1, "{flags:?}: stderr:\n{}", r.stderr);
        println!("{flags:?}: {}", r.errors()[0]);
        for f in [&notes, &rrd, &recording] {
            assert_eq!(
                std::fs::read(f).unwrap(),
                b"keep me",
                "{flags:?}: {}",
                f.display()
            );
        }
        assert_eq!(
            std::fs::read(out.join("summary.json")).unwrap(),
            earlier,
            "{flags:?}: a refused run changes no output"
        );
    }
    let before = std::fs::read(&frame).unwrap();
    let r = run(&frames, &out, &map_over_input);
    let line = r.failed_naming(&frame);
    assert!(line.contains("input"), "{line}");
    assert_eq!(std::fs::read(&frame).unwrap(), before);
}

#[test]
fn a_config_in_the_output_folder_is_read_before_the_folder_is_cleared() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let first = run(&sample(), &out, &["--frames", "0..4", "--max-range", "60"]);
    first.succeeded_with_frames(4);
    let (poses, config) = (
        std::fs::read(out.join("poses_kitti.txt")).unwrap(),
        std::fs::read(out.join("config.toml")).unwrap(),
    );
    let again = out.join("config.toml");
    let r = run(
        &sample(),
        &out,
        &["--frames", "0..4", "--config", again.to_str().unwrap()],
    );
    r.succeeded_with_frames(4);
    assert_eq!(std::fs::read(out.join("poses_kitti.txt")).unwrap(), poses);
    assert_eq!(std::fs::read(out.join("config.toml")).unwrap(), config);
}

#[test]
fn summary_json_is_written_when_the_disk_fills_and_names_the_output_that_failed() {
    let dir = tempfile::tempdir().unwrap();
    // The plots (150-300 KB) do not fit under the limit; the small files do.
    let out = dir.path().join("out-full");
    let o = with_file_limit(32, "run", &sample(), &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    println!("{stderr}");
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("trajectory.png"),
        "the error names the file: {stderr}"
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let reason = s["stop_reason"].as_str().unwrap_or_default();
    assert!(
        reason.contains("outputs incomplete") && reason.contains("trajectory.png"),
        "{s:#}"
    );
    assert_eq!(s["frames"], 10);
    assert!(!out.join("trajectory.png").exists());
    assert_no_temporaries(&out);
}

#[test]
fn convert_on_a_full_disk_leaves_whole_frames_only() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("converted");
    // A frame is 318 KiB: the first one cannot be written whole.
    let o = with_file_limit(32, "convert", &sample(), &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    println!("{stderr}");
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("000000.bin"),
        "the error names the frame: {stderr}"
    );
    for entry in std::fs::read_dir(out.join("velodyne")).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let whole = std::fs::metadata(sample().join("velodyne").join(&name)).map(|m| m.len());
        assert_eq!(
            std::fs::metadata(&path).unwrap().len(),
            whole.unwrap_or(u64::MAX),
            "{name}: a frame cut short (or a temporary) is left"
        );
    }
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
    let cases: [(&[&str], &str); 4] = [
        (
            &["--config", config.to_str().unwrap()],
            "data.max_range = nan",
        ),
        (
            &["--set", "registration.plane_gate=inf"],
            "registration.plane_gate = inf",
        ),
        (
            &["--set", "mapping.voxel_size=nan"],
            "mapping.voxel_size = nan",
        ),
        (&["--max-range", "NaN"], "data.max_range = nan"),
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
