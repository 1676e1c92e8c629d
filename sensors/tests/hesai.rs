//! The PandarXT-32 decoder on synthetic packets: geometry, times, dual returns, sweeps, and
//! how lost, late, foreign and malformed packets are counted.

use kiss_odom_sensors::hesai::{self, point_offset_ns, wire::field, Calibration};
mod common;
#[path = "common/hesai_xt32.rs"]
mod xt32;

use common::{feed, with, Log};
use kiss_odom_sensors::{Decode, PacketError, Pushed, Return, SweepEnd};
use xt32::{decoder, packet, Spec};

/// 2024-09-17 15:47:12 UTC, the shared recording's date, in ns since the epoch.
const DATE_NS: u64 = (19_983 * 86_400 + 15 * 3600 + 47 * 60 + 12) * 1_000_000_000;

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
        (with(g, 6, 16), PacketError::Header),
        (with(g, 12 + 130 * 3 + 1, 0x8D), PacketError::Azimuth),
        (
            with(g, field::DATE_TIME.start + 2, 31),
            PacketError::DateTime,
        ),
    ];
    for (bytes, want) in &cases {
        assert_eq!(feed(&mut dec, bytes, &mut log), Err(*want));
    }
    let us = with(g, field::MICROSECONDS.start + 3, 0x10);
    assert_eq!(feed(&mut dec, &us, &mut log), Err(PacketError::DateTime));
    // Nothing above changed the decoder: the next good packet goes on the sweep.
    assert_eq!(feed(&mut dec, g, &mut log), Ok(Pushed::Decoded));
    dec.finish(&mut log);
    let s = log.ends[0];
    assert_eq!((s.packets, s.out_of_order, s.other_sensor), (2, 2, 1));
    assert_eq!(s.bad_packets, cases.len() as u32 + 1);
    assert_eq!(s.lost_packets, 0);

    // A mode byte unknown, or naming dual returns in a single-return packet, before any
    // packet fixed the mode: refused naming the byte, or the header's count against it.
    for (mode, want) in [
        (0x3A, PacketError::UnknownReturnMode),
        (
            0x39,
            PacketError::ReturnCount {
                count: 1,
                mode: 0x39,
            },
        ),
    ] {
        let mut fresh = decoder();
        let bad = with(g, field::RETURN_MODE, mode);
        assert_eq!(feed(&mut fresh, &bad, &mut log), Err(want));
        assert_eq!(fresh.return_mode(), None);
    }
}

#[test]
fn a_pause_ends_the_sweep_once_its_packets_agree_and_a_clock_step_back_is_followed() {
    let mut dec = decoder();
    let mut log = Log::default();
    for p in sweep_packets(0, 0, 10, None) {
        feed(&mut dec, &p, &mut log).unwrap();
    }
    // 400 ms later: held out as a stray's time until RESYNC_PACKETS in a row agree, then the
    // sweep ends at the pause.
    let run = kiss_odom_sensors::RESYNC_PACKETS as usize;
    let ahead = sweep_packets(1440, 400_000, 20, None)
        .iter()
        .filter(|p| feed(&mut dec, p, &mut log) == Err(PacketError::Ahead))
        .count();
    assert_eq!(ahead, run - 1);
    // The clock steps back 0.2 s and stays there: after RESYNC_PACKETS late ones, theirs.
    let back = sweep_packets(2880, 200_000, 40, None);
    let refused = back
        .iter()
        .filter(|p| feed(&mut dec, p, &mut log) == Err(PacketError::Late))
        .count();
    dec.finish(&mut log);
    assert_eq!(refused, run - 1);
    let ends: Vec<_> = log.ends.iter().map(|s| s.end).collect();
    assert_eq!(ends, [SweepEnd::Gap, SweepEnd::Resync, SweepEnd::Finished]);
    assert_eq!(log.ends[0].packets, 10);
    assert_eq!(log.ends[1].packets, 20 - ahead as u32);
    assert_eq!(log.ends[1].out_of_order, ahead as u32);
    assert_eq!(log.ends[2].resyncs, 1);
    assert_eq!(log.ends[2].packets, 40 - refused as u32);
}

#[test]
fn a_stray_packets_time_is_refused_and_counted_not_made_a_sweep() {
    // One packet 10 s ahead, one far behind (a time that wrapped), amid a sweep: each
    // refused with what was wrong with it; the sweep goes on and no loss is invented.
    for (stray_us, want) in [
        (10_000_000 + 400 * 40, PacketError::Ahead),
        (0, PacketError::Late),
    ] {
        let mut dec = decoder();
        let mut log = Log::default();
        let mut packets = sweep_packets(0, 400_000, 300, Some(100));
        // The stray keeps its place in the sequence; only its time is wrong.
        let mut stray = sweep_packets(40 * 144, 0, 1, Some(140)).remove(0);
        let date = field::DATE_TIME.start;
        let secs = stray_us / 1_000_000;
        stray[date + 5] = 12 + secs as u8;
        stray[field::MICROSECONDS].copy_from_slice(&((stray_us % 1_000_000) as u32).to_le_bytes());
        packets[40] = stray.clone();
        let mut refused = Vec::new();
        for p in &packets {
            if let Err(e) = feed(&mut dec, p, &mut log) {
                refused.push(e);
            }
        }
        dec.finish(&mut log);
        assert_eq!(refused, [want], "{stray_us}");
        // The first sweep is the turn of 250 packets, the stray refused in it.
        assert_eq!(log.ends[0].end, SweepEnd::Complete);
        assert_eq!(log.ends[0].packets, 250);
        assert_eq!(log.ends[0].out_of_order, 1);
        assert_eq!(
            log.ends[0].lost_packets, 1,
            "the stray's place in the sequence"
        );
        assert!(log.ends.iter().all(|s| s.end != SweepEnd::Resync));
        // Past it, the times and sequence go on: nothing lost, nothing refused.
        assert_eq!((log.ends[1].lost_packets, log.ends[1].out_of_order), (0, 0));
    }
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
