//! The decoder chosen for what the packets are, and what it does not use said: Livox SDK 1
//! packets built here (the points of `sensors/tests/livox.rs`'s data type 2) on a given port,
//! a second Livox unit's SDK 2 packets on another, and a recording that ends inside a frame.

use super::super::frames::SweepFrames;
use super::super::identify::robosense_frame;
use super::super::sweeps::{decode, DatagramSource, LIVOX2_PORT, LIVOX_PORT};
use super::*;
use crate::dataset::{FrameSource, Item};
use kiss_odom_sensors::livox::{sdk1, sdk2};

/// 2024-09-17, in ns since the epoch.
const T0: u64 = 1_726_588_075_000_000_000;
/// An Avia packet's 96 firings at 240,000 a second.
const PACKET_NS: u64 = 400_000;

/// Datagrams from a list, as a capture would hand them on.
struct Listed(VecDeque<Datagram>);

impl DatagramSource for Listed {
    fn next_datagram(&mut self) -> Result<Option<Datagram>> {
        Ok(self.0.pop_front())
    }
}

/// An SDK 1 data type 2 packet stamped `t` (ns), each firing a point a few metres away.
fn sdk1_packet(t: u64) -> Vec<u8> {
    let (size, n) = sdk1::layout(2).unwrap();
    let mut b = vec![0u8; sdk1::packet_len(2).unwrap()];
    b[0..4].copy_from_slice(&[sdk1::VERSION, 1, 1, 0]);
    b[8] = 1;
    b[9] = 2;
    b[10..18].copy_from_slice(&t.to_le_bytes());
    for k in 0..n {
        let at = 18 + size * k;
        let x = 1000 + 10 * k as i32;
        b[at..at + 4].copy_from_slice(&x.to_le_bytes());
        b[at + 4..at + 8].copy_from_slice(&2000i32.to_le_bytes());
        b[at + 12] = 10;
        b[at + 13] = 16;
    }
    b
}

/// The start of an SDK 2 (Mid-360) point packet: version, length, data type 1.
fn sdk2_packet() -> Vec<u8> {
    let mut b = vec![0u8; sdk2::packet_len(1, sdk2::MID360_POINTS).unwrap()];
    let n = b.len() as u16;
    b[sdk2::field::LENGTH].copy_from_slice(&n.to_le_bytes());
    b[sdk2::field::DATA_TYPE] = 1;
    b
}

/// `count` Avia packets on port 56001 from `T0 + offset_ns`, one every 0.4 ms.
fn avia(count: u64, offset_ns: u64) -> Vec<Datagram> {
    (0..count)
        .map(|k| {
            let t = T0 + offset_ns + k * PACKET_NS;
            Datagram {
                time_ns: t,
                source: "192.168.1.100:56000".parse().unwrap(),
                port: LIVOX_PORT,
                payload: sdk1_packet(t),
            }
        })
        .collect()
}

fn sweeps_of(datagrams: Vec<Datagram>, opts: &SensorOptions) -> Result<PcapSweeps> {
    decode(
        Path::new("t.pcap"),
        Box::new(Listed(datagrams.into())),
        opts,
    )
}

#[test]
fn auto_on_a_given_port_decodes_the_family_its_packets_name() {
    let opts = SensorOptions {
        port: Some(LIVOX_PORT),
        ..SensorOptions::default()
    };
    let mut s = sweeps_of(avia(600, 0), &opts).unwrap();
    let frames = s.by_ref().collect::<Result<Vec<_>>>().unwrap();
    let r = s.report();
    println!(
        "{}: {} decoded, {} frames",
        r.sensor,
        r.decoded,
        frames.len()
    );
    assert!(r.sensor.starts_with("Livox"), "{}", r.sensor);
    assert_eq!((r.decoded, r.refused.len()), (600, 0), "{:?}", r.refused);
    assert!(frames.len() >= 2);
}

#[test]
fn a_second_livox_on_another_port_is_warned_as_a_second_hesai_is() {
    let mut d = avia(300, 0);
    let mid360: Vec<_> = (0..40)
        .map(|k| Datagram {
            time_ns: T0 + k * 10 * PACKET_NS + 1,
            source: "192.168.1.101:56300".parse().unwrap(),
            port: LIVOX2_PORT,
            payload: sdk2_packet(),
        })
        .collect();
    d.extend(mid360);
    d.sort_by_key(|p| p.time_ns);
    let opts = SensorOptions {
        sensor: SensorKind::Livox,
        ..SensorOptions::default()
    };
    let mut s = sweeps_of(d, &opts).unwrap();
    for sweep in s.by_ref() {
        sweep.unwrap();
    }
    let w = s.report().warnings();
    println!("{w:?}");
    assert!(
        w.iter()
            .any(|w| w.starts_with("40 sensor data packet(s) on port 56301")),
        "{w:?}"
    );
}

#[test]
fn options_the_sensor_does_not_use_are_named_and_a_missing_file_is_an_error() {
    let livox = SensorOptions {
        sensor: SensorKind::Livox,
        cut_angle_deg: Some(90.0),
        ..SensorOptions::default()
    };
    let s = sweeps_of(avia(10, 0), &livox).unwrap();
    let notes = s.report().notes.clone();
    println!("{notes:?}");
    assert!(notes
        .iter()
        .any(|n| n.starts_with("input.cut_angle = 90 not used")));
    let missing = SensorOptions {
        calibration: Some("no-such-file.csv".into()),
        ..livox
    };
    let e = sweeps_of(avia(10, 0), &missing).err().unwrap().to_string();
    println!("{e}");
    assert!(e.contains("no-such-file.csv: no such file"), "{e}");
    let velodyne = SensorOptions {
        sensor: SensorKind::Vlp16,
        port: Some(2368),
        frame_period_s: Some(0.05),
        ..SensorOptions::default()
    };
    let s = sweeps_of(Vec::new(), &velodyne).unwrap();
    let notes = &s.report().notes;
    println!("{notes:?}");
    assert!(notes
        .iter()
        .any(|n| n.starts_with("input.frame_period = 0.05 not used")));
}

#[test]
fn an_open_frame_at_the_end_of_the_recording_is_dropped_with_a_warning() {
    // Frames of 0.1 s (250 packets) from T0, which is on a frame boundary: two whole ones,
    // then 0.04 s of the third.
    let opts = SensorOptions {
        sensor: SensorKind::Livox,
        ..SensorOptions::default()
    };
    let s = sweeps_of(avia(600, 0), &opts).unwrap();
    let mut frames = SweepFrames::new(s, "t.pcap", 1 << 20);
    let mut packets = Vec::new();
    while let Some(item) = frames.next_item().unwrap() {
        if let Item::Frame(f) = item {
            packets.push(f.sweep.unwrap().stats.packets);
        }
    }
    let t = frames.trailer();
    println!("frames of {packets:?} packets; trailer {:?}", t.warnings);
    assert_eq!(packets, [250, 250]);
    assert!(
        t.warnings
            .iter()
            .any(|w| w.contains("t.pcap#2: the recording ends in this sweep, 100 packet(s)")),
        "{:?}",
        t.warnings
    );
}

#[test]
fn auto_on_a_given_port_decodes_a_hesai_recording_as_its_model() {
    // The PandarXT-16 scan of nebula's tests (its nominal angles are built in).
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/hesai-nebula/xt16.pcap");
    let opts = SensorOptions {
        port: Some(2368),
        ..SensorOptions::default()
    };
    let mut s = decode(&file, Box::new(pcap::open(&file).unwrap()), &opts).unwrap();
    for sweep in s.by_ref() {
        sweep.unwrap();
    }
    let r = s.report();
    println!("{}: {} of {} decoded", r.sensor, r.decoded, r.on_port);
    assert_eq!(r.sensor, hesai::Model::Xt16.name());
    assert!(r.decoded > 0 && r.refused.is_empty(), "{:?}", r.refused);
}

#[test]
fn auto_on_a_given_port_takes_a_robosense_its_packets_name() {
    use kiss_odom_sensors::robosense::{self, solid};
    let on_port = |payload: Vec<u8>| Datagram {
        time_ns: T0,
        source: "192.168.1.200:6699".parse().unwrap(),
        port: 6699,
        payload,
    };
    let opts = SensorOptions {
        port: Some(6699),
        ..SensorOptions::default()
    };
    let mut e1r = vec![0u8; solid::Model::E1r.packet_len()];
    e1r[..4].copy_from_slice(&solid::ID);
    let s = sweeps_of(vec![on_port(e1r)], &opts).unwrap();
    println!("{}", s.report().sensor);
    assert_eq!(s.report().sensor, "Robosense E1R");
    // The Airy by its layout: the decoder asks for the laser angles the network did not bring.
    let airy = robosense_frame(robosense::Model::Airy);
    let e = sweeps_of(vec![on_port(airy)], &opts)
        .err()
        .unwrap()
        .to_string();
    println!("{e}");
    assert!(e.contains("a RS-Airy needs its laser angles"), "{e}");
    // A Helios's packets could be a Helios-16P's: refused naming the models, not read as a
    // Velodyne's.
    let helios = robosense_frame(robosense::Model::Helios);
    let e = sweeps_of(vec![on_port(helios)], &opts)
        .err()
        .unwrap()
        .to_string();
    println!("{e}");
    assert!(e.contains("look like a spinning Robosense's"), "{e}");
}
