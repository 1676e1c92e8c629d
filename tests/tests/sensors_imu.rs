//! IMU packets in sensor captures: the shared Ouster recordings' (48-byte legacy packets on
//! port 7503: 10 and 30 of them) and the Livox Tele-15's (data type 6 on the data port: 74)
//! reach each frame's `imu` samples and `convert`'s `imu.csv`, in rad/s and m/s^2, checked
//! against the raw bytes and, for Ouster, against ouster-sdk 1.0.1 (`tests/sensors/dump_imu.py`
//! with the Python in `KISS_ODOM_SENSOR_PYTHON`; SKIP without it).

use kiss_odom_io::capture::sweeps;
use kiss_odom_io::imu::{self, ImuSample};
use kiss_odom_io::SensorOptions;
use kiss_odom_tests::{have_sensor_file, sensor_data};
use std::ffi::OsString;
use std::path::PathBuf;
use std::process::Command;

/// Recording, metadata and IMU packets in it.
const OUSTER: [(&str, &str, usize); 2] = [
    (
        "ouster/OS-0-32-U1_v2.2.0_1024x10.pcap",
        "ouster/OS-0-32-U1_v2.2.0_1024x10.json",
        10,
    ),
    (
        "ouster/OS-1-128_v2.3.0_1024x10_lb_n3.pcap",
        "ouster/OS-1-128_v2.3.0_1024x10.json",
        30,
    ),
];

/// Every frame's IMU samples, in order, and the report's count.
fn samples(pcap: &str, opts: &SensorOptions) -> (Vec<ImuSample>, u64) {
    let (sweeps, report) = sweeps::read_all(&sensor_data().join(pcap), opts).unwrap();
    (
        sweeps.into_iter().flat_map(|s| s.imu).collect(),
        report.imu_packets,
    )
}

fn ouster_opts(meta: &str) -> SensorOptions {
    SensorOptions {
        meta: Some(sensor_data().join(meta)),
        ..SensorOptions::default()
    }
}

/// The 48-byte packets on port 7503, read here from the bytes: gyro time, g, deg/s.
fn raw_ouster(pcap: &str) -> Vec<(u64, [f32; 3], [f32; 3])> {
    let mut c = kiss_odom_io::capture::pcap::open(&sensor_data().join(pcap)).unwrap();
    let mut out = Vec::new();
    while let Some(d) = c.next_datagram().unwrap() {
        if d.port != 7503 {
            continue;
        }
        let b = &d.payload;
        assert_eq!(b.len(), 48);
        let f = |i: usize| f32::from_le_bytes(b[i..i + 4].try_into().unwrap());
        let t = u64::from_le_bytes(b[16..24].try_into().unwrap());
        out.push((t, [f(24), f(28), f(32)], [f(36), f(40), f(44)]));
    }
    out
}

#[test]
fn ouster_imu_packets_reach_the_frames_in_si_units() {
    for (pcap, meta, count) in OUSTER {
        if !have_sensor_file(pcap) {
            return;
        }
        let (got, counted) = samples(pcap, &ouster_opts(meta));
        let raw = raw_ouster(pcap);
        assert_eq!(
            (got.len(), counted as usize, raw.len()),
            (count, count, count)
        );
        for (s, (t, accel_g, gyro_deg)) in got.iter().zip(&raw) {
            assert_eq!(s.time_ns, *t, "timed at the gyroscope's read");
            for i in 0..3 {
                assert_eq!(s.accel[i], f64::from(accel_g[i]) * imu::STANDARD_GRAVITY);
                assert_eq!(s.gyro[i], f64::from(gyro_deg[i]).to_radians());
            }
        }
        // Resting on a table: about one g, pointing up.
        let g = got.iter().map(|s| s.accel[2]).sum::<f64>() / got.len() as f64;
        println!("{pcap}: {count} IMU packets, mean accel z {g:.3} m/s^2");
        assert!((g - imu::STANDARD_GRAVITY).abs() < 0.5);
    }
}

#[test]
fn ouster_imu_samples_equal_ouster_sdks() {
    let Some(python) = std::env::var_os("KISS_ODOM_SENSOR_PYTHON") else {
        println!("SKIP: KISS_ODOM_SENSOR_PYTHON is not set (a Python with ouster-sdk 1.0.1)");
        return;
    };
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("sensors/dump_imu.py");
    for (pcap, meta, count) in OUSTER {
        if !have_sensor_file(pcap) {
            return;
        }
        let out = Command::new(&python)
            .arg(&script)
            .arg(sensor_data().join(pcap))
            .arg(sensor_data().join(meta))
            .output()
            .expect("cannot run KISS_ODOM_SENSOR_PYTHON");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let reference: Vec<serde_json::Value> = serde_json::from_slice(&out.stdout).unwrap();
        let (got, _) = samples(pcap, &ouster_opts(meta));
        assert_eq!((got.len(), reference.len()), (count, count));
        // ouster-sdk converts in f32: agreement to f32's precision.
        let tol = 1e-6;
        let mut worst: f64 = 0.0;
        for (s, r) in got.iter().zip(&reference) {
            assert_eq!(s.time_ns, r["gyro_ts"].as_u64().unwrap());
            for (ours, key) in [(s.accel, "accel"), (s.gyro, "gyro")] {
                for (i, v) in ours.iter().enumerate() {
                    let theirs = r[key][i].as_f64().unwrap();
                    worst = worst.max((v - theirs).abs() / theirs.abs().max(1e-3));
                }
            }
        }
        println!(
            "{pcap}: {count} samples, worst relative difference to ouster-sdk {worst:.1e} \
             (tolerance {tol:.0e})"
        );
        assert!(worst <= tol);
    }
}

#[test]
fn livox_imu_packets_reach_the_frames_and_convert_writes_imu_csv() {
    let pcap = "livox/livox_tele15_small.pcap";
    if !have_sensor_file(pcap) {
        return;
    }
    let (got, counted) = samples(pcap, &SensorOptions::default());
    assert_eq!((got.len(), counted), (74, 74));
    assert!(got.windows(2).all(|w| w[0].time_ns < w[1].time_ns));
    let g = got.iter().map(|s| s.accel[2]).sum::<f64>() / got.len() as f64;
    println!("{pcap}: 74 IMU samples, mean accel z {g:.3} m/s^2");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("converted");
    let args: Vec<OsString> = vec![
        "convert".into(),
        sensor_data().join(pcap).into(),
        "--out".into(),
        out.clone().into(),
        "--quiet".into(),
    ];
    kiss_odom_tests::kiss_odom(&args, &out).ok();
    let csv = imu::read_csv(&out.join(imu::CSV_NAME)).unwrap();
    // The recording ends in its fourth frame, which is not converted: imu.csv holds every
    // sample of the three before, exactly.
    let (sweeps, _) =
        sweeps::read_all(&sensor_data().join(pcap), &SensorOptions::default()).unwrap();
    assert_eq!(sweeps.len(), 4);
    let kept: Vec<ImuSample> = sweeps[..3].iter().flat_map(|s| s.imu.clone()).collect();
    assert!(!kept.is_empty() && kept.len() < got.len());
    assert_eq!(
        csv, kept,
        "imu.csv holds every sample of the frames converted, exactly"
    );
}

/// Every frame of a folder, with its IMU samples.
fn folder_frames(dir: &std::path::Path) -> Vec<kiss_odom_io::Frame> {
    let mut ds = kiss_odom_io::open(dir, kiss_odom_io::Format::Auto, &Default::default()).unwrap();
    let mut frames = Vec::new();
    while let Some(item) = ds.frames.next_item().unwrap() {
        match item {
            kiss_odom_io::Item::Frame(f) => frames.push(f),
            other => panic!("{other:?}"),
        }
    }
    frames
}

#[test]
fn a_simulated_imu_reaches_each_frame_up_to_its_time_and_convert_writes_it_back() {
    let dir = tempfile::tempdir().unwrap();
    let sim = dir.path().join("sim");
    let run = |args: &[&str], out: &std::path::Path| {
        let args: Vec<OsString> = args.iter().map(OsString::from).collect();
        let r = kiss_odom_tests::kiss_odom(&args, out);
        assert_eq!(r.code, 0, "{}", r.stderr);
    };
    let s = sim.to_str().unwrap();
    run(
        &[
            "simulate",
            "--out",
            s,
            "--frames",
            "6",
            "--seed",
            "11",
            "--profile",
            "handheld",
            "--beams",
            "16",
            "--columns",
            "256",
            "--imu-rate",
            "200",
        ],
        &sim,
    );
    let written = imu::read_csv(&sim.join(imu::CSV_NAME)).unwrap();
    // 200 Hz from 0 s to 0.1 s past the last point (at 0.5996 s): 0 to 0.695 s.
    assert_eq!(written.len(), 140);
    let frames = folder_frames(&sim);
    let times: Vec<f64> = std::fs::read_to_string(sim.join("times.txt"))
        .unwrap()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect();
    let mut handed: Vec<ImuSample> = Vec::new();
    for (k, f) in frames.iter().enumerate() {
        let before = if k == 0 { f64::MIN } else { times[k - 1] };
        let last = k + 1 == frames.len();
        assert!(!f.imu.is_empty());
        for s in &f.imu {
            assert!(
                s.seconds() > before && (last || s.seconds() <= times[k]),
                "frame {k}"
            );
        }
        println!("frame {k}: {} samples up to {:.4} s", f.imu.len(), times[k]);
        handed.extend(&f.imu);
    }
    assert_eq!(
        handed, written,
        "every sample in exactly one frame, in order"
    );
    let out = dir.path().join("converted");
    run(
        &["convert", s, "--out", out.to_str().unwrap(), "--quiet"],
        &out,
    );
    assert_eq!(imu::read_csv(&out.join(imu::CSV_NAME)).unwrap(), written);
    // A broken imu.csv is a warning, not a failed run.
    std::fs::write(sim.join(imu::CSV_NAME), "time,gyro\n1,2\n").unwrap();
    let ds = kiss_odom_io::open(&sim, kiss_odom_io::Format::Auto, &Default::default()).unwrap();
    assert!(
        ds.info
            .warnings
            .iter()
            .any(|w| w.contains("no IMU samples used")),
        "{:?}",
        ds.info.warnings
    );
    assert!(folder_frames(&sim).iter().all(|f| f.imu.is_empty()));
}
