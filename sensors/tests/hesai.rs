//! The PandarXT-32 decoder on synthetic packets: geometry, times, dual returns, sweeps, and
//! how lost, late, foreign and malformed packets are counted.

use kiss_odom_sensors::hesai::{self, point_offset_ns, wire::field, Calibration};
mod common;

use common::{feed, with, Log};
use kiss_odom_sensors::{Decode, PacketError, Pushed, Return, SweepEnd};

/// 2024-09-17 15:47:12 UTC, the shared recording's date, in ns since the epoch.
const DATE_NS: u64 = (19_983 * 86_400 + 15 * 3600 + 47 * 60 + 12) * 1_000_000_000;

struct Spec {
    /// Azimuth of the first firing and the step from firing to firing, 0.01 degree.
    azimuth: u16,
    step: u16,
    /// Microseconds within the second.
    us: u32,
    mode: u8,
    sequence: Option<u32>,
}

impl Spec {
    fn new(azimuth: u16, us: u32) -> Self {
        Self {
            azimuth,
            step: 18,
            us,
            mode: 0x37,
            sequence: None,
        }
    }
}

/// A packet whose every channel `c` of firing `f` returns `(100 + c + f) * 4 mm`, except that
/// channel 5 returns nothing.
fn packet(s: &Spec) -> Vec<u8> {
    let returns: u8 = if matches!(s.mode, 0x39 | 0x3B | 0x3C) {
        2
    } else {
        1
    };
    let len = if s.sequence.is_some() {
        field::LEN_WITH_SEQUENCE
    } else {
        field::LEN
    };
    let mut b = vec![0u8; len];
    b[0..6].copy_from_slice(&[0xEE, 0xFF, 6, 1, 0, 0]);
    b[6..12].copy_from_slice(&[32, 8, 0, 4, returns, u8::from(s.sequence.is_some())]);
    for k in 0..8 {
        let firing = k / usize::from(returns);
        let at = 12 + 130 * k;
        let az = (u32::from(s.azimuth) + u32::from(s.step) * firing as u32) % 36000;
        b[at..at + 2].copy_from_slice(&(az as u16).to_le_bytes());
        for c in 0..32 {
            let ch = at + 2 + 4 * c;
            let mut d = if c == 5 {
                0
            } else {
                100 + c as u16 + firing as u16
            };
            // In dual mode the second block of a pair differs on even channels only.
            if returns == 2 && k % 2 == 1 && c % 2 == 0 && d != 0 {
                d += 1000;
            }
            b[ch..ch + 2].copy_from_slice(&d.to_le_bytes());
            b[ch + 2] = c as u8;
        }
    }
    b[field::RETURN_MODE] = s.mode;
    b[field::MOTOR_SPEED].copy_from_slice(&600u16.to_le_bytes());
    b[field::DATE_TIME].copy_from_slice(&[124, 9, 17, 15, 47, 12]);
    b[field::MICROSECONDS].copy_from_slice(&s.us.to_le_bytes());
    b[field::MICROSECONDS.end] = 0x42;
    if let Some(q) = s.sequence {
        b[field::UDP_SEQUENCE].copy_from_slice(&q.to_le_bytes());
    }
    b
}

fn decoder() -> hesai::Decoder {
    hesai::Decoder::new(hesai::Config::default()).unwrap()
}

#[test]
fn a_single_return_packet_gives_each_return_its_place_and_time() {
    let mut dec = decoder();
    let mut log = Log::default();
    // Block azimuths 90.00, 90.18, ... degrees.
    assert_eq!(
        feed(&mut dec, &packet(&Spec::new(9000, 500_000)), &mut log),
        Ok(Pushed::Decoded)
    );
    dec.finish(&mut log);
    assert_eq!(log.ends.len(), 1);
    assert_eq!(log.ends[0].points, 8 * 31, "channel 5 returned nothing");
    assert_eq!(log.ends[0].end, SweepEnd::Finished);
    // The sweep begins at the packet's first firing: 350 us before the stamped last one,
    // plus the 5.632 + 0.368 us to channel 0.
    let t0 = DATE_NS + 500_000_000;
    assert_eq!(log.starts[0].start_ns, t0 - 344_000);
    let nominal = Calibration::nominal();
    for &(_, p, t, m) in &log.points {
        let (firing, c) = (usize::from(m.column), usize::from(m.ring));
        assert_eq!(m.ret, Return::Strongest);
        assert_eq!(m.intensity, c as u16);
        let d = (100 + c + firing) as f64 * 0.004;
        let e = nominal.elevation_deg[c].to_radians();
        let az = (90.0 + 0.18 * firing as f64).to_radians();
        let want = [d * e.cos() * az.cos(), -d * e.cos() * az.sin(), d * e.sin()];
        for k in 0..3 {
            assert!((p[k] - want[k]).abs() < 1e-12, "{p:?} vs {want:?}");
        }
        let offset = point_offset_ns(firing, c, 1);
        let want_t = (t0 as i64 + offset - log.starts[0].start_ns as i64) as f64 * 1e-9;
        assert_eq!(t, want_t);
    }
    // Azimuth 90 degrees (clockwise from x, seen from above) is to the right: -y.
    assert!(log.points[0].1[1] < 0.0 && log.points[0].1[0].abs() < 1e-12);
}

#[test]
fn dual_returns_pair_their_blocks_and_one_echo_is_one_point() {
    // Which return each block of the XT32's pair holds (`ReturnMode::from_byte`).
    for (mode, first, second) in [
        (0x39, Return::Strongest, Return::Last),
        (0x3B, Return::Last, Return::First),
        (0x3C, Return::First, Return::Strongest),
    ] {
        let mut dec = decoder();
        let mut log = Log::default();
        let spec = Spec {
            mode,
            ..Spec::new(100, 0)
        };
        feed(&mut dec, &packet(&spec), &mut log).unwrap();
        dec.finish(&mut log);
        // Four firings; 31 channels return (not channel 5): the 16 even ones twice, the 15
        // odd ones once.
        let even = (0..32).filter(|c| c % 2 == 0).count();
        let odd = 31 - even;
        assert_eq!(log.points.len(), 4 * (2 * even + odd), "mode {mode:#x}");
        for &(_, p, _, m) in &log.points {
            let d = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            let c = usize::from(m.ring);
            let want = match m.ret {
                r if r == first => 100 + c + usize::from(m.column),
                r if r == second => 1100 + c + usize::from(m.column),
                Return::Both => 100 + c + usize::from(m.column),
                r => panic!("{r:?} in mode {mode:#x}"),
            };
            assert!((d - want as f64 * 0.004).abs() < 1e-12);
            assert_eq!(m.ret == Return::Both, c % 2 == 1, "{m:?}");
        }
        assert_eq!(dec.return_mode().map(|m| m.returns()), Some(2));
    }
}

/// Packets of a 10 Hz single-return sweep: 400 us and 8 firings of 0.18 degree apart.
fn sweep_packets(from_az: u16, from_us: u32, n: u32, sequence: Option<u32>) -> Vec<Vec<u8>> {
    (0..n)
        .map(|i| {
            let az = (u32::from(from_az) + 144 * i) % 36000;
            packet(&Spec {
                sequence: sequence.map(|s| s + i),
                ..Spec::new(az as u16, from_us + 400 * i)
            })
        })
        .collect()
}

#[test]
fn sweeps_end_where_the_azimuth_wraps_and_losses_are_counted() {
    for sequence in [Some(7), None] {
        let mut dec = decoder();
        let mut log = Log::default();
        let packets = sweep_packets(0, 0, 500, sequence);
        let mut ended = Vec::new();
        for (i, p) in packets.iter().enumerate() {
            // Lose packets 30..33.
            if (30..33).contains(&i) {
                continue;
            }
            if feed(&mut dec, p, &mut log) == Ok(Pushed::Ended) {
                ended.push(i);
            }
        }
        dec.finish(&mut log);
        // 250 packets a turn: the first sweep ends with the packet that wraps past 0.
        assert_eq!(ended, [250], "{sequence:?}");
        assert_eq!(log.ends.len(), 2);
        assert_eq!(log.ends[0].lost_packets, 3, "{sequence:?}");
        assert_eq!(log.ends[0].packets, 248);
        assert_eq!(log.ends[1].lost_packets, 0);
        assert_eq!(log.ends[1].end, SweepEnd::Finished);
    }
}

#[test]
fn a_cut_angle_ends_sweeps_there() {
    let config = hesai::Config {
        cut_angle_deg: Some(180.0),
        ..hesai::Config::default()
    };
    let mut dec = hesai::Decoder::new(config).unwrap();
    let mut log = Log::default();
    let mut ended = Vec::new();
    for (i, p) in sweep_packets(0, 0, 300, None).iter().enumerate() {
        if feed(&mut dec, p, &mut log) == Ok(Pushed::Ended) {
            ended.push(i);
        }
    }
    // Packet 125 reaches 180.00 + 1.26 degrees: the coverage from 180 wraps there.
    assert_eq!(ended.len(), 1);
    let first_az = |i: usize| (144 * i) as f64 * 0.01;
    assert!(
        first_az(ended[0]) <= 180.0 && first_az(ended[0] + 1) > 179.0,
        "{ended:?}"
    );
    assert!(hesai::Decoder::new(hesai::Config {
        cut_angle_deg: Some(360.0),
        ..hesai::Config::default()
    })
    .is_err());
}

#[test]
fn late_foreign_and_damaged_packets_are_refused_and_counted() {
    let mut dec = decoder();
    let mut log = Log::default();
    let good = sweep_packets(0, 0, 3, Some(1));
    feed(&mut dec, &good[1], &mut log).unwrap();
    assert_eq!(feed(&mut dec, &good[0], &mut log), Err(PacketError::Late));
    assert_eq!(
        feed(&mut dec, &good[1], &mut log),
        Err(PacketError::Late),
        "a repeat"
    );
    let other_mode = packet(&Spec {
        mode: 0x38,
        ..Spec::new(0, 900)
    });
    assert_eq!(
        feed(&mut dec, &other_mode, &mut log),
        Err(PacketError::OtherSensor)
    );

    let g = &good[2];
    let cases: [(Vec<u8>, PacketError); 8] = [
        (g[..600].to_vec(), PacketError::Truncated),
        (g[..5].to_vec(), PacketError::Truncated),
        ([g.as_slice(), &[0]].concat(), PacketError::Length),
        (with(g, 0, 0xEF), PacketError::StartBytes),
        (with(g, 2, 4), PacketError::Version),
        (with(g, 6, 16), PacketError::UnknownModel),
        (with(g, 12 + 130 * 3 + 1, 0x8D), PacketError::Azimuth),
        (
            with(g, field::DATE_TIME.start + 2, 31),
            PacketError::Timestamp,
        ),
    ];
    for (bytes, want) in &cases {
        assert_eq!(feed(&mut dec, bytes, &mut log), Err(*want));
    }
    let us = with(g, field::MICROSECONDS.start + 3, 0x10);
    assert_eq!(feed(&mut dec, &us, &mut log), Err(PacketError::Timestamp));
    // Nothing above changed the decoder: the next good packet goes on the sweep.
    assert_eq!(feed(&mut dec, g, &mut log), Ok(Pushed::Decoded));
    dec.finish(&mut log);
    let s = log.ends[0];
    assert_eq!((s.packets, s.out_of_order, s.other_sensor), (2, 2, 1));
    assert_eq!(s.bad_packets, cases.len() as u32 + 1);
    assert_eq!(s.lost_packets, 0);

    // A mode byte unknown, or naming dual returns in a single-return packet, before any
    // packet fixed the mode.
    for mode in [0x3A, 0x39] {
        let mut fresh = decoder();
        let bad = with(g, field::RETURN_MODE, mode);
        assert_eq!(
            feed(&mut fresh, &bad, &mut log),
            Err(PacketError::UnknownReturnMode)
        );
        assert_eq!(fresh.return_mode(), None);
    }
}

#[test]
fn a_pause_ends_the_sweep_and_a_clock_step_back_is_followed() {
    let mut dec = decoder();
    let mut log = Log::default();
    for p in sweep_packets(0, 0, 10, None) {
        feed(&mut dec, &p, &mut log).unwrap();
    }
    // 400 ms later.
    for p in sweep_packets(1440, 400_000, 10, None) {
        feed(&mut dec, &p, &mut log).unwrap();
    }
    // The clock steps back 0.2 s and stays there: after RESYNC_PACKETS late ones, theirs.
    let back = sweep_packets(2880, 200_000, 40, None);
    let refused = back
        .iter()
        .filter(|p| feed(&mut dec, p, &mut log) == Err(PacketError::Late))
        .count();
    dec.finish(&mut log);
    assert_eq!(refused, kiss_odom_sensors::RESYNC_PACKETS as usize - 1);
    let ends: Vec<_> = log.ends.iter().map(|s| s.end).collect();
    assert_eq!(ends, [SweepEnd::Gap, SweepEnd::Resync, SweepEnd::Finished]);
    assert_eq!(log.ends[2].resyncs, 1);
    assert_eq!(log.ends[2].packets, 40 - refused as u32);
}

#[test]
fn a_calibration_moves_each_channel() {
    let mut calibration = Calibration::nominal();
    calibration.elevation_deg[0] = 0.0;
    calibration.azimuth_deg[0] = -90.0 + 45.0;
    let mut dec = hesai::Decoder::new(hesai::Config {
        calibration: Some(calibration),
        ..hesai::Config::default()
    })
    .unwrap();
    let mut log = Log::default();
    feed(&mut dec, &packet(&Spec::new(9000, 0)), &mut log).unwrap();
    dec.finish(&mut log);
    let (_, p, _, _) = log.points[0];
    // Channel 0 of firing 0: 0.4 m level, at 45 degrees: x = -y.
    assert!(
        (p[0] - 0.4 * 45f64.to_radians().cos()).abs() < 1e-12,
        "{p:?}"
    );
    assert!((p[0] + p[1]).abs() < 1e-12 && p[2] == 0.0, "{p:?}");
    let mut bad = Calibration::nominal();
    bad.elevation_deg[1] = f64::INFINITY;
    assert!(hesai::Decoder::new(hesai::Config {
        calibration: Some(bad),
        ..hesai::Config::default()
    })
    .is_err());
}
