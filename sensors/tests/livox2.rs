//! The Livox SDK 2 decoder (Mid-360, HAP) on synthetic packets: every data type's geometry,
//! per-point times from the packet's own interval, frames by time, the CRC, and how IMU,
//! lost, late and malformed packets are counted. And each header field of an SDK 1 and an
//! SDK 2 packet corrupted alone: refused naming that field.

use kiss_odom_sensors::livox::{self, sdk1, sdk2, Model};
mod common;
#[path = "common/livox_sdk1.rs"]
mod sdk1_packets;

use common::{feed, with, Log};
use kiss_odom_sensors::{Decode, PacketError, Pushed, Return, SweepEnd};

const T0: u64 = 1_726_588_075_299_964_555;
/// The Mid-360's packet: 96 points in 480 us.
const N: usize = sdk2::MID360_POINTS;
const INTERVAL: u16 = 4800;

/// `b` with its CRC-32 set from its bytes (as the sensor sends it).
fn sealed(mut b: Vec<u8>) -> Vec<u8> {
    let crc = sdk2::crc32(&b[sdk2::field::TIMESTAMP.start..]);
    b[sdk2::field::CRC32].copy_from_slice(&crc.to_le_bytes());
    b
}

/// A header of `data_type` with `points` points at `t` ns, its data zeroed.
fn header(data_type: u8, points: usize, t: u64) -> Vec<u8> {
    let len = sdk2::packet_len(data_type, points).unwrap();
    let mut b = vec![0u8; len];
    b[1..3].copy_from_slice(&(len as u16).to_le_bytes());
    b[3..5].copy_from_slice(&INTERVAL.to_le_bytes());
    b[5..7].copy_from_slice(&(points as u16).to_le_bytes());
    b[10] = data_type;
    b[11] = 1;
    b[28..36].copy_from_slice(&t.to_le_bytes());
    b
}

/// A packet of `data_type` at `t` ns whose point `k` is (1 + k / 10, 2, -0.5) m (the second
/// return twice as far), reflectivity k and tag 0x15; point 3 returns nothing.
fn packet(data_type: u8, t: u64) -> Vec<u8> {
    let size = sdk2::point_size(data_type).unwrap();
    let mut b = header(data_type, N, t);
    for k in 0..N {
        if k == 3 {
            continue;
        }
        let at = 36 + size * k;
        let p = &mut b[at..at + size];
        let xyz = [1.0 + k as f64 / 10.0, 2.0, -0.5];
        let cart = |p: &mut [u8], s: f64| {
            for (i, v) in xyz.iter().enumerate() {
                let mm = ((v * s * 1000.0).round() as i32).to_le_bytes();
                p[4 * i..4 * i + 4].copy_from_slice(&mm);
            }
            p[12] = k as u8;
            p[13] = 0x15;
        };
        match data_type {
            1 => cart(p, 1.0),
            sdk2::DUAL => {
                cart(p, 1.0);
                cart(&mut p[14..], 2.0);
            }
            2 => {
                for (i, v) in xyz.iter().enumerate() {
                    let cm = ((v * 100.0).round() as i16).to_le_bytes();
                    p[2 * i..2 * i + 2].copy_from_slice(&cm);
                }
                p[6] = k as u8;
                p[7] = 0x15;
            }
            3 => {
                let r = (xyz[0] * xyz[0] + xyz[1] * xyz[1] + xyz[2] * xyz[2]).sqrt();
                let zenith = ((xyz[2] / r).acos().to_degrees() * 100.0).round() as u16;
                let azimuth = (xyz[1].atan2(xyz[0]).to_degrees() * 100.0).round() as u16;
                p[0..4].copy_from_slice(&((r * 1000.0).round() as u32).to_le_bytes());
                p[4..6].copy_from_slice(&zenith.to_le_bytes());
                p[6..8].copy_from_slice(&azimuth.to_le_bytes());
                p[8] = k as u8;
                p[9] = 0x15;
            }
            _ => unreachable!(),
        }
    }
    sealed(b)
}

fn decoder(frame_period_ns: u64) -> livox::Decoder {
    livox::Decoder::new(livox::Config {
        model: Model::Mid360,
        frame_period_ns,
    })
    .unwrap()
}

#[test]
fn the_crc_is_the_common_crc_32() {
    // The check value every CRC-32 catalogue gives for "123456789".
    assert_eq!(sdk2::crc32(b"123456789"), 0xCBF4_3926);
    assert_eq!(sdk2::crc32(b""), 0);
}

#[test]
fn every_data_type_gives_the_same_points_at_the_packets_own_point_interval() {
    for data_type in [1, 2, 3, sdk2::DUAL] {
        let mut dec = decoder(100_000_000);
        let mut log = Log::default();
        feed(&mut dec, &packet(data_type, T0), &mut log).unwrap();
        dec.finish(&mut log);
        let dual = data_type == sdk2::DUAL;
        let per_firing = if dual { 2 } else { 1 };
        assert_eq!(log.points.len(), (N - 1) * per_firing, "type {data_type}");
        assert_eq!(log.starts[0].start_ns, T0);
        // 16-bit points are whole centimetres; spherical ones carry 0.01 degree angles.
        let tol = match data_type {
            2 => 5e-3,
            3 => 2e-3,
            _ => 1e-12,
        };
        for &(_, p, t, m) in &log.points {
            let k = usize::from(m.column);
            let s = if m.ret == Return::Second { 2.0 } else { 1.0 };
            let want = [(1.0 + k as f64 / 10.0) * s, 2.0 * s, -0.5 * s];
            for i in 0..3 {
                assert!(
                    (p[i] - want[i]).abs() < tol,
                    "type {data_type}: {p:?} vs {want:?}"
                );
            }
            // 480 us over 96 points: 5 us apart.
            assert_eq!(
                t,
                k as f64 * (f64::from(INTERVAL) * 100.0 / N as f64) * 1e-9
            );
            assert_eq!((m.intensity, m.ring), (k as u16, 0x15), "reflectivity, tag");
            assert!(m.ret == Return::First || (dual && m.ret == Return::Second));
        }
    }
}

#[test]
fn frames_are_cut_by_time_and_losses_counted_from_the_packets_span() {
    let mut dec = decoder(10_000_000);
    let mut log = Log::default();
    let mut ended_at = Vec::new();
    // 480 us a packet; 50 packets = 24 ms; lose packets 5..9.
    for i in 0..50u64 {
        if (5..9).contains(&i) {
            continue;
        }
        let before = log.ends.len();
        feed(&mut dec, &packet(1, T0 + 480_000 * i), &mut log).unwrap();
        if log.ends.len() > before {
            ended_at.push(i);
        }
    }
    dec.finish(&mut log);
    // Frames start at T0, +10 ms, +20 ms: packets 21 (10.08 ms) and 42 (20.16 ms) begin them.
    assert_eq!(ended_at, [21, 42]);
    let lost: Vec<u32> = log.ends.iter().map(|s| s.lost_packets).collect();
    assert_eq!(lost, [4, 0, 0]);
    let packets: Vec<u32> = log.ends.iter().map(|s| s.packets).collect();
    assert_eq!(packets, [17, 21, 8]);
    assert_eq!(log.ends[2].end, SweepEnd::Finished);
}

#[test]
fn a_frame_of_packets_with_no_points_is_an_empty_frame_not_an_error() {
    let mut dec = decoder(10_000_000);
    let mut log = Log::default();
    for i in 0..25u64 {
        let b = if i < 21 {
            sealed(header(1, N, T0 + 480_000 * i))
        } else {
            packet(1, T0 + 480_000 * i)
        };
        feed(&mut dec, &b, &mut log).unwrap();
    }
    // A packet that holds no point at all (dot_num 0) is decoded too.
    let empty = sealed(header(1, 0, T0 + 480_000 * 25));
    assert_eq!(empty.len(), 36);
    assert_eq!(feed(&mut dec, &empty, &mut log), Ok(Pushed::Decoded));
    dec.finish(&mut log);
    assert_eq!(log.ends.len(), 2);
    assert_eq!((log.ends[0].packets, log.ends[1].packets), (21, 5));
    assert!(
        log.points.iter().all(|p| p.0 == 1),
        "the first frame is empty"
    );
    assert_eq!(log.points.len(), 4 * (N - 1));
}

#[test]
fn imu_crc_version_length_and_late_packets_are_refused_and_counted() {
    let mut dec = decoder(100_000_000);
    let mut log = Log::default();
    let g = packet(1, T0 + 480_000);
    feed(&mut dec, &g, &mut log).unwrap();
    assert_eq!(
        feed(&mut dec, &packet(1, T0), &mut log),
        Err(PacketError::Late)
    );
    // An IMU packet on the point port: read by `imu`, refused by the decoder.
    let mut imu = header(sdk2::IMU, 1, T0 + 960_000);
    imu[36..40].copy_from_slice(&0.25f32.to_le_bytes());
    imu[56..60].copy_from_slice(&(-1.0f32).to_le_bytes());
    let imu = sealed(imu);
    assert_eq!(imu.len(), 60);
    let sample = sdk2::Packet::new_checked(&imu).unwrap().imu().unwrap();
    assert_eq!((sample.gyro[0], sample.accel_g[2]), (0.25, -1.0));
    assert_eq!(feed(&mut dec, &imu, &mut log), Err(PacketError::PacketType));
    // A point packet of another data type than the stream's: another sensor, or reconfigured.
    assert_eq!(
        feed(&mut dec, &packet(2, T0 + 960_000), &mut log),
        Err(PacketError::OtherSensor)
    );
    let mut flipped = g.clone();
    flipped[500] ^= 0x01;
    let mut long_field = g.clone();
    long_field[1] = long_field[1].wrapping_add(1);
    // An IMU packet that says it holds two samples (its length field and datagram agreeing);
    // a point packet whose points span no time.
    let mut two = header(sdk2::IMU, 2, T0 + 960_000);
    two[1..3].copy_from_slice(&60u16.to_le_bytes());
    two.truncate(60);
    let mut no_interval = g.clone();
    no_interval[3..5].copy_from_slice(&[0, 0]);
    let cases: [(Vec<u8>, PacketError); 10] = [
        (g[..1000].to_vec(), PacketError::Truncated),
        (g[..20].to_vec(), PacketError::Truncated),
        ([g.as_slice(), &[0]].concat(), PacketError::Length),
        (
            long_field,
            PacketError::LengthField {
                stated: 1381,
                expected: 1380,
            },
        ),
        (with(&g, 0, 5), PacketError::Version),
        (with(&g, 10, 9), PacketError::PacketType),
        (flipped, PacketError::Checksum),
        (sealed(with(&g, 11, 3)), PacketError::TimeType { kind: 3 }),
        (sealed(two), PacketError::ImuPoints { dot_num: 2 }),
        (no_interval, PacketError::PointInterval),
    ];
    for (bytes, want) in &cases {
        assert_eq!(feed(&mut dec, bytes, &mut log), Err(*want));
    }
    // The CRC covers the timestamp: a changed time with the old CRC is refused.
    let mut moved = g.clone();
    moved[28] ^= 0x10;
    assert_eq!(feed(&mut dec, &moved, &mut log), Err(PacketError::Checksum));
    assert_eq!(
        feed(&mut dec, &packet(1, T0 + 960_000), &mut log),
        Ok(Pushed::Decoded)
    );
    dec.finish(&mut log);
    let s = log.ends[0];
    assert_eq!((s.packets, s.out_of_order, s.other_sensor), (2, 1, 1));
    assert_eq!(s.bad_packets, cases.len() as u32 + 2, "with the IMU packet");
}

#[test]
fn an_sdk_1_packet_is_not_read_as_sdk_2_nor_the_other_way() {
    let mut dec = decoder(100_000_000);
    let mut log = Log::default();
    let mut sdk1 = vec![0u8; 18 + 14 * 96];
    sdk1[0] = 5;
    sdk1[9] = 2;
    assert_eq!(feed(&mut dec, &sdk1, &mut log), Err(PacketError::Version));
    let mut one = livox::Decoder::new(livox::Config::default()).unwrap();
    assert_eq!(
        feed(&mut one, &packet(1, T0), &mut log),
        Err(PacketError::Version)
    );
}

/// A Mid-360 point packet at `t` ns with counter `count`.
fn counted(t: u64, count: u16) -> Vec<u8> {
    let mut b = packet(1, t);
    b[sdk2::field::UDP_CNT].copy_from_slice(&count.to_le_bytes());
    sealed(b)
}

#[test]
fn losses_come_from_the_counter_where_the_times_agree_and_stay_within_bounds() {
    let mut dec = decoder(100_000_000);
    let mut log = Log::default();
    let mut refused = Vec::new();
    let mut push = |b: Vec<u8>, log: &mut Log| {
        if let Err(e) = feed(&mut dec, &b, log) {
            refused.push(e);
        }
    };
    let at = |i: u64| T0 + 480_000 * i;
    for i in 0..10 {
        push(counted(at(i), i as u16), &mut log);
    }
    // Packets 10..13 lost: the counter and the time both say so.
    push(counted(at(13), 13), &mut log);
    // A counter that jumps 1000 where the time moved one packet: the time's count, none.
    push(counted(at(14), 1014), &mut log);
    // One packet 10 s ahead, one whose time wrapped to near 2^64: held out as strays, then
    // the stream goes on where it was.
    push(counted(at(15) + 10_000_000_000, 1015), &mut log);
    push(counted(u64::MAX - 5, 1016), &mut log);
    for i in 17..30 {
        push(counted(at(i), 1000 + i as u16), &mut log);
    }
    dec.finish(&mut log);
    assert_eq!(refused, [PacketError::Ahead, PacketError::Ahead]);
    assert_eq!(log.ends.len(), 1, "no frame of a stray");
    let s = log.ends[0];
    // 3 lost before packet 13, and the two strays' places (15, 16) by time and counter.
    assert_eq!((s.lost_packets, s.out_of_order, s.packets), (3 + 2, 2, 25));
}

#[test]
fn the_last_frame_is_complete_when_its_packets_reach_its_end() {
    for (packets, end) in [(42, SweepEnd::Complete), (41, SweepEnd::Finished)] {
        let mut dec = decoder(10_000_000);
        let mut log = Log::default();
        for i in 0..packets {
            feed(&mut dec, &packet(1, T0 + 480_000 * i), &mut log).unwrap();
        }
        dec.finish(&mut log);
        // Packets 21..: the second frame, from 10.08 ms; the 42nd's points end at 20.16 ms.
        assert_eq!(log.ends.len(), 2);
        assert_eq!(log.ends[1].end, end, "{packets} packets");
    }
}

#[test]
fn each_corrupted_header_field_is_refused_by_its_own_name() {
    use PacketError::*;
    // A Horizon (SDK 1) or a Mid-360 (SDK 2) decoder, fresh or after a good packet.
    let refusal = |model: Model, after: bool, bytes: &[u8]| {
        let mut dec = livox::Decoder::new(livox::Config {
            model,
            ..livox::Config::default()
        })
        .unwrap();
        let mut log = Log::default();
        let good = match model {
            Model::Mid360 => packet(1, T0),
            _ => sdk1_packets::packet(2, T0),
        };
        if after {
            feed(&mut dec, &good, &mut log).unwrap();
        }
        dec.push(bytes, &mut log)
    };
    let (one, two) = (Model::Horizon, Model::Mid360);
    let (fresh, after) = (false, true);
    let g1 = sdk1_packets::packet(2, T0 + 400_000);
    let g2 = packet(1, T0 + 480_000);
    let s1 = |at: usize, v: u8| with(&g1, at, v);
    let s2 = |at: usize, v: u8| with(&g2, at, v);
    let s2_16 = |at: usize, v: u16| {
        let mut b = g2.clone();
        b[at..at + 2].copy_from_slice(&v.to_le_bytes());
        b
    };
    let (f1, f2) = (sdk1::field::DATA_TYPE, sdk2::field::DATA_TYPE);
    let mut gps = with(&g1, sdk1::field::TIMESTAMP_TYPE, 3);
    gps[10..14].copy_from_slice(&[24, 13, 17, 15]);
    let imu = sdk1_packets::packet(sdk1::IMU, T0 + 400_000);
    let points = |data_type, points, len| PointsLength {
        data_type,
        points,
        len,
    };
    let length_field = LengthField {
        stated: 1381,
        expected: 1380,
    };
    // (protocol, field, packet, after a good one, refusal, what its text names)
    #[rustfmt::skip]
    let rows = vec![
        (one, "version", s1(sdk1::field::VERSION, 1), fresh, Version, "protocol version"),
        (one, "data type", s1(f1, 9), fresh, PacketType, "data type"),
        // Another data type's length: the data type byte is what is wrong.
        (one, "data type", s1(f1, 0), fresh, points(0, 100, 1362), "data type 0"),
        (one, "data type", s1(f1, sdk1::IMU), fresh, points(6, 1, 1362), "data type 6"),
        (one, "length", g1[..1000].to_vec(), fresh, Truncated, "shorter"),
        (one, "timestamp type", s1(8, 7), fresh, TimeType { kind: 7 }, "timestamp type 7"),
        (one, "GPS month", gps, fresh, DateTime, "date"),
        (one, "IMU data", imu, fresh, PacketType, "IMU"),
        (one, "lidar id", s1(sdk1::field::LIDAR, 2), after, OtherSensor, "another sensor"),
        (two, "version", s2(sdk2::field::VERSION, 5), fresh, Version, "protocol version"),
        (two, "length", s2(1, 0x65), fresh, length_field, "length field 1381"),
        // The length field and the datagram agree: dot_num or the data type is what is wrong.
        (two, "dot_num", s2_16(5, 95), fresh, points(1, 95, 1380), "95 points"),
        (two, "dot_num", s2_16(5, 95), after, points(1, 95, 1380), "dot_num"),
        (two, "data type", s2(f2, 2), fresh, points(2, 96, 1380), "data type 2"),
        (two, "data type", s2(f2, 9), fresh, PacketType, "data type"),
        (two, "data type", s2(f2, sdk2::IMU), fresh, ImuPoints { dot_num: 96 }, "IMU packet"),
        (two, "time type", sealed(s2(11, 3)), fresh, TimeType { kind: 3 }, "timestamp type 3"),
        (two, "time_interval", s2_16(3, 0), fresh, PointInterval, "time_interval"),
        (two, "timestamp", s2(28, 0x77), fresh, Checksum, "CRC"),
    ];
    for (model, name, bytes, after, want, names) in &rows {
        let row = format!("{model:?} {name} (after a good packet: {after})");
        assert_eq!(refusal(*model, *after, bytes), Err(*want), "{row}");
        let text = want.to_string();
        assert!(
            text.contains(names),
            "{row}: \"{text}\" does not name {names}"
        );
    }
}
