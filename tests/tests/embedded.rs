//! Bare-metal runs against this workspace's build of the core.
//!
//! `embedded/run.sh` runs `kiss-odom-core` under QEMU on a Cortex-M4F (f32, quantised map,
//! `Capacities::SMALL`) and a Cortex-A53 (f64, exact map, `Capacities::FULL_SCALE`) over a few
//! kitti-mini frames embedded in the binary. Here the same frames (same conversion code,
//! `embedded/kitti.rs`) go through the core as the workspace builds it (nalgebra with `std`), and
//! every frame report and pose must print to the same characters (`{:e}` round-trips, so this is
//! bit-identity). `embedded/compare.sh` does the same against the embedded crate's own host
//! build; this test adds the workspace's feature set. Skipped, with the reason printed, when
//! QEMU, the Rust targets or kitti-mini are missing.

#[path = "../../embedded/kitti.rs"]
mod kitti;
#[path = "../../embedded/src/lines.rs"]
mod lines;

use kiss_odom_core::{Capacities, Config, Exact, Odometry, PointCodec, Quantized, Real};
use std::fmt::LowerExp;
use std::path::{Path, PathBuf};
use std::process::Command;

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn kitti_root() -> PathBuf {
    std::env::var_os("KISS_KITTI_MINI")
        .map(PathBuf::from)
        .unwrap_or_else(|| kitti::default_root(&repo_root()))
}

/// Why the bare-metal runs cannot happen here, if they cannot.
fn skip_reason() -> Option<String> {
    let marker = repo_root().join("embedded/target/qemu-skipped");
    if let Ok(why) = std::fs::read_to_string(&marker) {
        return Some(format!(
            "install-qemu.sh could not install QEMU: {}",
            why.trim()
        ));
    }
    for q in ["qemu-system-arm", "qemu-system-aarch64"] {
        let found = Command::new(q)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success());
        if !found {
            return Some(format!("{q} not found (run embedded/install-qemu.sh)"));
        }
    }
    let sysroot = Command::new("rustc")
        .args(["--print", "sysroot"])
        .output()
        .ok()?;
    let sysroot = PathBuf::from(String::from_utf8_lossy(&sysroot.stdout).trim());
    for t in ["thumbv7em-none-eabihf", "aarch64-unknown-none"] {
        if !sysroot.join("lib/rustlib").join(t).exists() {
            return Some(format!(
                "rust target {t} not installed (rustup target add {t})"
            ));
        }
    }
    if !kitti_root().join("sequences").exists() {
        return Some(format!(
            "kitti-mini not found at {}",
            kitti_root().display()
        ));
    }
    None
}

/// The selection the program reports on its `config` line.
fn selection(output: &str) -> kitti::Selection {
    let config = output
        .lines()
        .find(|l| l.starts_with("config "))
        .expect("no config line in the program's output");
    let field = |k: &str| -> String {
        config
            .split_whitespace()
            .find_map(|w| w.strip_prefix(&format!("{k}=")))
            .unwrap_or_else(|| panic!("no {k} in {config}"))
            .to_string()
    };
    kitti::Selection {
        root: kitti_root(),
        sequence: field("sequence"),
        first: field("first").parse().unwrap(),
        frames: field("frames").parse().unwrap(),
        max_range: field("max_range").parse().unwrap(),
        keep_every: field("keep_every").parse().unwrap(),
    }
}

/// Runs the frames through the workspace's core and prints them as the program does.
fn host_lines<T, P>(sel: &kitti::Selection, voxel_size: f64, caps: Capacities) -> Vec<String>
where
    T: Real + LowerExp,
    P: PointCodec<T>,
{
    let mut arena = vec![0u64; caps.arena_words::<T, P>()];
    let config = Config {
        voxel_size: T::of(voxel_size),
        ..Config::new(T::of(sel.max_range))
    };
    let mut odom = Odometry::<T, P, _>::new(config, caps, &mut arena[..]).unwrap();
    let mut out = Vec::new();
    for (i, frame) in kitti::load(sel).unwrap().iter().enumerate() {
        let points: Vec<[T; 3]> = frame.points.iter().map(|p| p.map(T::of)).collect();
        let r = odom.register_frame(&points, None).unwrap();
        out.push(lines::FrameLine(i, points.len(), &r).to_string());
        out.push(lines::PoseLine(i, &r.pose).to_string());
    }
    out
}

/// Runs `embedded/run.sh target` and returns its stdout.
fn run_target(target: &str) -> String {
    let t0 = std::time::Instant::now();
    let out = Command::new("bash")
        .arg(repo_root().join("embedded/run.sh"))
        .arg(target)
        .env_remove("KISS_FEATURES")
        .output()
        .expect("cannot start embedded/run.sh");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "embedded/run.sh {target} failed ({}):\n{stdout}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    println!(
        "{target}: built and ran in {:.1} s",
        t0.elapsed().as_secs_f64()
    );
    stdout
}

/// Largest absolute difference between the numbers of two pose lines.
fn pose_difference(a: &str, b: &str) -> f64 {
    let nums = |s: &str| -> Vec<f64> {
        s.split_whitespace()
            .skip(2)
            .map(|w| w.parse().unwrap_or(f64::NAN))
            .collect()
    };
    nums(a)
        .iter()
        .zip(nums(b))
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn check_target<T: Real + LowerExp, P: PointCodec<T>>(target: &str, caps: Capacities) {
    let output = run_target(target);
    let sel = selection(&output);
    let voxel: f64 = output
        .lines()
        .find(|l| l.starts_with("config "))
        .and_then(|l| {
            l.split_whitespace()
                .find_map(|w| w.strip_prefix("voxel_size="))
        })
        .and_then(|v| v.parse().ok())
        .expect("no voxel_size on the config line");
    let emulated: Vec<&str> = output
        .lines()
        .filter(|l| l.starts_with("frame ") || l.starts_with("pose "))
        .collect();
    let host = host_lines::<T, P>(&sel, voxel, caps);
    assert_eq!(emulated.len(), host.len(), "line count differs:\n{output}");
    let mut worst = 0.0f64;
    let mut mismatches = Vec::new();
    for (e, h) in emulated.iter().zip(&host) {
        if e != h {
            if e.starts_with("pose ") {
                worst = worst.max(pose_difference(e, h));
            }
            mismatches.push(format!("  {target}: {e}\n  host:  {h}"));
        }
    }
    println!(
        "{target}: {} frames, worst pose difference {worst:e} (tolerance 0: bit-identical), {} \
         differing lines",
        sel.frames,
        mismatches.len()
    );
    assert!(mismatches.is_empty(), "{}", mismatches.join("\n"));
}

#[test]
fn emulated_targets_match_the_workspace_core_bit_for_bit() {
    if let Some(why) = skip_reason() {
        println!("SKIP emulated_targets_match_the_workspace_core_bit_for_bit: {why}");
        return;
    }
    check_target::<f32, Quantized>("thumbv7em", Capacities::SMALL);
    check_target::<f64, Exact>("aarch64", Capacities::FULL_SCALE);
}

#[test]
fn embedded_frames_use_the_host_readers_kitti_correction() {
    let sel = kitti::Selection {
        root: kitti_root(),
        sequence: "05".into(),
        first: 0,
        frames: 1,
        max_range: 100.0,
        keep_every: 1,
    };
    let path = kitti::scan_path(&sel, 0);
    if !path.exists() {
        println!("SKIP: {} not found", path.display());
        return;
    }
    let raw = kitti::read_scan(&path).unwrap();
    let mut host = raw.clone();
    kiss_odom_io::folders::kitti::correct_scan(&mut host);
    let differing = raw
        .iter()
        .zip(&host)
        .filter(|(p, h)| kitti::correct_kitti(**p).map(f64::to_bits) != h.map(f64::to_bits))
        .count();
    println!(
        "{} points, {differing} corrected differently (tolerance 0)",
        raw.len()
    );
    assert_eq!(differing, 0);
}
