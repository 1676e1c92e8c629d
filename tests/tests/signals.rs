//! SIGINT and SIGTERM sent to a real `kiss-odom` process: `run` stops after the
//! current frame, writes what it has (poses up to that frame, `frames.csv`, `summary.json`
//! with `"interrupted": true`), leaves no temporary file and exits with 128 + the signal;
//! `simulate` leaves no partial data set; help written into a pipe whose reader is gone is no
//! panic. These need the binary (`kiss-odom-cli`, this package's
//! copy of the command).
#![cfg(target_os = "linux")]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

/// A generic folder of `n` real scans, links to the 10 of the KITTI sample forth and back, so
/// the motion stays smooth and the run takes seconds.
fn long_dataset(root: &Path, n: usize) -> PathBuf {
    let sample = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/kitti-05-reduced");
    let sample = sample.canonicalize().unwrap().join("velodyne");
    let frames = root.join("velodyne");
    std::fs::create_dir_all(&frames).unwrap();
    for k in 0..n {
        let (lap, i) = (k / 10, k % 10);
        let scan = if lap % 2 == 0 { i } else { 9 - i };
        let target = sample.join(format!("{scan:06}.bin"));
        std::os::unix::fs::symlink(target, frames.join(format!("{k:06}.bin"))).unwrap();
    }
    root.to_path_buf()
}

/// CPU seconds the process has used (utime + stime of `/proc/PID/stat`, at the kernel's
/// 100 ticks a second).
fn cpu_seconds(pid: u32) -> Option<f64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let ticks: u64 = fields.get(11)?.parse::<u64>().ok()? + fields.get(12)?.parse::<u64>().ok()?;
    Some(ticks as f64 / 100.0)
}

/// Waits until `ready` holds; fails if the child exits first or after five minutes (a hang
/// guard, not a speed check).
fn wait_until(child: &mut Child, what: &str, mut ready: impl FnMut() -> bool) {
    let ok = kiss_odom_tests::wait_until(Duration::from_secs(300), || {
        if ready() {
            return true;
        }
        if let Some(status) = child.try_wait().unwrap() {
            panic!("the process ended ({status}) before {what}");
        }
        false
    });
    assert!(ok, "{what}: no progress");
}

fn signal(child: &Child, name: &str) {
    let ok = Command::new("kill")
        .args([format!("-{name}"), child.id().to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok, "kill -{name}");
}

/// Lines of a text output, its `#` comment lines (the TUM file's header) left out.
fn lines(path: &Path) -> usize {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .filter(|l| !l.starts_with('#'))
        .count()
}

#[test]
fn an_interrupted_run_writes_the_frames_so_far_and_exits_with_the_signal() {
    let dir = tempfile::tempdir().unwrap();
    let total = 600;
    let data = long_dataset(&dir.path().join("data"), total);
    for (name, number) in [("INT", 2), ("TERM", 15)] {
        let out = dir.path().join(format!("out-{name}"));
        let tmp = dir.path().join(format!("tmp-{name}"));
        std::fs::create_dir(&tmp).unwrap();
        let mut child = Command::new(env!("CARGO_BIN_EXE_kiss-odom-cli"))
            .arg("run")
            .arg(&data)
            .arg("--out")
            .arg(&out)
            .args(["--threads", "1", "--quiet"])
            .env("TMPDIR", &tmp)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // A third of a second of CPU: well into the frames (5-25 ms each), far from the end.
        let pid = child.id();
        wait_until(&mut child, "a third of a second of frames", || {
            cpu_seconds(pid).is_some_and(|s| s >= 0.3)
        });
        signal(&child, name);
        let result = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(128 + number), "{name}: {stderr}");
        assert!(stderr.contains("interrupted by signal"), "{stderr}");

        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        let frames = summary["frames"].as_u64().unwrap() as usize;
        println!("SIG{name}: stopped after {frames} of {total} frames");
        assert_eq!(summary["interrupted"], true);
        assert!(summary["stop_reason"].is_null(), "{summary:#}");
        assert!(frames > 0 && frames < total, "{frames} frames");
        assert_eq!(lines(&out.join("poses_kitti.txt")), frames);
        assert_eq!(lines(&out.join("poses_tum.txt")), frames);
        assert_eq!(
            lines(&out.join("frames.csv")),
            frames + 1,
            "header and rows"
        );
        assert!(out.join("trajectory.png").is_file());
        let hidden: Vec<_> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .filter(|n| n.to_string_lossy().starts_with('.'))
            .collect();
        assert!(hidden.is_empty(), "temporary files left: {hidden:?}");
        assert_eq!(std::fs::read_dir(&tmp).unwrap().count(), 0, "TMPDIR");
    }
}

#[test]
fn an_interrupted_simulate_leaves_no_data_set() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sim");
    let mut child = Command::new(env!("CARGO_BIN_EXE_kiss-odom-cli"))
        .arg("simulate")
        .arg("--out")
        .arg(&out)
        .args(["--frames", "400"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Two frames written in the staging folder: the simulation is under way.
    let second_frame = || {
        std::fs::read_dir(&out).ok().is_some_and(|entries| {
            entries
                .flatten()
                .any(|e| e.path().join("velodyne/000001.bin").is_file())
        })
    };
    wait_until(&mut child, "two simulated frames", second_frame);
    signal(&child, "TERM");
    let result = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(143), "{stderr}");
    let left: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(left.is_empty(), "an interrupted simulate left {left:?}");

    // And `run` finds nothing to take for a data set.
    let run = Command::new(env!("CARGO_BIN_EXE_kiss-odom-cli"))
        .arg("run")
        .arg(&out)
        .arg("--out")
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.contains("no frames"), "{stderr}");
}

#[test]
fn help_into_a_pipe_whose_reader_has_gone_ends_without_a_panic() {
    // `kiss-odom run --help | head -1`: the reader is gone before the help is written. Written
    // with `print!`, the help would panic (exit 101, a backtrace) when the write fails.
    let (reader, writer) = std::io::pipe().expect("a pipe");
    drop(reader);
    let out = Command::new(env!("CARGO_BIN_EXE_kiss-odom-cli"))
        .args(["run", "--help"])
        .stdout(writer)
        .stderr(Stdio::piped())
        .output()
        .expect("cannot start kiss-odom");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.code(), Some(0), "{stderr}");
}
