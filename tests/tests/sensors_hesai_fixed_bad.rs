//! Damaged captures of the fixed-layout Hesai models (`fixtures/hesai-nebula/`): a truncated
//! packet, a packet of another product, a flipped return mode, packets of two models on one
//! port, a missing or malformed angle correction file. Each is a counted, reported skip or an
//! error naming the file and the reason, never a panic.

use kiss_odom_io::capture::pcap::{self, Datagram};
use kiss_odom_io::capture::sweeps;
use kiss_odom_io::dataset::{SensorKind, SensorOptions};
use kiss_odom_tests::repo;
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    repo().join("fixtures/hesai-nebula").join(name)
}

fn datagrams(name: &str) -> Vec<Datagram> {
    pcap::open(&fixture(name))
        .unwrap()
        .map(|d| d.unwrap())
        .collect()
}

fn write(dir: &Path, name: &str, d: &[Datagram]) -> PathBuf {
    let path = dir.join(name);
    pcap::write(&path, d, 9000).unwrap();
    path
}

fn opts(sensor: SensorKind, csv: &str) -> SensorOptions {
    SensorOptions {
        sensor,
        calibration: Some(fixture(csv)),
        ..SensorOptions::default()
    }
}

#[test]
fn damaged_packets_are_counted_skips_with_their_reasons() {
    let dir = tempfile::tempdir().unwrap();
    // XT16: one packet cut short, one with the XT32's laser count, one whose header says
    // single return while its mode byte says dual.
    let mut d = datagrams("xt16.pcap");
    let n = d.len() as u64;
    d[3].payload.truncate(500);
    d[5].payload[6] = 32;
    d[7].payload[10] = 1;
    let path = write(dir.path(), "xt16.pcap", &d);
    let (sweeps, report) =
        sweeps::read_all(&path, &opts(SensorKind::Xt16, "PandarXT16.csv")).unwrap();
    assert_eq!(report.decoded, n - 3);
    let bad: u32 = sweeps.iter().map(|s| s.stats.bad_packets).sum();
    assert_eq!(bad, 3);
    let reasons: Vec<_> = report.refused.keys().cloned().collect();
    println!("XT16 refusals: {:?}", report.refused);
    for needle in ["truncated", "unknown model", "return-mode"] {
        assert!(
            reasons.iter().any(|r| r.contains(needle)),
            "{needle}: {reasons:?}"
        );
    }
    assert!(report.warnings().iter().any(|w| w.contains("refused")));

    // 40P: its mode byte flipped from dual (0x39) to strongest (0x37) in one packet: not the
    // sweep's mode, so another sensor's.
    let mut d = datagrams("40p.pcap");
    let n = d.len() as u64;
    let mode = 1240 + 14;
    assert_eq!(d[4].payload[mode], 0x39);
    d[4].payload[mode] = 0x37;
    let path = write(dir.path(), "40p.pcap", &d);
    let (sweeps, report) =
        sweeps::read_all(&path, &opts(SensorKind::Pandar40p, "Pandar40P.csv")).unwrap();
    assert_eq!(report.decoded, n - 1);
    let other: u32 = sweeps.iter().map(|s| s.stats.other_sensor).sum();
    assert_eq!(other, 1, "{:?}", report.refused);
}

#[test]
fn packets_of_two_models_on_one_port_decode_the_one_and_count_the_other() {
    let dir = tempfile::tempdir().unwrap();
    let xt32m = datagrams("xt32m.pcap");
    let qt64 = datagrams("qt64.pcap");
    let mut d = xt32m.clone();
    // The QT64's packets among the XT32M's, at the XT32M's times.
    for (k, q) in qt64.iter().enumerate() {
        let at = (2 * k + 1).min(d.len());
        let mut q = q.clone();
        q.time_ns = d[at - 1].time_ns;
        d.insert(at, q);
    }
    let path = write(dir.path(), "mixed.pcap", &d);
    // Found as the model most packets come from; the other's refused with the reason.
    let (_, report) = sweeps::read_all(
        &path,
        &SensorOptions {
            calibration: Some(fixture("PandarXT32M.csv")),
            ..SensorOptions::default()
        },
    )
    .unwrap();
    println!(
        "mixed: {} decoded, refused {:?}",
        report.decoded, report.refused
    );
    assert_eq!(report.sensor, "Hesai PandarXT32M");
    assert_eq!(report.decoded, xt32m.len() as u64);
    let refused: u64 = report.refused.values().sum();
    assert_eq!(refused, qt64.len() as u64);
    assert!(report
        .refused
        .keys()
        .any(|r| r.contains("protocol version")));
}

#[test]
fn a_missing_or_malformed_angle_correction_file_is_an_error_naming_it() {
    let pcap = fixture("40p.pcap");
    let none = SensorOptions {
        sensor: SensorKind::Pandar40p,
        ..SensorOptions::default()
    };
    let e = format!("{:#}", sweeps::read_all(&pcap, &none).unwrap_err());
    assert!(
        e.contains("--calibration") && e.contains("Pandar40P"),
        "{e}"
    );
    let dir = tempfile::tempdir().unwrap();
    let gone = dir.path().join("gone.csv");
    let e = format!(
        "{:#}",
        sweeps::read_all(
            &pcap,
            &SensorOptions {
                calibration: Some(gone.clone()),
                ..none.clone()
            }
        )
        .unwrap_err()
    );
    assert!(e.contains("gone.csv"), "{e}");
    // The XT16's file (16 rows) for the 40P; a row whose angle is not a number.
    let bad = |name: &str, text: &str| {
        let csv = dir.path().join(name);
        std::fs::write(&csv, text).unwrap();
        let o = SensorOptions {
            calibration: Some(csv),
            ..none.clone()
        };
        format!("{:#}", sweeps::read_all(&pcap, &o).unwrap_err())
    };
    let xt16 = std::fs::read_to_string(fixture("PandarXT16.csv")).unwrap();
    let e = bad("xt16.csv", &xt16);
    assert!(
        e.contains("xt16.csv") && e.contains("24 of the 40 channels"),
        "{e}"
    );
    let rows: String = (1..=40).map(|i| format!("{i},1.0,x\n")).collect();
    let e = bad("text.csv", &format!("Laser id,Elevation,Azimuth\n{rows}"));
    assert!(e.contains("text.csv") && e.contains("not a number"), "{e}");
}
