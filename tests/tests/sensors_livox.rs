//! The Livox SDK 1 decoder on the shared real recording (`livox/livox_tele15_small.pcap`, a
//! Tele-15: data type 2 points and IMU packets to port 56001): frames, times and IMU packets,
//! through the command, and point by point against cu-livox 1.3.0's parser (copper-rs) when
//! `KISS_ODOM_COPPER_DUMP` names the `tests/copper` tool (`bash tests/copper/compare.sh`).

use crate::sensor_points::{copper_dump, decode, payloads, run_poses, Points};
use kiss_odom_io::capture::sweeps;
use kiss_odom_io::dataset::SensorOptions;
use kiss_odom_sensors::{livox, PointMeta};
use kiss_odom_tests::{have_sensor_file, sensor_data};

const FILE: &str = "livox/livox_tele15_small.pcap";

/// Our decoder on every point packet (IMU packets are counted, as the readers do).
fn decode_all(payloads: &[Vec<u8>]) -> (Points, usize) {
    let is_imu = |p: &[u8]| livox::sdk1::Packet::new_checked(p).is_ok_and(|p| p.imu().is_some());
    let points: Vec<&[u8]> = payloads
        .iter()
        .map(Vec::as_slice)
        .filter(|p| !is_imu(p))
        .collect();
    let imu = payloads.len() - points.len();
    let index: std::collections::HashMap<u64, usize> = payloads
        .iter()
        .enumerate()
        .filter(|(_, p)| !is_imu(p))
        .map(|(n, p)| {
            (
                livox::sdk1::Packet::new_checked(p)
                    .unwrap()
                    .time_ns()
                    .unwrap(),
                n,
            )
        })
        .collect();
    let mut log = decode(
        livox::Decoder::new(livox::Config::default()).unwrap(),
        &points,
    );
    // Points reach the sink in chunks, not packet by packet: each point's packet is the one
    // stamped at its time less its firing's offset (every stamp is distinct).
    let firing = livox::Model::Horizon.firing_ns().unwrap_or(0.0);
    for (n, _, (start, t), m) in &mut log.points {
        let offset = (f64::from(m.column) * firing).round() as i64;
        let stamp = (*start as i64 + (*t * 1e9).round() as i64 - offset) as u64;
        *n = index[&stamp];
    }
    (log, imu)
}

#[test]
fn the_recording_decodes_into_frames_of_a_tenth_of_a_second() {
    if !have_sensor_file(FILE) {
        return;
    }
    let payloads = payloads(FILE);
    let (log, imu) = decode_all(&payloads);
    let decoded: u32 = log.sweeps.iter().map(|s| s.packets).sum();
    let refused: u32 = log
        .sweeps
        .iter()
        .map(|s| s.bad_packets + s.out_of_order)
        .sum();
    println!(
        "{FILE}: {} packets, {decoded} point packets decoded, {imu} IMU, {} frames, {} points",
        payloads.len(),
        log.sweeps.len(),
        log.points.len()
    );
    assert_eq!((decoded as usize + imu, refused), (payloads.len(), 0));
    assert_eq!(imu, 74);
    // 0.37 s: three whole frames of 0.1 s and the rest.
    assert_eq!(log.sweeps.len(), 4);
    // Each point's time leads back to its packet's stamp (decode_all looks it up, exactly,
    // from the time less 1/240,000 s per firing): then every packet has the returns its bytes
    // hold, counted here from the raw coordinates.
    let mut per_packet = vec![0usize; payloads.len()];
    for &(n, _, (_, t), _) in &log.points {
        per_packet[n] += 1;
        // A frame holds the packets that begin in its 0.1 s, each 0.4 ms of points.
        assert!((0.0..0.1004).contains(&t), "{t}");
    }
    for (n, bytes) in payloads.iter().enumerate() {
        if bytes.len() != 1362 {
            continue;
        }
        let returns = bytes[18..]
            .chunks(14)
            .filter(|p| p[..12].iter().any(|b| *b != 0))
            .count();
        assert_eq!(per_packet[n], returns, "packet {n}");
    }
    let lost: u32 = log.sweeps.iter().map(|s| s.lost_packets).sum();
    assert_eq!(lost, 0, "packets come 398-401 us apart: none lost");
}

#[test]
fn the_command_finds_the_sensor_and_counts_the_imu_packets() {
    if !have_sensor_file(FILE) {
        return;
    }
    let (frames, report) = sweeps::read_all(&sensor_data().join(FILE), &SensorOptions::default())
        .expect("auto-detected as Livox");
    assert_eq!(report.sensor, "Livox Horizon/Tele-15/Avia");
    assert_eq!((report.decoded, report.imu_packets), (926, 74));
    assert!(
        report.other_sources.is_empty(),
        "{:?}",
        report.other_sources
    );
    assert_eq!(frames.len(), 4);
    // The fourth is the open frame the recording ends in (0.07 s of its 0.1 s): not
    // registered.
    assert_eq!(run_poses(FILE), 3);
}

#[test]
fn points_equal_cu_livox_parsers() {
    if !have_sensor_file(FILE) {
        return;
    }
    let Some(dump) = copper_dump("livox", FILE) else {
        return;
    };
    let payloads = payloads(FILE);
    let (log, imu) = decode_all(&payloads);
    let ours: std::collections::HashMap<(usize, usize), ([f64; 3], PointMeta)> = log
        .points
        .iter()
        .map(|&(n, p, _, m)| ((n, usize::from(m.column)), (p, m)))
        .collect();
    let (mut theirs, mut zero, mut worst, mut worst_rel, mut worst_t) = (0, 0, 0f64, 0f64, 0u64);
    for line in dump.lines() {
        let v: Vec<&str> = line.split(',').collect();
        let (n, k): (usize, usize) = (v[0].parse().unwrap(), v[1].parse().unwrap());
        let xyz: [f64; 3] = [
            v[2].parse().unwrap(),
            v[3].parse().unwrap(),
            v[4].parse().unwrap(),
        ];
        let (refl, tag): (u16, u16) = (v[5].parse().unwrap(), v[6].parse().unwrap());
        let t: u64 = v[7].parse().unwrap();
        theirs += 1;
        let Some((p, m)) = ours.get(&(n, k)) else {
            assert_eq!(
                xyz, [0.0; 3],
                "a point only cu-livox decodes: packet {n} point {k}"
            );
            zero += 1;
            continue;
        };
        let d = xyz.iter().map(|v| v * v).sum::<f64>().sqrt();
        let e = (0..3).map(|i| (p[i] - xyz[i]).powi(2)).sum::<f64>().sqrt();
        worst = worst.max(e);
        worst_rel = worst_rel.max(e / d);
        assert_eq!((m.intensity, m.ring), (refl, tag));
        let packet = livox::sdk1::Packet::new_checked(&payloads[n])
            .unwrap()
            .time_ns()
            .unwrap();
        worst_t = worst_t.max(packet.abs_diff(t));
    }
    println!(
        "cu-livox: {theirs} points of {} packets ({imu} IMU packets refused by it), {zero} at \
         the origin (no return: cu-livox keeps them, we drop them); ours {} = {theirs} - {zero}",
        theirs / 96,
        log.points.len()
    );
    assert_eq!(theirs / 96 + imu, payloads.len());
    assert_eq!(log.points.len(), theirs - zero);
    println!("xyz: worst {worst:.2e} m, {worst_rel:.2e} of the distance (cu-livox: f32); tolerance 1e-6 of it");
    assert!(worst_rel < 1e-6);
    println!("packet time: worst {worst_t} ns against cu-livox's header timestamp, tolerance 0");
    assert_eq!(worst_t, 0);
}
