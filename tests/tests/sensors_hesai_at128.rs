//! The PandarAT128 through the capture reader: nebula's angle correction file
//! (`fixtures/hesai-nebula/PandarAT128.dat`) read to the numbers nebula's loader gives it, its
//! returns in the field nebula's decoded AT128 scan fills, and the errors a user meets (no
//! correction file, a CSV instead of it, a damaged or encrypted one, a cut angle).

use kiss_odom_io::capture::hesai_at128;
use kiss_odom_io::capture::pcap::{self, Datagram};
use kiss_odom_io::capture::sweeps;
use kiss_odom_io::dataset::{SensorKind, SensorOptions};
use kiss_odom_sensors::hesai::wire_fixed::{AT128_SEQUENCE, PANDARAT128};
use kiss_odom_sensors::hesai::UNITS_PER_DEG;
use kiss_odom_tests::repo;
use std::path::{Path, PathBuf};

fn dat() -> PathBuf {
    repo().join("fixtures/hesai-nebula/PandarAT128.dat")
}

#[test]
fn nebulas_correction_file_reads_to_the_numbers_of_nebulas_loader() {
    let c = hesai_at128::read(&dat()).unwrap();
    let deg = |u: f64| u / f64::from(UNITS_PER_DEG);
    // Version 1.5, resolution 2: every stored value doubled (nebula's `load_from_bytes`).
    assert_eq!((c.frames, c.adjust_unit), (3, 2));
    let starts: Vec<f64> = c.start[..3].iter().map(|&s| deg(f64::from(s))).collect();
    let ends: Vec<f64> = c.end[..3].iter().map(|&s| deg(f64::from(s))).collect();
    println!("PandarAT128.dat frames: starts {starts:?}, ends {ends:?} degrees");
    assert_eq!(starts, [23.331171875, 143.20515625, 263.14859375]);
    assert_eq!(ends, [143.20515625, 263.14859375, 23.331171875]);
    let az: Vec<f64> = c.azimuth[..2].iter().map(|&a| deg(f64::from(a))).collect();
    assert_eq!(az, [-2.4, 0.65]);
    let el = |ch: usize| deg(f64::from(c.elevation[ch]));
    assert_eq!(
        (el(0), el(64), el(127)),
        (12.9153125, 0.130234375, -12.455078125)
    );
    // Adjustments in the file's bytes (times the resolution: hundredths of a degree).
    assert_eq!(c.azimuth_adjust[5][90], 1);
    assert_eq!(c.azimuth_adjust[0][17], 23);
    assert_eq!(c.azimuth_adjust[127][100], -4);
}

/// An AT128 packet, single strongest return, channel `c` of both blocks at `(3000 + 7 c)`
/// 4 mm units, block 0 at motor angle `motor` (units), block 1 0.05 degree on.
fn packet(motor: u32, k: u32) -> Vec<u8> {
    let f = &PANDARAT128;
    let mut b = vec![0u8; f.default_len()];
    b[..12].copy_from_slice(&[0xEE, 0xFF, 4, 3, 0, 0, 128, 2, 0, 4, 1, 1]);
    for blk in 0..2 {
        let (at, m) = (f.block_at(blk), motor + 1_280 * blk as u32);
        b[at..at + 2].copy_from_slice(&((m >> 8) as u16).to_le_bytes());
        b[at + 2] = m as u8;
        for c in 0..128 {
            let u = at + 3 + 4 * c;
            b[u..u + 2].copy_from_slice(&(3000 + 7 * c as u16).to_le_bytes());
        }
    }
    let tail = f.tail_at();
    b[tail + f.micros..tail + f.micros + 4].copy_from_slice(&(84 * k).to_le_bytes());
    b[tail + f.return_mode] = 0x37;
    b[tail + f.date + 1..tail + f.date + 6].copy_from_slice(&1_704_067_200u64.to_be_bytes()[3..]);
    b[tail + AT128_SEQUENCE..tail + AT128_SEQUENCE + 4].copy_from_slice(&k.to_le_bytes());
    b
}

/// A capture of packets across frame 0's field of nebula's file: motor 38.4 to 98.4 degrees.
fn capture(dir: &Path) -> PathBuf {
    let start = (23.331171875 * f64::from(UNITS_PER_DEG)) as u32;
    let d: Vec<Datagram> = (0..121)
        .map(|k| Datagram {
            time_ns: 1_704_067_200_000_000_000 + u64::from(k) * 84_000,
            source: "192.168.1.201:2368".parse().unwrap(),
            port: 2368,
            payload: packet(start + 15 * UNITS_PER_DEG + k * 12_800, k),
        })
        .collect();
    let path = dir.join("at128.pcap");
    pcap::write(&path, &d, 9000).unwrap();
    path
}

#[test]
fn returns_fill_the_field_nebulas_decoded_at128_scan_fills() {
    let dir = tempfile::tempdir().unwrap();
    let opts = SensorOptions {
        sensor: SensorKind::At128,
        calibration: Some(dat()),
        ..SensorOptions::default()
    };
    let (sweeps, report) = sweeps::read_all(&capture(dir.path()), &opts).unwrap();
    assert_eq!(report.sensor, "Hesai PandarAT128");
    assert_eq!((sweeps.len(), report.decoded), (1, 121));
    let (mut az, mut el) = ((f64::MAX, f64::MIN), (f64::MAX, f64::MIN));
    for p in &sweeps[0].points {
        let a = p[0].atan2(p[1]).to_degrees();
        let e = p[2].atan2(p[0].hypot(p[1])).to_degrees();
        az = (az.0.min(a), az.1.max(a));
        el = (el.0.min(e), el.1.max(e));
    }
    // Nebula's decoded AT128 scan (decoder_ground_truth/at128/1679653308704927652.pcd, its
    // x = d cos(el) sin(az), y = d cos(el) cos(az)) spans azimuth atan2(x, y) 30.1 to 148.4
    // degrees and elevation -9.0 to 13.1; the whole field of frame 0 here, all channels.
    println!(
        "{} points: azimuth atan2(x, y) {:.2} to {:.2} degrees, elevation {:.2} to {:.2}",
        sweeps[0].points.len(),
        az.0,
        az.1,
        el.0,
        el.1
    );
    assert_eq!(sweeps[0].points.len(), 121 * 2 * 128);
    assert!(
        az.0 > 27.0 && az.0 < 31.0 && az.1 > 149.0 && az.1 < 153.0,
        "{az:?}"
    );
    assert!(
        el.0 > -13.5 && el.0 < -12.0 && el.1 > 12.5 && el.1 < 13.5,
        "{el:?}"
    );
}

#[test]
fn a_missing_wrong_damaged_or_encrypted_correction_is_an_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let pcap = capture(dir.path());
    let why = |calibration: Option<PathBuf>, cut: Option<f64>| {
        let opts = SensorOptions {
            calibration,
            cut_angle_deg: cut,
            ..SensorOptions::default()
        };
        match sweeps::read_all(&pcap, &opts) {
            Err(e) => format!("{e:#}"),
            Ok(_) => panic!("{opts:?}: decoded"),
        }
    };
    // Found by its packets; without the file.
    let e = why(None, None);
    assert!(e.contains("at128.pcap") && e.contains(".dat"), "{e}");
    let csv = repo().join("fixtures/hesai-nebula/PandarXT16.csv");
    let e = why(Some(csv), None);
    assert!(
        e.contains("PandarXT16.csv") && e.contains("encrypted"),
        "{e}"
    );
    let mut bytes = std::fs::read(dat()).unwrap();
    bytes[20_000] ^= 0x10;
    let damaged = dir.path().join("damaged.dat");
    std::fs::write(&damaged, &bytes).unwrap();
    let e = why(Some(damaged), None);
    assert!(e.contains("damaged.dat") && e.contains("SHA-256"), "{e}");
    let e = why(Some(dat()), Some(0.0));
    assert!(e.contains("input.cut_angle"), "{e}");
    println!("the last: {e}");
}
