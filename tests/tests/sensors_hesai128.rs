//! The PandarQT128 decoder on a real sector (`fixtures/hesai-qt128/`, see its SOURCE.md):
//! found by its protocol, decoded through the reader with Hesai's angle correction file, and
//! point by point against TIER IV nebula's decoder.

use crate::common::pcd_points;
use kiss_odom_io::capture::sweeps;
use kiss_odom_io::dataset::{SensorKind, SensorOptions};
use kiss_odom_sensors::Return;
use kiss_odom_tests::repo;
use std::collections::HashMap;
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    repo().join("fixtures/hesai-qt128").join(name)
}

fn options(sensor: SensorKind) -> SensorOptions {
    SensorOptions {
        sensor,
        calibration: Some(fixture("PandarQT128.csv")),
        ..SensorOptions::default()
    }
}

#[test]
fn the_sector_equals_nebulas_points() {
    let pcap = fixture("qt128-sector.pcap");
    let (sweeps, report) =
        sweeps::read_all(&pcap, &options(SensorKind::Auto)).expect("found as a QT128");
    assert_eq!(report.sensor, "Hesai PandarQT128");
    assert_eq!(report.decoded, 90);
    let stats: u32 = sweeps.iter().map(|s| s.stats.lost_packets).sum();
    assert_eq!(stats, 0, "consecutive sequence numbers");

    // What nebula keeps (its test configuration): returns from 0.3 m to the QT128's 50 m,
    // and of a dual pair less than 0.1 m apart only the second block's (the strongest).
    let mut ours = Vec::new();
    let mut strongest = HashMap::new();
    let points = sweeps.iter().flat_map(|s| {
        s.points
            .iter()
            .zip(&s.meta)
            .map(move |(p, m)| (s.stats.index, p, m))
    });
    for (sweep, p, m) in points.clone() {
        if m.ret == Return::Strongest {
            strongest.insert((sweep, m.ring, m.column), norm(p));
        }
    }
    let mut dual_dropped = 0;
    for (sweep, p, m) in points {
        let d = norm(p);
        if !(0.3 - 1e-9..=50.0 + 1e-9).contains(&d) {
            continue;
        }
        if m.ret == Return::Last {
            if let Some(s) = strongest.get(&(sweep, m.ring, m.column)) {
                if (s - d).abs() < 0.1 {
                    dual_dropped += 1;
                    continue;
                }
            }
        }
        // Nebula's frame: x to azimuth 90 degrees (our -y), y to azimuth 0 (our x).
        ours.push([-p[1], p[0], p[2]]);
    }
    let theirs = pcd_points(&std::fs::read(fixture("nebula-points.pcd")).unwrap());

    // Each of nebula's points has its own nearest point of ours.
    let mut used = vec![false; ours.len()];
    let mut worst = 0f64;
    for t in &theirs {
        let (i, e) = ours
            .iter()
            .enumerate()
            .map(|(i, o)| (i, dist(o, t)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        assert!(!used[i], "two of nebula's points nearest to one of ours");
        used[i] = true;
        worst = worst.max(e);
    }
    println!(
        "QT128 sector: {} points of ours ({dual_dropped} dual returns nebula drops as within \
         0.1 m), {} of nebula's; worst distance {worst:.2e} m, tolerance 1e-5 m (float32 at \
         up to 50 m)",
        ours.len(),
        theirs.len()
    );
    assert_eq!(ours.len(), theirs.len());
    assert!(worst < 1e-5);
}

#[test]
fn a_qt128_needs_its_angle_correction_file() {
    let pcap = fixture("qt128-sector.pcap");
    let no_file = SensorOptions {
        sensor: SensorKind::Qt128,
        ..SensorOptions::default()
    };
    let e = sweeps::read_all(&pcap, &no_file).unwrap_err().to_string();
    assert!(e.contains("--calibration") && e.contains("QT128"), "{e}");
    // An XT32's file (32 rows) is not the QT128's.
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("xt32.csv");
    let rows: String = (1..=32).map(|i| format!("{i},{},0\n", 16 - i)).collect();
    std::fs::write(&csv, format!("Laser id,Elevation,Azimuth\n{rows}")).unwrap();
    let wrong = SensorOptions {
        calibration: Some(csv),
        ..options(SensorKind::Qt128)
    };
    let e = format!("{:#}", sweeps::read_all(&pcap, &wrong).unwrap_err());
    assert!(e.contains("96 of the 128 channels have no row"), "{e}");
    // Named as a protocol 1.4 sensor, every packet is refused as another protocol.
    let e = sweeps::read_all(&pcap, &options(SensorKind::Ot128))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("90 packets on port 2368, none decoded") && e.contains("not the model's"),
        "{e}"
    );
}

fn norm(p: &[f64; 3]) -> f64 {
    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    norm(&[a[0] - b[0], a[1] - b[1], a[2] - b[2]])
}
