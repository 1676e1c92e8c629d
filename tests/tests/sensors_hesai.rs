//! The PandarXT-32 decoder on the shared real recording (`hesai/hesai-xt32-small.pcap`, dual
//! return, UDP sequence numbers): against the packets' own sequence numbers and times, through
//! the command, and point by point against cu-hesai 1.3.0's parser (copper-rs) when
//! `KISS_ODOM_COPPER_DUMP` names the `tests/copper` tool (`bash tests/copper/compare.sh` builds
//! it and runs this; without it the comparison prints SKIP).

use crate::sensor_points::{copper_dump, decode, payloads, run_poses, Points};
use kiss_odom_io::capture::sweeps;
use kiss_odom_io::dataset::SensorOptions;
use kiss_odom_sensors::hesai::{self, wire::field};
use kiss_odom_sensors::Return;
use kiss_odom_tests::{have_sensor_file, sensor_data};

const FILE: &str = "hesai/hesai-xt32-small.pcap";

fn decode_all(payloads: &[Vec<u8>]) -> Points {
    let dec = hesai::Decoder::new(hesai::Config::default()).unwrap();
    let bytes: Vec<&[u8]> = payloads.iter().map(Vec::as_slice).collect();
    let mut log = decode(dec, &bytes);
    // Points reach the sink in chunks, not packet by packet: each point's packet is the one
    // stamped at its time less its firing's and channel's offsets (every stamp is distinct).
    let index: std::collections::HashMap<u64, usize> = payloads
        .iter()
        .enumerate()
        .map(|(n, p)| (hesai::Packet::new_checked(p).unwrap().unix_ns().unwrap(), n))
        .collect();
    assert_eq!(index.len(), payloads.len());
    for (n, _, (start, t), m) in &mut log.points {
        let offset =
            hesai::point_offset_ns(2 * (usize::from(m.column) % 4), usize::from(m.ring), 2);
        let stamp = (*start as i64 + (*t * 1e9).round() as i64 - offset) as u64;
        *n = index[&stamp];
    }
    log
}

fn sequence(p: &[u8]) -> u32 {
    u32::from_le_bytes(p[field::UDP_SEQUENCE].try_into().unwrap())
}

#[test]
fn the_recording_decodes_whole_with_its_losses_counted() {
    if !have_sensor_file(FILE) {
        return;
    }
    let payloads = payloads(FILE);
    let log = decode_all(&payloads);
    // Losses from the sequence numbers, counted here from the raw bytes.
    let gaps: u32 = payloads
        .windows(2)
        .map(|w| sequence(&w[1]).wrapping_sub(sequence(&w[0])) - 1)
        .sum();
    let decoded: u32 = log.sweeps.iter().map(|s| s.packets).sum();
    let lost: u32 = log.sweeps.iter().map(|s| s.lost_packets).sum();
    let refused: u32 = log
        .sweeps
        .iter()
        .map(|s| s.bad_packets + s.out_of_order)
        .sum();
    println!(
        "{FILE}: {} packets, {decoded} decoded, {lost} lost (sequence gaps {gaps}), {} sweeps, {} points",
        payloads.len(),
        log.sweeps.len(),
        log.points.len()
    );
    assert_eq!((decoded as usize, refused), (payloads.len(), 0));
    assert!(gaps > 0, "the recording has lost packets");
    assert_eq!(lost, gaps);
    // 0.2 s at 600 rpm: a whole turn from where the recording starts, then the rest.
    assert_eq!(log.sweeps.len(), 2);
    assert_eq!(log.sweeps[0].end, kiss_odom_sensors::SweepEnd::Complete);
    // Each point's time leads back to its packet's stamp (decode_all looks it up, exactly):
    // then every packet has the returns its bytes hold, counted here from the raw channels
    // (a dual pair of one echo is one point).
    let mut per_packet = vec![0usize; payloads.len()];
    for p in &log.points {
        per_packet[p.0] += 1;
    }
    for (n, bytes) in payloads.iter().enumerate() {
        let p = hesai::Packet::new_checked(bytes).unwrap();
        let mut want = 0;
        for firing in 0..4 {
            for c in 0..32 {
                let (a, b) = (p.channel(2 * firing, c).0, p.channel(2 * firing + 1, c).0);
                want += if a == b {
                    usize::from(a != 0)
                } else {
                    usize::from(a != 0) + usize::from(b != 0)
                };
            }
        }
        assert_eq!(per_packet[n], want, "packet {n}");
    }
}

#[test]
fn the_command_finds_the_sensor_and_runs() {
    if !have_sensor_file(FILE) {
        return;
    }
    let (sweeps, report) = sweeps::read_all(&sensor_data().join(FILE), &SensorOptions::default())
        .expect("auto-detected as a PandarXT-32");
    assert_eq!(report.sensor, "Hesai PandarXT-32");
    assert_eq!(report.decoded, 1000);
    assert_eq!(sweeps.len(), 2);
    assert_eq!(run_poses(FILE), 2);
}

/// One line of `copper-dump hesai`.
struct Theirs {
    packet: usize,
    block: usize,
    channel: usize,
    xyz: [f64; 3],
    reflectivity: f64,
    block_ns: u64,
}

#[test]
fn points_equal_cu_hesai_parsers() {
    if !have_sensor_file(FILE) {
        return;
    }
    let Some(dump) = copper_dump("hesai", FILE) else {
        return;
    };
    let theirs: Vec<Theirs> = dump
        .lines()
        .map(|l| {
            let v: Vec<&str> = l.split(',').collect();
            Theirs {
                packet: v[0].parse().unwrap(),
                block: v[1].parse().unwrap(),
                channel: v[2].parse().unwrap(),
                xyz: [
                    v[3].parse().unwrap(),
                    v[4].parse().unwrap(),
                    v[5].parse().unwrap(),
                ],
                reflectivity: v[6].parse().unwrap(),
                block_ns: v[7].parse().unwrap(),
            }
        })
        .collect();
    let payloads = payloads(FILE);
    let log = decode_all(&payloads);
    assert_eq!(
        theirs.len(),
        payloads.len() * 256,
        "cu-hesai keeps every channel"
    );

    // Ours, by (packet, block, channel): a dual pair's first block holds the first return,
    // the second the strongest (mode 0x3C); one echo in both is one point, for both blocks.
    let mut ours = std::collections::HashMap::new();
    for (n, p, _, m) in &log.points {
        let firing = usize::from(m.column) % 4;
        let blocks: &[usize] = match m.ret {
            Return::First => &[2 * firing],
            Return::Strongest => &[2 * firing + 1],
            Return::Both => &[2 * firing, 2 * firing + 1],
            r => panic!("{r:?} in a first-and-strongest recording"),
        };
        for &b in blocks {
            assert!(ours
                .insert((*n, b, usize::from(m.ring)), (*p, m.intensity))
                .is_none());
        }
    }
    let (mut zero, mut worst, mut worst_rel) = (0, 0f64, 0f64);
    for t in &theirs {
        let d = t.xyz.iter().map(|v| v * v).sum::<f64>().sqrt();
        let Some((p, intensity)) = ours.get(&(t.packet, t.block, t.channel)) else {
            assert!(
                d == 0.0,
                "a return only cu-hesai decodes: packet {} block {} channel {}",
                t.packet,
                t.block,
                t.channel
            );
            zero += 1;
            continue;
        };
        // cu-hesai takes the clockwise azimuth as counter-clockwise: its y is ours negated.
        let e = [p[0] - t.xyz[0], p[1] + t.xyz[1], p[2] - t.xyz[2]];
        let e = e.iter().map(|v| v * v).sum::<f64>().sqrt();
        worst = worst.max(e);
        worst_rel = worst_rel.max(e / d);
        assert_eq!(f64::from(*intensity), t.reflectivity.round());
    }
    let pairs_as_one = log
        .points
        .iter()
        .filter(|p| p.3.ret == Return::Both)
        .count();
    println!(
        "cu-hesai: {} channels, {zero} without a return (cu-hesai keeps them as points at the \
         origin; we drop them), {pairs_as_one} dual pairs of one echo (cu-hesai: two equal \
         points; we: one). Ours: {} points = {} - {zero} - {pairs_as_one}.",
        theirs.len(),
        log.points.len(),
        theirs.len()
    );
    assert_eq!(log.points.len(), theirs.len() - zero - pairs_as_one);
    // cu-hesai computes in f32: a few ulp of the distance.
    println!("xyz: worst {worst:.2e} m, {worst_rel:.2e} of the distance; tolerance 1e-6 of it");
    assert!(worst_rel < 1e-6);
    // Block times: cu-hesai's Packet::block_ts reads the header's return count 2 as single
    // return (it tests for 1), so it spaces all eight blocks 50 us apart; its last block,
    // the stamped firing, is the same in both readings: compare that one.
    let mut worst_t = 0f64;
    for t in theirs.iter().filter(|t| t.block == 7) {
        let stamped = log
            .points
            .iter()
            .find(|p| p.0 == t.packet && usize::from(p.3.column) % 4 == 3 && p.3.ring == 0);
        if let Some((_, _, (start, t_s), _)) = stamped {
            let after_block = (*start as i64 - t.block_ns as i64) as f64 + t_s * 1e9;
            worst_t = worst_t.max((after_block - 368.0).abs());
        }
    }
    println!(
        "stamped firing's time: worst {worst_t:.1} ns against cu-hesai's block_ts, tolerance 1 ns"
    );
    assert!(worst_t < 1.0);
}
