//! The live cross-check against the reference kiss-icp 1.3.0, run in-process through the CLI.
//!
//! `crosscheck_on_kitti_mini_05_is_within_every_tolerance` needs a Python with kiss-icp 1.3.0
//! in `KISS_ODOM_PYTHON` (a venv made from `tests/reference/requirements.txt`) and kitti-mini
//! (`KISS_ODOM_KITTI_MINI`, default `../shared/data/kitti-mini` beside the repository); without
//! them it prints why and passes without checking anything. The table and tolerance logic
//! itself is unit-tested in `host/cli/src/crosscheck/report.rs`.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn cli(args: &[&OsString]) -> (i32, String) {
    let mut argv: Vec<OsString> = vec!["kiss-odom-dev".into(), "crosscheck".into()];
    argv.extend(args.iter().map(|a| (*a).clone()));
    let mut err = Vec::new();
    let code = kiss_odom::dev::main_with(argv, &mut err);
    (code, String::from_utf8_lossy(&err).into_owned())
}

/// The Python to use, or why the live test cannot run.
fn reference_python() -> Result<OsString, String> {
    let py = std::env::var_os("KISS_ODOM_PYTHON")
        .ok_or("KISS_ODOM_PYTHON is not set (a Python with kiss-icp 1.3.0)")?;
    let ok = Command::new(&py)
        .args(["-c", "import kiss_icp, numpy"])
        .output()
        .map_err(|e| format!("cannot run {}: {e}", Path::new(&py).display()))?;
    if !ok.status.success() {
        return Err(format!(
            "{} cannot import kiss_icp",
            Path::new(&py).display()
        ));
    }
    Ok(py)
}

#[test]
fn crosscheck_on_kitti_mini_05_is_within_every_tolerance() {
    let python = match reference_python() {
        Ok(p) => p,
        Err(why) => {
            println!("SKIP: {why}");
            return;
        }
    };
    let data = std::env::var_os("KISS_ODOM_KITTI_MINI")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo().join("../shared/data/kitti-mini"));
    let seq = data.join("sequences/05");
    if !seq.is_dir() {
        println!(
            "SKIP: {} not found (set KISS_ODOM_KITTI_MINI)",
            seq.display()
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("crosscheck.json");
    let args: Vec<OsString> = vec![
        seq.into(),
        "--python".into(),
        python,
        "--driver".into(),
        repo().join("tests/reference/driver.py").into(),
        "--json".into(),
        json.clone().into(),
        "--quiet".into(),
    ];
    let (code, err) = cli(&args.iter().collect::<Vec<_>>());
    print!("{err}");
    let figures: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    // The table (every figure next to its tolerance) went to stdout, captured by the harness.
    let sections = figures["sections"].as_array().unwrap();
    let titles: Vec<&str> = sections
        .iter()
        .map(|s| s["title"].as_str().unwrap())
        .collect();
    for want in [
        "preprocessing",
        "downsampling",
        "correspondences",
        "adaptive threshold",
        "end to end",
    ] {
        assert!(
            titles.iter().any(|t| t.contains(want)),
            "no {want} section in {titles:?}"
        );
    }
    assert_eq!(code, 0, "a tolerance was exceeded:\n{err}");
    assert_eq!(figures["passed"], true);
}

#[test]
fn a_reference_that_cannot_run_is_an_error_not_a_pass() {
    let seq: OsString = repo().join("fixtures/kitti-05-reduced").into();
    let bad: OsString = "/nonexistent/python-for-kiss-odom".into();
    let flag: OsString = "--python".into();
    let (code, err) = cli(&[&seq, &flag, &bad]);
    assert_eq!(code, 1);
    assert!(err.contains("cannot start"), "{err}");
}
