//! The IMU consistency check end to end (`run --imu FILE`): on a generated drone flight a
//! gyroscope in deg/s or with its z axis flipped is rejected within the first second, with a
//! warning naming the cause, and the run stays near the LiDAR-only one; the right IMU is never
//! rejected.

use kiss_odom_tests::{run, Run};
use std::path::Path;

/// A change to a sample's gyroscope rates.
type Rates = dyn Fn([f64; 3]) -> [f64; 3];

/// `imu.csv` of `from` with each sample's gyroscope rates changed by `f`, written to `to`.
fn rewrite(from: &Path, to: &Path, f: &Rates) {
    let text = std::fs::read_to_string(from).unwrap();
    let mut lines = text.lines();
    let mut out = format!("{}\n", lines.next().unwrap());
    for l in lines {
        let v: Vec<&str> = l.split(',').collect();
        let g: Vec<f64> = v[1..4].iter().map(|x| x.parse().unwrap()).collect();
        let g = f([g[0], g[1], g[2]]);
        out += &format!("{},{},{},{},{}\n", v[0], g[0], g[1], g[2], v[4..].join(","));
    }
    std::fs::write(to, out).unwrap();
}

fn rejected(r: &Run) -> Vec<usize> {
    let states = r.column("imu_prior");
    (0..states.len())
        .filter(|&k| states[k] == "rejected")
        .collect()
}

#[test]
fn a_wrong_gyroscope_is_rejected_within_a_second_and_the_right_one_never() {
    let tmp = tempfile::tempdir().unwrap();
    let sim = tmp.path().join("sim");
    crate::imu_prior::simulate(&sim, "drone", "41", "150");
    let out = |name: &str| tmp.path().join(name);
    let off = run(&sim, &out("off"), &["--set", "data.deskew=true"]);
    let a_off = off.ok().number("metrics.ate_m");

    let right = run(
        &sim,
        &out("right"),
        &["--set", "data.deskew=true", "--imu", "auto"],
    );
    right.ok();
    let states = right.column("imu_prior");
    assert!(states[1..].iter().all(|s| s == "used"), "{states:?}");
    assert_eq!(right.number("imu_rejected_frames"), 0.0);
    assert!(right.warnings().is_empty(), "{}", right.stderr);
    let worst = right
        .column("imu_disagreement")
        .iter()
        .skip(2)
        .filter_map(|v| v.parse::<f64>().ok())
        .fold(0.0, f64::max);
    println!(
        "right IMU: ATE {:.3} m (off {a_off:.3} m), 0 frames rejected, worst disagreement \
         {worst:.4} rad against a tolerance of at least {} rad",
        right.number("metrics.ate_m"),
        kiss_odom_drive::imu_check::FLOOR_RAD
    );

    let degrees = |g: [f64; 3]| g.map(f64::to_degrees);
    let flip_z = |g: [f64; 3]| [g[0], g[1], -g[2]];
    let variants: [(&str, &Rates, &str); 2] =
        [("degs", &degrees, "57.3"), ("flipz", &flip_z, "z axis")];
    for (name, f, cause) in variants {
        let csv = out(&format!("{name}.csv"));
        rewrite(&sim.join("imu.csv"), &csv, f);
        let r = run(
            &sim,
            &out(name),
            &["--set", "data.deskew=true", "--imu", csv.to_str().unwrap()],
        );
        r.ok();
        let frames = rejected(&r);
        let first = frames.first().copied().unwrap_or(usize::MAX);
        let a = r.number("metrics.ate_m");
        println!(
            "{name}: first rejected frame {first}, {} rejected, ATE {a:.3} m against {a_off:.3} m \
             with --imu off (tolerance +10 %)",
            frames.len()
        );
        r.warning_with(&["gyroscope prior", cause]);
        // Frames are 0.1 s apart: rejected within the first second.
        assert!(first <= 10, "{name}: first rejected frame {first}");
        assert_eq!(r.number("imu_rejected_frames"), frames.len() as f64);
        assert!(a <= 1.1 * a_off, "{name}: ATE {a} m, off {a_off} m");
    }
}
