//! The degeneracy modes end to end on generated data. Robust mode
//! (`--degeneracy robust`: frames the reference leaves degenerate registered again with
//! point-to-plane terms) follows an open field from a standing start where reference mode turns
//! away, and with its tunnel setting (plane terms on every frame, finer voxels) a tunnel where
//! reference mode stays stuck; it flags those frames `planes`. On an urban street it registers
//! nothing again and gives the reference's poses bit for bit. A mode name other than these two is
//! refused, in a settings file and on the command line, naming the ones there are.

use crate::common;

use common::{distance, repo, run, RunExt};
use nalgebra::Matrix4;
use std::ffi::OsString;
use std::path::Path;

fn simulate(dir: &Path, profile: &str, frames: usize) {
    let argv: Vec<OsString> = [
        "simulate",
        "--out",
        dir.to_str().unwrap(),
        "--frames",
        &frames.to_string(),
        "--seed",
        "2",
        "--profile",
        profile,
    ]
    .iter()
    .map(OsString::from)
    .collect();
    let (code, err) = common::kiss_odom(argv);
    assert_eq!(code, 0, "simulate failed: {err}");
}

/// Simulates `frames` of `profile` in `dir` and runs reference mode and `other` (with `args`)
/// on them.
fn both_modes(
    dir: &Path,
    profile: &str,
    frames: usize,
    other: &str,
    args: &[&str],
) -> (common::Run, common::Run) {
    let data = dir.join(profile);
    simulate(&data, profile, frames);
    let reference = run_mode(&data, &dir.join("reference"), "reference", &[]);
    (reference, run_mode(&data, &dir.join(other), other, args))
}

/// Runs degeneracy `mode` (with `args`, one thread) on `data`, writing to `out`.
fn run_mode(data: &Path, out: &Path, mode: &str, args: &[&str]) -> common::Run {
    let mode = format!("registration.degeneracy={mode}");
    let argv: Vec<&str> = ["--threads", "1", "--set", &mode]
        .into_iter()
        .chain(args.iter().copied())
        .collect();
    run(data, out, &argv)
}

/// Frames of a run flagged `planes` (registered again with plane terms).
fn plane_frames(r: &common::Run) -> usize {
    r.rows()
        .iter()
        .filter(|row| row.flags.iter().any(|f| f == "planes"))
        .count()
}

/// Worst position error of a run's poses against the simulator's (m).
fn worst_error(data: &Path, r: &common::Run) -> f64 {
    let truth = kiss_odom_io::poses::read_kitti_matrices(&data.join("poses.txt")).unwrap();
    let est = r.poses();
    assert_eq!(truth.len(), est.len());
    est.iter()
        .zip(&truth)
        .map(|(e, t)| distance(t, e))
        .fold(0.0, f64::max)
}

/// Robust mode (with `args`) on `profile` from a standing start: `measure` of its run and of
/// reference mode's over `frames`; most frames are registered with plane terms.
fn robust_and_reference(
    profile: &str,
    frames: usize,
    args: &[&str],
    measure: fn(&Path, &common::Run) -> f64,
) -> (f64, f64) {
    let dir = tempfile::tempdir().unwrap();
    let (reference, robust) = both_modes(dir.path(), profile, frames, "robust", args);
    reference.succeeded_with_frames(frames);
    robust.succeeded_with_frames(frames);
    let planes = plane_frames(&robust);
    println!("{profile}: {planes} of {frames} frames registered with plane terms");
    assert!(planes > frames / 2 && plane_frames(&reference) == 0);
    let data = dir.path().join(profile);
    (measure(&data, &robust), measure(&data, &reference))
}

/// Position RMSE after a rigid alignment (m), as `kiss-odom eval` reports it.
fn ate(data: &Path, r: &common::Run) -> f64 {
    let read = kiss_odom_io::poses::read_kitti;
    let truth = read(&data.join("poses.txt")).unwrap();
    let est = read(&r.out.join("poses_kitti.txt")).unwrap();
    kiss_odom_io::metrics::absolute_trajectory_error(&est, &truth)
        .unwrap()
        .ate_m
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "heavy: cargo test --release --test workspace degeneracy::"
)]
fn robust_mode_follows_a_tunnel_where_reference_mode_stays_stuck() {
    let tunnel = [
        "--set",
        "registration.plane_gate=1",
        "--set",
        "mapping.voxel_size=0.5",
    ];
    let (robust, reference) = robust_and_reference("tunnel", 80, &tunnel, worst_error);
    println!(
        "tunnel, 80 frames: worst position error robust {robust:.3} m (tol: a fifth of \
         reference mode's), reference {reference:.3} m"
    );
    assert!(robust < 0.2 * reference);
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "heavy: cargo test --release --test workspace degeneracy::"
)]
fn robust_mode_follows_an_open_field_where_reference_mode_turns_away() {
    let (robust, reference) = robust_and_reference("field", 80, &[], ate);
    println!(
        "field, 80 frames: ATE robust {robust:.3} m (tol: half of reference mode's), \
         reference {reference:.3} m"
    );
    assert!(robust < 0.5 * reference);
}

/// Length of the path from frame `from` on (m).
fn path_from(poses: &[Matrix4<f64>], from: usize) -> f64 {
    poses[from..]
        .windows(2)
        .map(|w| distance(&w[0], &w[1]))
        .sum()
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "heavy: cargo test --release --test workspace degeneracy::"
)]
fn with_the_vehicle_prior_robust_mode_learns_a_corridors_speed() {
    // The bare corridor says nothing about motion along its axis; the vehicle starts at rest,
    // so every method stands still until the first turn. There a car-like vehicle's motion
    // across the corridor tells its motion along it: once through the turn, robust mode with
    // the vehicle prior travels about the true distance (at the speed it learnt: how the speed
    // changes on a straight, nothing tells), while reference mode stays stuck and plane terms
    // alone step along the axis at random.
    let frames = 160;
    let tunnel = [
        "--set",
        "registration.plane_gate=1",
        "--set",
        "mapping.voxel_size=0.5",
    ];
    let vehicle = [
        "--set",
        "registration.lateral_prior=1",
        "--set",
        "registration.prediction_prior=0.01",
    ];
    let dir = tempfile::tempdir().unwrap();
    let with: Vec<&str> = tunnel.iter().chain(&vehicle).copied().collect();
    let (reference, robust) = both_modes(dir.path(), "corridor", frames, "robust", &with);
    let (data, out) = (dir.path().join("corridor"), dir.path().join("without"));
    let without = run_mode(&data, &out, "robust", &tunnel);
    for r in [&reference, &robust, &without] {
        r.succeeded_with_frames(frames);
    }
    let truth =
        kiss_odom_io::poses::read_kitti_matrices(&dir.path().join("corridor/poses.txt")).unwrap();
    // The first frame whose heading left the axis by 10 mrad.
    let turn = truth
        .iter()
        .position(|m| m[(1, 0)].abs() > 0.01)
        .expect("the route turns within the run");
    let from = turn + 20;
    assert!(
        from + 30 < frames,
        "the turn at frame {turn} leaves frames to measure"
    );
    let true_path = path_from(&truth, from);
    let ratio = |r: &common::Run| path_from(&r.poses(), from) / true_path;
    let (with, reference, without) = (ratio(&robust), ratio(&reference), ratio(&without));
    println!(
        "corridor, turn at frame {turn}, frames {from}-{frames} ({true_path:.1} m): distance \
         over the true one with the vehicle prior {with:.3} (tol 0.7-1.3), reference mode \
         {reference:.3}, plane terms alone {without:.3}"
    );
    assert!((0.7..1.3).contains(&with));
    assert!(
        reference < 0.5,
        "reference mode stays stuck in a bare corridor"
    );
    assert!(
        (without - 1.0).abs() > 2.0 * (with - 1.0).abs(),
        "the prior is what makes the difference"
    );
}

#[test]
fn on_an_urban_street_robust_mode_registers_nothing_again_and_gives_the_reference_poses() {
    let dir = tempfile::tempdir().unwrap();
    let (reference, robust) = both_modes(dir.path(), "urban", 40, "robust", &[]);
    let read = |r: &common::Run| std::fs::read(r.out.join("poses_kitti.txt")).unwrap();
    assert_eq!(plane_frames(&robust), 0);
    assert_eq!(
        read(&reference),
        read(&robust),
        "robust mode changed an urban run"
    );
}

#[test]
fn an_unknown_mode_is_refused_in_a_settings_file_and_on_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let data = repo().join("fixtures/kitti-05-reduced");
    let old = dir.path().join("old.toml");
    std::fs::write(&old, "[registration]\ndegeneracy = \"hold\"\n").unwrap();
    let r = run(
        &data,
        &dir.path().join("a"),
        &["--config", old.to_str().unwrap()],
    );
    let said = r.failed_naming(&old);
    println!("{said}");
    for needle in ["`hold`", "expected `reference` or `robust`"] {
        assert!(said.contains(needle), "{needle:?} in {said}");
    }
    let r = run(
        &data,
        &dir.path().join("b"),
        &["--set", "registration.degeneracy=hold"],
    );
    println!("{}", r.stderr.trim());
    assert_ne!(r.code, 0, "--degeneracy hold is refused");
    assert!(
        r.stderr.contains("hold") && r.stderr.contains("robust"),
        "{}",
        r.stderr
    );
}
