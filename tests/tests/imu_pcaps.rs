//! The simulator's IMU in its sensor pcaps: `simulate --sensor os1-64|mid360 --format pcap
//! --imu-rate 200` writes each IMU sample as the sensor's IMU packet (an Ouster's legacy IMU
//! packet on `udp_port_imu`, a Mid-360's SDK 2 IMU datagram on port 56401), and `run PCAP
//! --imu auto` takes them: the prior is used on every frame after the first, with a tenth of a
//! second's samples each, and the poses come closer to the simulation's ground truth than
//! without it.

use kiss_odom_tests::{run, Run};
use std::path::Path;

const FRAMES: usize = 30;
const IMU_RATE_HZ: f64 = 200.0;

/// `FRAMES` frames of `profile` (seed `seed`) as `sensor`'s pcap, with an IMU at 200 Hz.
fn simulate(dir: &Path, sensor: &str, profile: &str, seed: &str) {
    let (frames, rate) = (FRAMES.to_string(), IMU_RATE_HZ.to_string());
    kiss_odom_tests::simulate(
        dir,
        &[
            "--profile",
            profile,
            "--seed",
            seed,
            "--frames",
            &frames,
            "--sensor",
            sensor,
            "--format",
            "pcap",
            "--imu-rate",
            &rate,
        ],
    );
}

/// ATE (m) and mean relative rotation error (rad) of a run against the simulation's poses.
fn errors(r: &Run, sim: &Path) -> (f64, f64) {
    use kiss_odom_io::poses::read_kitti;
    let est = read_kitti(&r.out.join("poses_kitti.txt")).unwrap();
    let gt = read_kitti(&sim.join("poses.txt")).unwrap();
    assert_eq!(est.len(), gt.len(), "a pose per simulated frame");
    let m = kiss_odom_io::metrics::evaluate(&est, &gt).unwrap();
    (m.ate_m, m.rpe_rad_mean)
}

/// Simulates `sensor`'s pcap and runs it with and without `--imu auto`, checking the prior
/// and printing both runs' errors against the ground truth.
fn prior_from_the_pcap(sensor: &str, profile: &str, seed: &str) {
    let tmp = tempfile::tempdir().unwrap();
    let sim = tmp.path().join(sensor);
    simulate(&sim, sensor, profile, seed);
    let pcap = sim.join("packets.pcap");
    let meta = sim.join("packets.json");
    let mut flags = vec![];
    if sensor == "os1-64" {
        flags.extend(["--calibration", meta.to_str().unwrap()]);
    }
    let with = [&flags[..], &["--imu", "auto"]].concat();
    let on = run(&pcap, &tmp.path().join("on"), &with);
    let off = run(&pcap, &tmp.path().join("off"), &flags);
    assert_eq!(on.ok().number("warnings"), 0.0, "{sensor}: {}", on.stderr);
    off.ok();
    let states = on.column("imu_prior");
    assert_eq!(states.len(), FRAMES, "{sensor}");
    assert_eq!(states[0], "first", "{sensor}");
    assert!(
        states[1..].iter().all(|s| s == "used"),
        "{sensor}: {states:?}"
    );
    assert!(off.column("imu_prior").iter().all(String::is_empty));
    // A frame's tenth of a second holds 20 samples at 200 Hz (one more or less where a sample
    // falls on its edge).
    let counts: Vec<f64> = on.column("imu_samples")[1..]
        .iter()
        .map(|n| n.parse().unwrap())
        .collect();
    let per_frame = IMU_RATE_HZ / 10.0;
    assert!(
        counts.iter().all(|n| (n - per_frame).abs() <= 1.0),
        "{sensor}: {counts:?}"
    );
    let ((ate_on, rot_on), (ate_off, rot_off)) = (errors(&on, &sim), errors(&off, &sim));
    println!(
        "{sensor} {profile} seed {seed}, {FRAMES} frames, IMU packets at {IMU_RATE_HZ} Hz \
         ({per_frame} a frame): ATE {ate_on:.4} m with the prior, {ate_off:.4} m without; \
         RPE {rot_on:.5} / {rot_off:.5} rad"
    );
    assert!(ate_on < ate_off && rot_on < rot_off, "{sensor}");
}

#[test]
fn ouster_imu_packets_in_a_simulated_pcap_give_the_prior_its_samples() {
    prior_from_the_pcap("os1-64", "drone", "41");
}

#[test]
fn mid360_imu_packets_in_a_simulated_pcap_give_the_prior_its_samples() {
    prior_from_the_pcap("mid360", "handheld", "42");
}

/// A change to an angular rate as a sensor's packets carry it (f32).
type Rate = dyn Fn(f32) -> f32;

/// The pcap `from` with each Mid-360 IMU datagram's angular rates changed by `f` (its CRC
/// resealed, as a sensor that sends them wrong would), written to `to`.
fn rewrite_gyro(from: &Path, to: &Path, f: &Rate) {
    use kiss_odom_io::capture::pcap;
    use kiss_odom_sensors::livox::sdk2::{crc32, field, IMU};
    let mut datagrams: Vec<_> = pcap::open(from).unwrap().map(|d| d.unwrap()).collect();
    let mut changed = 0;
    for d in datagrams
        .iter_mut()
        .filter(|d| d.payload.get(field::DATA_TYPE) == Some(&IMU))
    {
        let b = &mut d.payload;
        for at in (field::DATA..field::DATA + 12).step_by(4) {
            let v = f32::from_le_bytes(b[at..at + 4].try_into().unwrap());
            b[at..at + 4].copy_from_slice(&f(v).to_le_bytes());
        }
        let crc = crc32(&b[field::TIMESTAMP.start..]);
        b[field::CRC32].copy_from_slice(&crc.to_le_bytes());
        changed += 1;
    }
    assert!(changed > 100, "{changed} IMU datagrams");
    pcap::write(to, &datagrams, 9000).unwrap();
}

/// A Mid-360 whose IMU packets give the gyroscope in deg/s, or 1e30 rad/s: `--imu auto` stops
/// using it within the first second, names the cause, and the run stays within 10 % of the
/// LiDAR-only one's ATE.
#[test]
fn a_wrong_mid360_gyroscope_in_its_packets_is_refused_within_a_second() {
    let tmp = tempfile::tempdir().unwrap();
    let sim = tmp.path().join("mid360");
    simulate(&sim, "mid360", "handheld", "43");
    let off = run(&sim.join("packets.pcap"), &tmp.path().join("off"), &[]);
    let (ate_off, _) = errors(off.ok(), &sim);
    let degrees = |v: f32| v.to_degrees();
    let huge = |_: f32| 1e30_f32;
    let variants: [(&str, &Rate, &str); 2] = [
        ("degs", &degrees, "degrees per second"),
        ("1e30", &huge, "beyond 35 rad/s"),
    ];
    for (name, f, cause) in variants {
        let pcap = tmp.path().join(format!("{name}.pcap"));
        rewrite_gyro(&sim.join("packets.pcap"), &pcap, f);
        let r = run(&pcap, &tmp.path().join(name), &["--imu", "auto"]);
        r.ok();
        let states = r.column("imu_prior");
        let first = states
            .iter()
            .position(|s| s != "first" && s != "used")
            .unwrap_or(usize::MAX);
        let (ate, _) = errors(&r, &sim);
        let warning = r.warnings().first().copied().unwrap_or("(none)");
        println!(
            "{name}: prior not used from frame {first} ({}), ATE {ate:.4} m against {ate_off:.4} \
             m with --imu off (tolerance +10 %); warning: {warning}",
            states.get(first).map_or("-", String::as_str)
        );
        assert!(first <= 10, "{name}: {states:?}");
        assert!(
            states[first..].iter().all(|s| s != "used"),
            "{name}: {states:?}"
        );
        r.warning_with(&["gyroscope", cause]);
        assert!(ate <= 1.1 * ate_off, "{name}: ATE {ate} m, off {ate_off} m");
    }
}
