//! The Livox SDK 1 decoder on synthetic packets: every data type's geometry, per-point times,
//! frames by time, and how lost, late, foreign and malformed packets are counted.

use kiss_odom_sensors::livox::{self, sdk1, Model};
mod common;
#[path = "common/livox_sdk1.rs"]
mod sdk1_packets;

use common::{feed, with, Log};
use kiss_odom_sensors::{ConfigError, Decode, PacketError, Pushed, Return, SweepEnd};
use sdk1_packets::packet;

const T0: u64 = 1_726_588_075_299_964_555;

fn decoder() -> livox::Decoder {
    livox::Decoder::new(livox::Config::default()).unwrap()
}

#[test]
fn every_data_type_gives_the_same_points_at_their_firing_times() {
    for data_type in 0..6u8 {
        let mut dec = decoder();
        let mut log = Log::default();
        feed(&mut dec, &packet(data_type, T0), &mut log).unwrap();
        dec.finish(&mut log);
        let (_, n) = sdk1::layout(data_type).unwrap();
        let dual = matches!(data_type, 4 | 5);
        assert_eq!(
            log.points.len(),
            (n - 1) * if dual { 2 } else { 1 },
            "type {data_type}"
        );
        assert_eq!(log.starts[0].start_ns, T0);
        // Spherical types carry 0.01 degree angles: up to 1e-4 rad of a 100 m point.
        let tol = if matches!(data_type, 1 | 3 | 5) {
            2e-2
        } else {
            1e-12
        };
        for &(_, p, t, m) in &log.points {
            let k = usize::from(m.column);
            let s = if m.ret == Return::Second { 2.0 } else { 1.0 };
            let want = [(1.0 + k as f64) * s, 2.0 * s, -0.5 * s];
            for i in 0..3 {
                assert!(
                    (p[i] - want[i]).abs() < tol,
                    "type {data_type}: {p:?} vs {want:?}"
                );
            }
            assert_eq!(t, k as f64 * (1e9 / 240_000.0) * 1e-9);
            assert_eq!(m.intensity, k as u16);
            assert_eq!(m.ring, if data_type < 2 { 0 } else { 16 }, "the tag");
            assert!(m.ret == Return::First || (dual && m.ret == Return::Second));
        }
    }
}

#[test]
fn frames_are_cut_by_time_and_losses_counted_from_the_packet_times() {
    let mut dec = livox::Decoder::new(livox::Config {
        model: Model::Horizon,
        frame_period_ns: 10_000_000,
    })
    .unwrap();
    let mut log = Log::default();
    let mut ended_at = Vec::new();
    // 96 firings of 4.1667 us: 400 us a packet; 60 packets = 24 ms; lose packets 10..13.
    for i in 0..60u64 {
        if (10..13).contains(&i) {
            continue;
        }
        let before = log.ends.len();
        feed(&mut dec, &packet(2, T0 + 400_000 * i), &mut log).unwrap();
        if log.ends.len() > before {
            ended_at.push(i);
        }
    }
    dec.finish(&mut log);
    // Frames start at T0, T0 + 10 ms, T0 + 20 ms: packets 25 and 50 begin the next ones.
    assert_eq!(ended_at, [25, 50]);
    let starts: Vec<u64> = log.starts.iter().map(|s| s.start_ns).collect();
    assert_eq!(starts, [T0, T0 + 10_000_000, T0 + 20_000_000]);
    let lost: Vec<u32> = log.ends.iter().map(|s| s.lost_packets).collect();
    assert_eq!(lost, [3, 0, 0]);
    assert_eq!(log.ends[2].end, SweepEnd::Finished);
    // A frame's times start at its start.
    let first_of_second = log.points.iter().find(|p| p.0 == 1).unwrap();
    assert_eq!(first_of_second.2, 0.0);
    // A pause of more than 0.3 s: its first packets are held out as a stray's time until
    // RESYNC_PACKETS in a row agree; then the frame ends and the next starts at the packet,
    // and the pause is not counted as losses.
    let mut dec = decoder();
    let mut log = Log::default();
    feed(&mut dec, &packet(2, T0), &mut log).unwrap();
    let after = |i: u64| packet(2, T0 + 400_000_000 + 400_000 * i);
    let run = u64::from(kiss_odom_sensors::RESYNC_PACKETS);
    for i in 0..run - 1 {
        assert_eq!(feed(&mut dec, &after(i), &mut log), Err(PacketError::Ahead));
    }
    feed(&mut dec, &after(run - 1), &mut log).unwrap();
    assert_eq!(log.ends[0].end, SweepEnd::Gap);
    assert_eq!(log.ends[0].out_of_order, run as u32 - 1);
    assert_eq!(
        log.starts[1].start_ns,
        T0 + 400_000_000 + 400_000 * (run - 1)
    );
    dec.finish(&mut log);
    assert_eq!(log.ends[1].lost_packets, 0);
    assert_eq!(
        livox::Decoder::new(livox::Config {
            frame_period_ns: 0,
            ..livox::Config::default()
        })
        .err(),
        Some(ConfigError::FramePeriod)
    );
}

#[test]
fn the_mid_40_fires_every_10_us() {
    let mut dec = livox::Decoder::new(livox::Config {
        model: Model::Mid40,
        ..livox::Config::default()
    })
    .unwrap();
    let mut log = Log::default();
    feed(&mut dec, &packet(0, T0), &mut log).unwrap();
    dec.finish(&mut log);
    let last = log.points.last().unwrap();
    assert_eq!(last.2, 99.0 * 10_000.0 * 1e-9);
}

#[test]
fn gps_time_is_a_utc_date_and_microseconds_in_the_hour() {
    let mut b = packet(2, 0);
    b[8] = 3;
    // 2024-09-17 15h, 47 min 55.2999 s into the hour.
    b[10..14].copy_from_slice(&[24, 9, 17, 15]);
    b[14..18].copy_from_slice(&2_875_299_964u32.to_le_bytes());
    let p = livox::sdk1::Packet::new_checked(&b).unwrap();
    assert_eq!(p.time_ns(), Some(T0 - 555));
    b[12] = 31;
    assert_eq!(
        livox::sdk1::Packet::new_checked(&b).err(),
        Some(PacketError::DateTime)
    );
    // A timestamp type the protocol does not define.
    assert_eq!(
        livox::sdk1::Packet::new_checked(&with(&packet(2, 0), 8, 7)).err(),
        Some(PacketError::TimeType { kind: 7 })
    );
}

#[test]
fn imu_late_foreign_and_damaged_packets_are_refused_and_counted() {
    let mut dec = decoder();
    let mut log = Log::default();
    let g = packet(2, T0 + 400_000);
    feed(&mut dec, &g, &mut log).unwrap();
    assert_eq!(
        feed(&mut dec, &packet(2, T0), &mut log),
        Err(PacketError::Late)
    );
    let mut other = packet(2, T0 + 800_000);
    other[2] = 2;
    assert_eq!(
        feed(&mut dec, &other, &mut log),
        Err(PacketError::OtherSensor)
    );
    assert_eq!(
        feed(&mut dec, &packet(0, T0 + 800_000), &mut log),
        Err(PacketError::OtherSensor)
    );
    let mut imu = packet(6, T0 + 800_000);
    imu[18..22].copy_from_slice(&0.5f32.to_le_bytes());
    imu[38..42].copy_from_slice(&(-1.0f32).to_le_bytes());
    let sample = livox::sdk1::Packet::new_checked(&imu)
        .unwrap()
        .imu()
        .unwrap();
    assert_eq!((sample.gyro[0], sample.accel_g[2]), (0.5, -1.0));
    assert_eq!(feed(&mut dec, &imu, &mut log), Err(PacketError::PacketType));
    let cases: [(Vec<u8>, PacketError); 5] = [
        (g[..1000].to_vec(), PacketError::Truncated),
        (g[..10].to_vec(), PacketError::Truncated),
        ([g.as_slice(), &[0]].concat(), PacketError::Length),
        (with(&g, 0, 1), PacketError::Version),
        (with(&g, 9, 9), PacketError::PacketType),
    ];
    for (bytes, want) in &cases {
        assert_eq!(feed(&mut dec, bytes, &mut log), Err(*want));
    }
    assert_eq!(
        feed(&mut dec, &packet(2, T0 + 800_000), &mut log),
        Ok(Pushed::Decoded)
    );
    dec.finish(&mut log);
    let s = log.ends[0];
    assert_eq!((s.packets, s.out_of_order, s.other_sensor), (2, 1, 2));
    assert_eq!(s.bad_packets, cases.len() as u32 + 1, "with the IMU packet");
}

#[test]
fn a_clock_step_back_is_followed_after_a_run_of_late_packets() {
    let mut dec = decoder();
    let mut log = Log::default();
    for i in 0..5 {
        feed(&mut dec, &packet(2, T0 + 400_000 * i), &mut log).unwrap();
    }
    let mut refused = 0;
    for i in 0..30 {
        if feed(&mut dec, &packet(2, 1_000 + 400_000 * i), &mut log) == Err(PacketError::Late) {
            refused += 1;
        }
    }
    dec.finish(&mut log);
    assert_eq!(refused, kiss_odom_sensors::RESYNC_PACKETS - 1);
    let ends: Vec<_> = log.ends.iter().map(|s| s.end).collect();
    assert_eq!(ends, [SweepEnd::Resync, SweepEnd::Finished]);
    assert_eq!(log.ends[1].resyncs, 1);
    assert_eq!(log.starts[1].start_ns, 1_000 + 400_000 * u64::from(refused));
}

#[test]
fn a_stray_packets_time_is_refused_and_counted_not_made_a_frame() {
    // 0.4 s of packets, one of them stamped 10 s ahead (or at 2^64 - 1 ns): the frames are
    // the ones without it, the stray counted as out of order, no loss invented.
    for stray in [T0 + 10_000_000_000, u64::MAX] {
        let mut dec = decoder();
        let mut log = Log::default();
        let mut refused = Vec::new();
        for i in 0..1000u64 {
            let t = if i == 400 { stray } else { T0 + 400_000 * i };
            if let Err(e) = feed(&mut dec, &packet(2, t), &mut log) {
                refused.push(e);
            }
        }
        dec.finish(&mut log);
        assert_eq!(refused, [PacketError::Ahead], "{stray}");
        let starts: Vec<u64> = log.starts.iter().map(|s| s.start_ns).collect();
        let want: Vec<u64> = (0..4).map(|k| T0 + 100_000_000 * k).collect();
        assert_eq!(starts, want, "{stray}");
        let lost: u32 = log.ends.iter().map(|s| s.lost_packets).sum();
        let late: u32 = log.ends.iter().map(|s| s.out_of_order).sum();
        // The stray's place: one packet missing from the times.
        assert_eq!((lost, late), (1, 1), "{stray}");
        assert!(log.ends.iter().all(|s| s.end != SweepEnd::Resync));
    }
}
