//! Dataset reading that needs a process of its own: a memory limit set with
//! `ulimit -v`, or a `TMPDIR` the run must not touch. The command runs as a child under `sh`,
//! so the limit applies to `kiss-odom run` alone.

use kiss_odom_tests::{kitti_copy, repo, Run};
use std::path::Path;
use std::process::Command;

/// Address-space limit of the memory test, KiB (`ulimit -v`): about 1 GB, half a 2 GiB frame.
const ADDRESS_SPACE_KIB: u64 = 1_000_000;

/// `kiss-odom run INPUT --out OUT --quiet` in a child process started by `sh -c` after the
/// shell commands `setup`, with the environment `env` added.
fn run_child(input: &Path, out: &Path, setup: &str, env: &[(&str, &Path)]) -> Run {
    let mut cmd = Command::new("sh");
    cmd.arg("-c")
        .arg(format!("{setup} exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_kiss-odom-cli"))
        .arg("run")
        .arg(input)
        .arg("--out")
        .arg(out)
        .arg("--quiet");
    for (k, v) in env {
        cmd.env(k, v);
    }
    let output = cmd.output().expect("cannot start the child");
    Run {
        code: output.status.code().unwrap_or(-1),
        stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
        out: out.to_path_buf(),
    }
}

/// A 2 GiB sparse file: `head` then zeros.
fn sparse(path: &Path, head: &[u8]) {
    std::fs::write(path, head).unwrap();
    let f = std::fs::OpenOptions::new().write(true).open(path).unwrap();
    f.set_len(2 << 30).unwrap();
}

/// A frame costs at most `scan_points` points of memory whatever its file's size: a 2 GB
/// `.bin` frame under a 1 GB address-space limit is truncated with a warning, where reading it
/// whole would abort the process and lose the run. The PLY and PCD readers are held to the same
/// bound.
#[test]
fn a_two_gigabyte_frame_is_truncated_with_a_warning_under_a_one_gigabyte_limit() {
    let dir = tempfile::tempdir().unwrap();
    let setup = format!("ulimit -v {ADDRESS_SPACE_KIB} &&");
    let scan = std::fs::read(repo().join("fixtures/kitti-05-reduced/velodyne/000005.bin")).unwrap();

    let data = kitti_copy(dir.path(), "bin");
    let big = data.join("velodyne/000005.bin");
    sparse(&big, &scan);
    let r = run_child(&data, &dir.path().join("out-bin"), &setup, &[]);
    r.ok()
        .warning_with(&["000005.bin", "first 262144 of 134217728 points"]);
    assert_eq!(r.number("frames"), 10.0);
    assert_eq!(r.number("skipped_frames"), 0.0);

    // The same for a binary PLY and PCD frame declaring 2 GiB of points.
    let xyz: Vec<u8> = scan
        .chunks_exact(16)
        .flat_map(|p| p[..12].to_vec())
        .collect();
    let n = (2u64 << 30) / 12 - 1024;
    let ply = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\n\
         property float y\nproperty float z\nend_header\n"
    );
    let pcd = format!(
        "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\n\
         VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA binary\n"
    );
    for (ext, header) in [("ply", ply), ("pcd", pcd)] {
        let folder = dir.path().join(ext);
        std::fs::create_dir_all(folder.join("velodyne")).unwrap();
        let mut head = header.into_bytes();
        head.extend_from_slice(&xyz);
        sparse(&folder.join(format!("velodyne/000000.{ext}")), &head);
        let r = run_child(&folder, &dir.path().join(format!("out-{ext}")), &setup, &[]);
        r.ok()
            .warning_with(&[&format!("000000.{ext}"), &format!("first 262144 of {n}")]);
        assert_eq!(r.number("frames"), 1.0, "{ext}");
    }
}

/// A damaged bag is read in place, not from a temporary copy: with no usable `TMPDIR` at all
/// the frames before the damage are still processed.
#[test]
fn a_damaged_bag_is_read_without_a_temporary_copy() {
    let dir = tempfile::tempdir().unwrap();
    let bag = repo().join("fixtures/bags/truncated.bag");
    let nowhere = dir.path().join("no-such-tmpdir");
    let r = run_child(&bag, &dir.path().join("out"), "", &[("TMPDIR", &nowhere)]);
    let line = r.failed_with(&["truncated.bag", "cut short"]);
    assert!(!line.contains("temporary"), "{line}");
    assert_eq!(
        r.lines("poses_kitti.txt").len(),
        3,
        "the frames before the damage"
    );
    assert!(!nowhere.exists());
}
