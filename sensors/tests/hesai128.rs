//! The PandarQT128 (protocol 3.2) and Pandar128/OT128 (protocol 1.4) decoding on synthetic
//! packets: layouts from the header flags, geometry from the calibration, per-point times,
//! dual returns, sweeps, and the bad packets each refuses.

use kiss_odom_sensors::hesai::{self, Calibration, Firing, Model};
mod common;
#[path = "common/hesai_wide.rs"]
mod wide;

use common::{feed, with, Log};
use kiss_odom_sensors::{ConfigError, Decode, PacketError, Pushed, Return};
use wide::{calibration, decoder, packet, seal, step, tail_at, Spec};

/// 2024-10-30 07:36:29 UTC in ns since the epoch.
const DATE_NS: u64 = (20_026 * 86_400 + 7 * 3600 + 36 * 60 + 29) * 1_000_000_000;

#[test]
fn every_return_takes_its_channels_angles_and_firing_time() {
    for (model, spec) in [
        (Model::Qt128, Spec::qt(9000, 250_000)),
        (Model::Pandar128, Spec::p128(9000, 250_000)),
        (Model::Ot128, Spec::p128(9000, 250_000)),
    ] {
        let mut dec = decoder(model);
        let mut log = Log::default();
        let bytes = packet(&spec);
        assert_eq!(feed(&mut dec, &bytes, &mut log), Ok(Pushed::Decoded));
        dec.finish(&mut log);
        // Two firings of 127 returns (channel 9 has none).
        assert_eq!(log.points.len(), 2 * 127, "{model:?}");
        let cal = calibration();
        let t0 = (DATE_NS + 250_000_000) as i64;
        let start = log.starts[0].start_ns as i64;
        let (mut times, mut nears) = (Vec::new(), 0);
        for &(_, p, t, m) in &log.points {
            let (k, c) = (usize::from(m.column), usize::from(m.ring));
            let raw = if c % 2 == 0 {
                200 + c + 1000 * k
            } else {
                200 + c
            };
            let d = raw as f64 * 0.004;
            let e = cal.elevation_deg[c].to_radians();
            let az =
                (90.0 + 0.01 * (step(&spec) as usize * k) as f64 + cal.azimuth_deg[c]).to_radians();
            let want = [d * e.cos() * az.cos(), -d * e.cos() * az.sin(), d * e.sin()];
            for i in 0..3 {
                assert!(
                    (p[i] - want[i]).abs() < 1e-12,
                    "{model:?} {p:?} vs {want:?}"
                );
            }
            assert_eq!(m.ret, Return::Strongest);
            assert_eq!(m.intensity, c as u16);
            let state = Firing {
                returns: 1,
                mode_flag: spec.mode_flag,
                operational_state: spec.operational_state,
                azimuth_state: (spec.azimuth_states >> (14 - 2 * k) & 3) as u8,
                near: d < 2.85,
            };
            nears += usize::from(state.near);
            let want_ns = t0 + model.point_offset_ns(k, c, &state) - start;
            assert_eq!(t, want_ns as f64 * 1e-9, "{model:?} block {k} channel {c}");
            times.push(want_ns);
        }
        // Returns on both sides of the Pandar128's near-field limit (0.8 m to 4.8 m).
        assert!(nears > 0 && nears < times.len(), "{model:?}: {nears} near");
        // The sweep begins at the first firing's start: no point before it, the first soon
        // after.
        let first = times.iter().min().copied().unwrap_or(-1);
        assert!((0..3_000).contains(&first), "{model:?}: {first} ns");
    }
}

#[test]
fn dual_returns_pair_the_two_blocks_in_the_models_order() {
    for (model, spec, first, second) in [
        (Model::Qt128, Spec::qt(100, 0), Return::Last, Return::First),
        (
            Model::Ot128,
            Spec::p128(100, 0),
            Return::Last,
            Return::First,
        ),
    ] {
        let mut dec = decoder(model);
        let mut log = Log::default();
        let dual = Spec { mode: 0x3B, ..spec };
        feed(&mut dec, &packet(&dual), &mut log).unwrap();
        dec.finish(&mut log);
        // One firing: the 64 even channels twice, the 63 odd ones but channel 9 once.
        assert_eq!(log.points.len(), 2 * 64 + 63, "{model:?}");
        for &(_, p, _, m) in &log.points {
            let c = usize::from(m.ring);
            let d = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            let raw = match m.ret {
                Return::Both => 200 + c,
                r if r == first => 200 + c,
                r if r == second => 1200 + c,
                r => panic!("{r:?}"),
            };
            assert!((d - raw as f64 * 0.004).abs() < 1e-12);
            assert_eq!(m.ret == Return::Both, c % 2 == 1);
            assert_eq!(m.column, 0);
        }
    }
}

#[test]
fn sweeps_end_where_the_azimuth_wraps_and_sequence_gaps_are_losses() {
    // QT128 at 10 Hz: 900 packets a turn, 0.4 degrees and 222.22 us apart.
    let mut dec = decoder(Model::Qt128);
    let mut log = Log::default();
    let mut ended = Vec::new();
    for i in 0..1000u32 {
        if (40..43).contains(&i) {
            continue;
        }
        let spec = Spec {
            sequence: 100 + i,
            ..Spec::qt(((200 + 80 * i) % 36000) as u16, 222 * i)
        };
        if feed(&mut dec, &packet(&spec), &mut log) == Ok(Pushed::Ended) {
            ended.push(i);
        }
    }
    dec.finish(&mut log);
    // The packet whose last block is a full turn from the first's (80 i >= 36000) ends it.
    assert_eq!(ended, [450, 900]);
    assert_eq!(log.ends[0].lost_packets, 3);
    assert_eq!(log.ends[0].packets, 448);
    assert_eq!((log.ends[1].packets, log.ends[1].lost_packets), (450, 0));
}

#[test]
fn bad_packets_are_refused_with_their_reason() {
    let qt = packet(&Spec::qt(100, 0));
    let p128 = packet(&Spec::p128(100, 0));
    let mut dec = decoder(Model::Qt128);
    let mut log = Log::default();
    let mut refused = |bytes: &[u8]| feed(&mut dec, bytes, &mut log).unwrap_err();
    assert_eq!(refused(&qt[..qt.len() - 1]), PacketError::Truncated);
    assert_eq!(refused(&qt[..8]), PacketError::Truncated);
    assert_eq!(
        refused(&[qt.clone(), vec![0]].concat()),
        PacketError::Length
    );
    assert_eq!(refused(&with(&qt, 0, 0xEF)), PacketError::StartBytes);
    assert_eq!(refused(&with(&qt, 3, 3)), PacketError::Version);
    // A 1.4 packet to the QT128: the other protocol.
    assert_eq!(refused(&p128), PacketError::Version);
    // 64 lasers, or a distance unit not 4 mm.
    assert_eq!(refused(&with(&qt, 6, 64)), PacketError::Header);
    assert_eq!(refused(&with(&qt, 9, 2)), PacketError::Header);
    // A flag that changes the layout (no signature): the packet's length is what other flags
    // announce, so the flags are named.
    assert_eq!(
        refused(&with(&qt, 11, 0x15)),
        PacketError::HeaderFlags {
            flags: 0x15,
            announced: 1095,
            len: 1127
        }
    );
    assert_eq!(
        refused(&seal(&mut with(&qt, 10, 3))),
        PacketError::ReturnCount {
            count: 3,
            mode: 0x37
        }
    );
    // A distance or a tail byte changed on the way: the body's or the tail's CRC fails.
    assert_eq!(refused(&with(&qt, 14, 0x77)), PacketError::Checksum);
    let t = tail_at(&Spec::qt(0, 0));
    assert_eq!(refused(&with(&qt, t + 22, 0x77)), PacketError::Checksum);
    // With the CRCs sealed again, what the bytes say is checked.
    assert_eq!(
        refused(&seal(&mut with(&qt, 13, 0x8D))),
        PacketError::Azimuth
    );
    assert_eq!(
        refused(&seal(&mut with(&qt, t + 16, 13))),
        PacketError::DateTime
    );
    assert_eq!(
        refused(&seal(&mut with(&qt, t + 12, 0x3A))),
        PacketError::UnknownReturnMode
    );
    // Nothing refused was decoded; the good packet still is, and one whose signature differs.
    assert!(log.points.is_empty());
    assert_eq!(feed(&mut dec, &qt, &mut log), Ok(Pushed::Decoded));
    let later = packet(&Spec {
        sequence: 1,
        ..Spec::qt(140, 300)
    });
    let n = later.len();
    assert_eq!(
        feed(&mut dec, &with(&later, n - 1, 0x77), &mut log),
        Ok(Pushed::Decoded)
    );
    // Another return mode from now on: another sensor on the port.
    let other = seal(&mut with(&packet(&Spec::qt(180, 600)), t + 12, 0x38));
    assert_eq!(
        feed(&mut dec, &other, &mut log),
        Err(PacketError::OtherSensor)
    );
}

#[test]
fn the_wide_models_need_a_calibration_of_their_channels() {
    let config = |model, calibration| hesai::Config {
        model,
        calibration,
        ..hesai::Config::default()
    };
    for model in [Model::Qt128, Model::Pandar128, Model::Ot128] {
        assert!(matches!(
            hesai::Decoder::new(config(model, None)),
            Err(ConfigError::Calibration)
        ));
        assert!(matches!(
            hesai::Decoder::new(config(model, Some(Calibration::nominal()))),
            Err(ConfigError::Calibration)
        ));
    }
    assert!(matches!(
        hesai::Decoder::new(config(Model::Xt32, Some(calibration()))),
        Err(ConfigError::Calibration)
    ));
    assert!(hesai::Decoder::new(config(Model::Xt32, None)).is_ok());
}

#[test]
fn protocol_1_4_packets_whose_crcs_do_not_match_are_refused_as_the_qt128s_are() {
    for model in [Model::Ot128, Model::Pandar128] {
        let p128 = packet(&Spec::p128(100, 0));
        let t = tail_at(&Spec::p128(0, 0));
        let mut dec = decoder(model);
        let mut log = Log::default();
        // A distance, a tail byte (the return mode), the sequence number changed on the way.
        for at in [14, t + 12, t + 26] {
            assert_eq!(
                feed(&mut dec, &with(&p128, at, p128[at] ^ 0x40), &mut log),
                Err(PacketError::Checksum),
                "{model:?} byte {at}"
            );
        }
        // The functional safety part and the signature have CRCs of their own (not checked).
        assert_eq!(feed(&mut dec, &p128, &mut log), Ok(Pushed::Decoded));
        assert!(log.points.iter().all(|p| p.0 == 0));
        dec.finish(&mut log);
        assert_eq!(log.ends[0].bad_packets, 3, "{model:?}");
    }
}

#[test]
fn fields_that_contradict_each_other_are_refused_naming_both() {
    let t = tail_at(&Spec::p128(0, 0));
    let mut dec = decoder(Model::Ot128);
    let mut log = Log::default();
    let mut refused = |bytes: Vec<u8>| feed(&mut dec, &bytes, &mut log).unwrap_err();
    // Operational states the OT128's firing-time file does not list: shutdown, energy saving,
    // none; standard with azimuth state 2.
    for state in [1, 3, 7] {
        let p = Spec {
            operational_state: state,
            ..Spec::p128(100, 0)
        };
        assert_eq!(
            refused(packet(&p)),
            PacketError::FiringState {
                operational: state,
                azimuth: 0
            }
        );
    }
    let p = Spec {
        azimuth_states: 0b10 << 14,
        ..Spec::p128(100, 0)
    };
    assert_eq!(
        refused(packet(&p)),
        PacketError::FiringState {
            operational: 2,
            azimuth: 2
        }
    );
    // High resolution fires every 0.1 degree at 600 rpm: blocks 0.2 degree apart are
    // standard-state packets that say high resolution.
    let p = Spec {
        operational_state: 0,
        ..Spec::p128(100, 0)
    };
    let mut b = packet(&p);
    b[12 + 2 + 128 * 3..][..2].copy_from_slice(&120u16.to_le_bytes());
    assert_eq!(
        refused(seal(&mut b)),
        PacketError::FiringStep {
            step: 20,
            expected: 10
        }
    );
    // The rotor does not turn: both firings at one azimuth.
    let mut b = packet(&Spec::p128(100, 0));
    b[12 + 2 + 128 * 3..][..2].copy_from_slice(&100u16.to_le_bytes());
    assert_eq!(
        refused(seal(&mut b)),
        PacketError::FiringStep {
            step: 0,
            expected: 20
        }
    );
    // A dual-return mode byte over single-return data (two firings, two azimuths), and
    // the header's count against the mode byte.
    let mut b = packet(&Spec::p128(100, 0));
    b[10] = 2;
    b[t + 12] = 0x39;
    assert_eq!(
        refused(seal(&mut b)),
        PacketError::DualPair {
            first: 100,
            second: 120
        }
    );
    let mut b = packet(&Spec::p128(100, 0));
    b[t + 12] = 0x39;
    assert_eq!(
        refused(seal(&mut b)),
        PacketError::ReturnCount {
            count: 1,
            mode: 0x39
        }
    );
    // A QT128 packet relabelled protocol 1.4: its layout reads the same, its CRCs hold, but
    // its firings are 0.4 degree apart where the 1.4 states it reads give 0.1.
    let mut qt = packet(&Spec {
        flags: 0x15,
        ..Spec::qt(100, 0)
    });
    qt[2..4].copy_from_slice(&[1, 4]);
    let e = refused(qt);
    assert!(
        matches!(e, PacketError::FiringStep { step: 40, .. }),
        "{e:?}"
    );
    assert!(e.to_string().contains("40 apart"), "{e}");
    // None of them was decoded; a packet that agrees with itself is.
    assert!(log.points.is_empty());
    assert_eq!(
        feed(&mut dec, &packet(&Spec::p128(100, 0)), &mut log),
        Ok(Pushed::Decoded)
    );
}
