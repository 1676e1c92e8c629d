//! The opt-in gyroscope prior end to end (`run --imu auto`) on simulated recordings with an IMU
//! (`simulate --imu-rate`), on seeds not used to tune it: it tracks fast turns the
//! constant-velocity model loses, changes nothing when no sample comes, survives an IMU that
//! stops, and flags a clock offset it cannot bridge.

use kiss_odom_tests::run;
use std::path::Path;

/// `frames` frames of `profile` (seed `seed`), 32 x 512 beams, with an IMU at 200 Hz; also the
/// IMU check's drive (`imu_check.rs`).
pub(crate) fn simulate(dir: &Path, profile: &str, seed: &str, frames: &str) {
    kiss_odom_tests::simulate(
        dir,
        &[
            "--profile",
            profile,
            "--seed",
            seed,
            "--frames",
            frames,
            "--beams",
            "32",
            "--columns",
            "512",
            "--imu-rate",
            "200",
        ],
    );
}

#[test]
fn the_gyroscope_prior_tracks_fast_turns_the_constant_velocity_model_loses() {
    let tmp = tempfile::tempdir().unwrap();
    for (profile, seed) in [("drone", "31"), ("handheld", "32")] {
        let sim = tmp.path().join(profile);
        simulate(&sim, profile, seed, "80");
        let on = run(
            &sim,
            &tmp.path().join(format!("{profile}-on")),
            &["--imu", "auto"],
        );
        let off = run(&sim, &tmp.path().join(format!("{profile}-off")), &[]);
        on.ok();
        off.ok();
        let (a_on, a_off) = (on.number("metrics.ate_m"), off.number("metrics.ate_m"));
        // Relative rotation error: ARE's alignment, fitted to positions, is loose on a short
        // walk.
        let (r_on, r_off) = (
            on.number("metrics.rpe_rad_mean"),
            off.number("metrics.rpe_rad_mean"),
        );
        println!("{profile} seed {seed}, 80 frames: ATE {a_on:.3} m with the prior, {a_off:.3} m without; RPE {r_on:.4} / {r_off:.4} rad");
        assert!(a_on < 0.5 * a_off && r_on < 0.5 * r_off, "{profile}");
        let used = on.column("imu_prior");
        assert_eq!(used[0], "first");
        assert!(used[1..].iter().all(|u| u == "used"), "{used:?}");
        assert!(off.column("imu_prior").iter().all(String::is_empty));
    }
}

#[test]
fn without_samples_the_prior_changes_nothing_and_an_imu_that_stops_is_survived() {
    let tmp = tempfile::tempdir().unwrap();
    let sim = tmp.path().join("sim");
    simulate(&sim, "drone", "33", "30");
    let csv = std::fs::read_to_string(sim.join("imu.csv")).unwrap();
    // No imu.csv: every frame falls back to the constant-velocity model, bit for bit.
    std::fs::rename(sim.join("imu.csv"), tmp.path().join("imu.csv")).unwrap();
    let none = run(&sim, &tmp.path().join("none"), &["--imu", "auto"]);
    let off = run(&sim, &tmp.path().join("off"), &[]);
    assert_eq!(
        none.ok().lines("poses_kitti.txt"),
        off.ok().lines("poses_kitti.txt")
    );
    let states = none.column("imu_prior");
    assert_eq!(states[0], "first");
    assert!(states[1..].iter().all(|s| s == "no_samples"), "{states:?}");
    // Once, counted: a pose the user did not ask for.
    none.warning_with(&["frame 1 ", "no IMU sample", "without the gyroscope prior"]);
    assert_eq!(none.number("warnings"), 1.0);
    assert_eq!(off.number("warnings"), 0.0);
    // The IMU stops after 1.5 s: the frames after it fall back and say so; the run goes on.
    let kept: Vec<&str> = csv
        .lines()
        .take_while(|l| {
            l.split(',')
                .next()
                .and_then(|t| t.parse::<f64>().ok())
                .is_none_or(|t| t < 1.5)
        })
        .collect();
    std::fs::write(sim.join("imu.csv"), kept.join("\n") + "\n").unwrap();
    let stops = run(&sim, &tmp.path().join("stops"), &["--imu", "auto"]);
    let states = stops.ok().column("imu_prior");
    println!("IMU stopping at 1.5 s: {states:?}");
    assert!(states[1..14].iter().all(|s| s == "used"));
    assert!(states[16..].iter().all(|s| s == "no_samples"));
    assert_eq!(stops.number("registered_frames"), 30.0);
    stops.warning_with(&["no IMU sample", "without the gyroscope prior"]);
    // An extrinsic off by 5 degrees is used, and shows in ICP's disagreement with the
    // gyroscope; a malformed one is refused.
    std::fs::write(sim.join("imu.csv"), &csv).unwrap();
    let mean = |r: &kiss_odom_tests::Run| {
        let v: Vec<f64> = r.column("imu_residual")[1..]
            .iter()
            .map(|x| x.parse().unwrap())
            .collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    let right = run(&sim, &tmp.path().join("right"), &["--imu", "auto"]);
    let tilted = run(
        &sim,
        &tmp.path().join("tilted"),
        &["--imu", "auto", "--set", "imu.extrinsic=[0,0,0,5,0,0]"],
    );
    let (r, t) = (mean(right.ok()), mean(tilted.ok()));
    println!("mean disagreement: {r:.4} rad/s with the right extrinsic, {t:.4} with it 5 deg off");
    assert!(t > 1.4 * r, "{t} vs {r}");
    let bad = run(
        &sim,
        &tmp.path().join("bad"),
        &["--imu", "auto", "--set", "imu.extrinsic=[0,0,5]"],
    );
    bad.failed_with(&["--set imu.extrinsic=[0,0,5]", "imu.extrinsic"]);
    // A clock offset the prior cannot bridge (0.2 s) is flagged frame by frame, not used.
    std::fs::write(sim.join("imu.csv"), &csv).unwrap();
    let shifted = run(
        &sim,
        &tmp.path().join("shifted"),
        &["--imu", "auto", "--set", "imu.time_offset=0.2"],
    );
    let states = shifted.ok().column("imu_prior");
    assert!(states[1..].iter().all(|s| s == "gap"), "{states:?}");
    shifted.warning_with(&["frame 1 ", "imu.max_gap", "imu.time_offset"]);
    let strict = run(
        &sim,
        &tmp.path().join("strict"),
        &[
            "--imu",
            "auto",
            "--set",
            "imu.time_offset=0.2",
            "--set",
            "output.strict=true",
        ],
    );
    strict.failed_with(&["imu.max_gap", "output.strict"]);
    assert_eq!(
        shifted.lines("poses_kitti.txt"),
        off.lines("poses_kitti.txt")
    );
}
