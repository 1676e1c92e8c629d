//! The Robosense decoder: angles from a DIFOP packet, points where the geometry puts them,
//! and bad input (no angles, a malformed DIFOP, another model's packets, truncated packets,
//! a dual-return packet of another mode) refused with its reason and counted; each field of an MSOP
//! packet corrupted alone is refused naming that field; the RS-Airy's two blocks a firing,
//! firing tables and in-packet return mode.

mod common;

use common::{feed, with, Log};
use kiss_odom_sensors::robosense::{
    wire, AiryInstall, Calibration, Config, Decoder, Model, AIRY_96, AIRY_CHANNEL_MODE,
    AIRY_DATA_TYPE, AIRY_INSTALL, AIRY_RETURN_MODE,
};
use kiss_odom_sensors::{Decode, PacketError, Return};

/// Laser `i`'s elevation in the test's DIFOP packets, hundredths of a degree: rising with `i`
/// (the RS-16's lasers 0-7 below the horizon, as its DIFOP says them).
fn elevation(model: Model, i: usize) -> i32 {
    if model == Model::Rs16 {
        (2 * i as i32 - 15) * 100
    } else {
        (i as i32 - 16) * 50
    }
}

/// A DIFOP packet of `model` with laser `i` at [`elevation`] and no horizontal offset, and
/// the return-mode byte `mode`.
fn difop(model: Model, mode: u8) -> Vec<u8> {
    let mut b = vec![0u8; wire::LEN];
    b[..8].copy_from_slice(&wire::DIFOP_ID);
    b[8..10].copy_from_slice(&600u16.to_be_bytes());
    let at = model.difop();
    b[at.return_mode] = mode;
    for i in 0..model.lasers() {
        let v = elevation(model, i);
        match at.horizontal {
            Some(_) => {
                b[at.vertical + 3 * i] = u8::from(v < 0);
                b[at.vertical + 3 * i + 1..at.vertical + 3 * i + 3]
                    .copy_from_slice(&(v.unsigned_abs() as u16).to_be_bytes());
            }
            None => {
                let w = (v.unsigned_abs() * 100).to_be_bytes();
                b[at.vertical + 3 * i..at.vertical + 3 * i + 3].copy_from_slice(&w[1..]);
            }
        }
    }
    b
}

/// An MSOP packet of `model` at UTC second `s` and microsecond `us`, blocks from azimuth `az`
/// (each firing's blocks `step` apart, `per` blocks a firing), every channel 10 m.
fn msop(model: Model, (s, us): (u64, u32), az: u16, per: usize) -> Vec<u8> {
    let l = model.layout();
    let mut b = vec![0u8; wire::LEN];
    b[..l.id.len()].copy_from_slice(l.id);
    let (at, _) = l.stamp;
    if model.layout().stamp.1 == kiss_odom_sensors::robosense::Stamp::Utc {
        b[at..at + 6].copy_from_slice(&s.to_be_bytes()[2..]);
        b[at + 6..at + 10].copy_from_slice(&us.to_be_bytes());
    } else {
        // 2024-01-01 00:00:00 plus s seconds (s < 60), ms and us.
        b[at..at + 6].copy_from_slice(&[24, 1, 1, 0, 0, s as u8]);
        b[at + 6..at + 8].copy_from_slice(&((us / 1000) as u16).to_be_bytes());
        b[at + 8..at + 10].copy_from_slice(&((us % 1000) as u16).to_be_bytes());
    }
    if model == Model::Airy {
        b[AIRY_CHANNEL_MODE] = AIRY_96;
        b[AIRY_RETURN_MODE] = if per == 4 { 0x03 } else { 0x01 };
    }
    let raw = (10.0 / model.distance_resolution_m()) as u16;
    for k in 0..l.blocks {
        let at = l.header + k * l.block_len();
        b[at..at + l.block_id.len()].copy_from_slice(l.block_id);
        let a = az + 20 * (k / per) as u16;
        b[at + l.azimuth_at..at + l.azimuth_at + 2].copy_from_slice(&a.to_be_bytes());
        for c in 0..l.channels {
            let d = at + l.azimuth_at + 2 + 3 * c;
            b[d..d + 2].copy_from_slice(&raw.to_be_bytes());
            b[d + 2] = 50;
        }
    }
    b
}

/// Block `k` of an MSOP packet of `model` with every channel at `metres`.
fn set_range(p: &mut [u8], model: Model, k: usize, metres: f64) {
    let l = model.layout();
    let raw = (metres / model.distance_resolution_m()) as u16;
    for c in 0..l.channels {
        let at = l.header + k * l.block_len() + l.azimuth_at + 2 + 3 * c;
        p[at..at + 2].copy_from_slice(&raw.to_be_bytes());
    }
}

/// A point's horizontal distance from the sensor axis less the lens centre's offset: its
/// range times the cosine of its laser's elevation.
fn reach(model: Model, p: &[f64; 3], ring: u16) -> f64 {
    let v = (f64::from(elevation(model, usize::from(ring))) * 0.01).to_radians();
    (p[0].hypot(p[1]) - model.lens_m().0) / v.cos()
}

fn decoder(model: Model) -> Decoder {
    Decoder::new(Config {
        model,
        calibration: None,
        cut_angle_deg: None,
    })
    .unwrap()
}

#[test]
fn points_wait_for_the_difop_angles_then_follow_them() {
    for model in Model::ALL {
        let mut dec = decoder(model);
        let mut log = Log::default();
        let single = if model == Model::Ruby {
            0x02
        } else if matches!(model, Model::Helios | Model::Helios16p) {
            0x04
        } else {
            0x01
        };
        let p = msop(model, (1_704_067_200 % 60, 0), 1000, 1);
        assert_eq!(
            feed(&mut dec, &p, &mut log),
            Err(PacketError::NoCalibration)
        );
        assert!(!dec.calibrated());
        assert_eq!(
            feed(&mut dec, &difop(model, single), &mut log),
            Err(PacketError::PacketType)
        );
        assert!(dec.calibrated(), "{model:?}");
        feed(&mut dec, &p, &mut log).unwrap();
        dec.finish(&mut log);
        let l = model.layout();
        assert_eq!(log.points.len(), l.blocks * l.channels, "{model:?}");
        // Every point 10 m from the lens centre at its laser's elevation.
        let (rx, rz) = model.lens_m();
        for (_, p, _, m) in &log.points {
            // Rings count up from the lowest laser: laser order here.
            let v = (f64::from(elevation(model, usize::from(m.ring))) * 0.01).to_radians();
            let z = 10.0 * v.sin() + rz;
            assert!((p[2] - z).abs() < 1e-3, "{model:?} {p:?} ring {}", m.ring);
            let rho = p[0].hypot(p[1]);
            assert!(
                (rho - (10.0 * v.cos() + rx)).abs() < 1e-3,
                "{model:?} {p:?}"
            );
        }
    }
}

#[test]
fn bad_input_is_refused_with_its_reason() {
    let model = Model::Helios;
    let mut dec = decoder(model);
    let mut log = Log::default();
    // A DIFOP whose angle entries are unset (sign 0xFF): no angles.
    let unset = with(&difop(model, 0x04), 468, 0xFF);
    assert_eq!(
        feed(&mut dec, &unset, &mut log),
        Err(PacketError::NoCalibration)
    );
    assert!(!dec.calibrated());
    let _ = feed(&mut dec, &difop(model, 0x04), &mut log);
    let p = msop(model, (1000, 0), 1000, 1);
    assert_eq!(
        feed(&mut dec, &p[..1200], &mut log),
        Err(PacketError::Truncated)
    );
    // An RS-32's packet (the 8-byte id): not this model's.
    let rs32 = msop(Model::Rs32, (10, 0), 1000, 1);
    assert_eq!(
        feed(&mut dec, &rs32, &mut log),
        Err(PacketError::StartBytes)
    );
    // A Ruby's (4-byte id, FE blocks): another Robosense model.
    let ruby = msop(Model::Ruby, (1000, 0), 1000, 1);
    assert_eq!(
        feed(&mut dec, &ruby, &mut log),
        Err(PacketError::OtherSensor)
    );
    let mut late_us = p.clone();
    late_us[26..30].copy_from_slice(&2_000_000u32.to_be_bytes());
    assert_eq!(
        feed(&mut dec, &late_us, &mut log),
        Err(PacketError::DateTime)
    );
    // 2^48 - 1 seconds: more microseconds than a u64 holds.
    let mut far = p.clone();
    far[20..26].fill(0xFF);
    assert_eq!(feed(&mut dec, &far, &mut log), Err(PacketError::DateTime));
    feed(&mut dec, &p, &mut log).unwrap();
    dec.finish(&mut log);
    let s = log.ends.last().unwrap();
    assert_eq!((s.packets, s.bad_packets, s.other_sensor), (1, 6, 1));
}

#[test]
fn dual_return_pairs_give_strongest_and_second() {
    let mut dec = decoder(Model::Rs32);
    let mut log = Log::default();
    let _ = feed(&mut dec, &difop(Model::Rs32, 0x00), &mut log);
    // Each firing's first block (its first return) at 10 m, its second at 20 m.
    let mut p = msop(Model::Rs32, (10, 0), 1000, 2);
    for k in (1..12).step_by(2) {
        set_range(&mut p, Model::Rs32, k, 20.0);
    }
    feed(&mut dec, &p, &mut log).unwrap();
    dec.finish(&mut log);
    assert_eq!(log.points.len(), 12 * 32);
    for (_, p, _, m) in &log.points {
        let want = if m.ret == Return::Strongest {
            10.0
        } else {
            20.0
        };
        assert!((reach(Model::Rs32, p, m.ring) - want).abs() < 1e-6, "{m:?}");
    }
    let strongest = log.points.iter().filter(|p| p.3.ret == Return::Strongest);
    assert_eq!(strongest.count(), 6 * 32);
}

/// A dual-return RS-Ruby packet of firings at `first` and `first + 20` (0.01 degree): AAB
/// (the first firing's two returns, the second's first) or ABB.
fn ruby_dual(us: u32, first: u16, aab: bool) -> Vec<u8> {
    let mut p = msop(Model::Ruby, (1000, us), first, 1);
    let l = Model::Ruby.layout();
    let azimuths = if aab {
        [first, first, first + 20]
    } else {
        [first, first + 20, first + 20]
    };
    for (k, a) in azimuths.iter().enumerate() {
        let at = l.header + k * l.block_len() + l.azimuth_at;
        p[at..at + 2].copy_from_slice(&a.to_be_bytes());
    }
    p
}

#[test]
fn the_rubys_dual_return_packets_pair_blocks_across_packets_as_rs_driver() {
    let model = Model::Ruby;
    for told in [true, false] {
        let mut dec = decoder(model);
        let mut log = Log::default();
        // Told by the DIFOP packet (0x03), or found by the packets' azimuths (an angle file).
        let d = difop(model, if told { 0x03 } else { 0x02 });
        let _ = feed(&mut dec, &d, &mut log);
        if !told {
            dec = Decoder::new(Config {
                model,
                calibration: Some(Calibration {
                    dual: None,
                    ..Calibration::from_difop(model, &wire::Difop::new_checked(&d).unwrap())
                        .unwrap()
                }),
                cut_angle_deg: None,
            })
            .unwrap();
        }
        // Firings F0 F1 | F1 F2 | F3 F4 ...: AAB at t, ABB one firing (55.55 us) later, the
        // next AAB two firings after that.
        let packets = [
            ruby_dual(0, 1000, true),
            ruby_dual(56, 1020, false),
            ruby_dual(167, 1060, true),
        ];
        for p in &packets {
            feed(&mut dec, p, &mut log).unwrap();
        }
        dec.finish(&mut log);
        let s = log.ends.last().unwrap();
        assert_eq!((s.packets, s.lost_packets), (3, 0), "told {told}");
        let n = |ret: Return| log.points.iter().filter(|p| p.3.ret == ret).count();
        // 9 blocks: firings F0-F3 both returns (8 blocks), F4 its first.
        assert_eq!(
            (n(Return::Strongest), n(Return::Second)),
            (5 * 128, 4 * 128)
        );
        // F1's second return (the ABB's A) is F1's column, at F1's azimuth.
        let f1: Vec<_> = log.points.iter().filter(|p| p.3.column == 1).collect();
        assert_eq!(f1.len(), 2 * 128, "told {told}");
        // Columns F0-F4.
        let columns: std::collections::BTreeSet<_> =
            log.points.iter().map(|p| p.3.column).collect();
        assert_eq!(columns.into_iter().collect::<Vec<_>>(), vec![0, 1, 2, 3, 4]);
    }
    // A packet that pairs no blocks under dual return: another return mode's.
    let mut dec = decoder(model);
    let mut log = Log::default();
    let _ = feed(&mut dec, &difop(model, 0x03), &mut log);
    let single = msop(model, (1000, 0), 1000, 1);
    assert_eq!(
        feed(&mut dec, &single, &mut log),
        Err(PacketError::OtherSensor)
    );
}

#[test]
fn an_angle_table_of_another_length_is_refused() {
    let c = Calibration {
        lasers: Default::default(),
        dual: None,
        install: AiryInstall::default(),
    };
    let r = Decoder::new(Config {
        model: Model::Rs16,
        calibration: Some(c),
        cut_angle_deg: None,
    });
    assert!(r.is_err());
}

#[test]
fn each_corrupted_header_field_is_refused_by_its_own_name() {
    use PacketError::*;
    // A decoder of `model` with its DIFOP angles, as it takes the good packet.
    let refusal = |model: Model, bytes: &[u8]| {
        let mut dec = decoder(model);
        let mut log = Log::default();
        let single = match model {
            Model::Ruby => 0x02,
            Model::Helios => 0x04,
            _ => 0x01,
        };
        let _ = feed(&mut dec, &difop(model, single), &mut log);
        assert!(dec.calibrated());
        let per = model.halves();
        assert!(feed(&mut dec, &msop(model, (10, 0), 1000, per), &mut log).is_ok());
        dec.push(bytes, &mut log)
    };
    let (rs32, helios, ruby, airy) = (Model::Rs32, Model::Helios, Model::Ruby, Model::Airy);
    let set = |model: Model, at: usize, v: u8| {
        let per = model.halves();
        with(&msop(model, (11, 0), 1000, per), at, v)
    };
    // Block 2's flag, its azimuth's high byte, and the time stamp's (`Stamp`) fields.
    let block = |model: Model| {
        let l = model.layout();
        l.header + 2 * l.block_len()
    };
    let azimuth = |model: Model| block(model) + model.layout().azimuth_at;
    let stamp = |model: Model| model.layout().stamp.0;
    let ruby_packet = msop(ruby, (11, 0), 1000, 1);
    // (model, field, packet, refusal, what its text names)
    #[rustfmt::skip]
    let rows = vec![
        (rs32, "length", msop(rs32, (11, 0), 1000, 1)[..1200].to_vec(), Truncated, "shorter"),
        (rs32, "id", set(rs32, 3, 0x5A), StartBytes, "start bytes"),
        (rs32, "block 2 flag", set(rs32, block(rs32) + 1, 0x12), BlockFlag, "block flag"),
        (rs32, "azimuth", set(rs32, azimuth(rs32), 0x8D), Azimuth, "azimuth"),
        (rs32, "month", set(rs32, stamp(rs32) + 1, 13), DateTime, "date"),
        (helios, "block 2 flag", set(helios, block(helios), 0x00), BlockFlag, "block flag"),
        (helios, "microseconds", set(helios, stamp(helios) + 7, 0x10), DateTime, "date"),
        (ruby, "block 2 flag", set(ruby, block(ruby), 0xFD), BlockFlag, "block flag"),
        // Another model's blocks (the Ruby's FE) where the Helios has FF EE: its packet.
        (helios, "blocks", ruby_packet, OtherSensor, "another sensor"),
        // The Airy and the Helios share the id and the first block: the later blocks tell.
        (helios, "Airy blocks", msop(airy, (11, 0), 1000, 2), OtherSensor, "another sensor"),
        (airy, "Helios blocks", msop(helios, (11, 0), 1000, 1), OtherSensor, "another sensor"),
        (airy, "block 2 flag", set(airy, block(airy) + 1, 0x12), BlockFlag, "block flag"),
        (airy, "channel mode", set(airy, AIRY_CHANNEL_MODE, 0x01), Header, "laser count"),
        (airy, "data type", set(airy, AIRY_DATA_TYPE, 0x01), PacketType, "not a point data"),
        (airy, "return mode", set(airy, AIRY_RETURN_MODE, 0x03), OtherSensor, "another sensor"),
    ];
    for (model, name, bytes, want, names) in &rows {
        let row = format!("{model:?} {name}");
        assert_eq!(refusal(*model, bytes), Err(*want), "{row}");
        let text = want.to_string();
        assert!(
            text.contains(names),
            "{row}: \"{text}\" does not name {names}"
        );
    }
}

#[test]
fn the_airy_fills_a_firing_from_two_blocks_at_its_install_modes_times() {
    let model = Model::Airy;
    // The DIFOP's install mode picks the table: the first laser of the second group of eight
    // (channel 8) fires 5.712 us into the firing mounted normally, 11.424 on its side and
    // 7.616 as the Airy M (also without a mode: 0xFF); laser 56, block 1's channel 8, is of
    // the eighth group: 50.456, 71.400 and 61.880 us.
    let table = [
        (0u8, 5.712, 50.456),
        (1, 11.424, 71.4),
        (2, 7.616, 61.88),
        (0xFF, 7.616, 61.88),
    ];
    for (install, want_us, want_56) in table {
        let mut dec = decoder(model);
        let mut log = Log::default();
        let _ = feed(
            &mut dec,
            &with(&difop(model, 0), AIRY_INSTALL, install),
            &mut log,
        );
        feed(&mut dec, &msop(model, (10, 0), 1000, 2), &mut log).unwrap();
        dec.finish(&mut log);
        assert_eq!(log.points.len(), 8 * 48);
        // Laser 8 (ring 8: elevations rise with the laser) of the first firing, and laser
        // 56.
        let at = |ring: u16| {
            let p = log
                .points
                .iter()
                .find(|p| p.3.ring == ring && p.3.column == 0);
            p.map(|p| p.2 * 1e6).unwrap()
        };
        let (t0, t8, t56) = (at(0), at(8), at(56));
        assert!(
            (t8 - t0 - want_us).abs() < 1e-6,
            "mode {install}: {}",
            t8 - t0
        );
        assert!(
            (t56 - t0 - want_56).abs() < 1e-6,
            "mode {install}: {}",
            t56 - t0
        );
    }
}

#[test]
fn the_airys_dual_return_packets_give_two_returns_a_firing_and_its_feature_bits_are_not_range() {
    let model = Model::Airy;
    let mut dec = decoder(model);
    let mut log = Log::default();
    let _ = feed(&mut dec, &difop(model, 0), &mut log);
    // Two firings of four blocks: the first return's two (lasers 0-47, 48-95) at 10 m, the
    // second's at 20 m; every distance with its two feature bits set.
    let mut p = msop(model, (10, 0), 1000, 4);
    let l = model.layout();
    for k in [2, 3, 6, 7] {
        set_range(&mut p, model, k, 20.0);
    }
    for k in 0..l.blocks {
        for c in 0..l.channels {
            p[l.header + k * l.block_len() + l.azimuth_at + 2 + 3 * c] |= 0xC0;
        }
    }
    feed(&mut dec, &p, &mut log).unwrap();
    dec.finish(&mut log);
    assert_eq!(log.points.len(), 8 * 48);
    let second = log.points.iter().filter(|p| p.3.ret == Return::Second);
    assert_eq!(second.count(), 2 * 96);
    // rs_driver's lens centre: RX 0.0075, RY 0.00664 (their hypotenuse along the rotor's
    // azimuth), RZ 0.04532 m.
    let (rxy, rz) = (0.0075f64.hypot(0.00664), 0.04532);
    for (_, p, _, m) in &log.points {
        let d = if m.ret == Return::Strongest {
            10.0
        } else {
            20.0
        };
        let v = (f64::from(elevation(model, usize::from(m.ring))) * 0.01).to_radians();
        assert!(
            (p[0].hypot(p[1]) - (d * v.cos() + rxy)).abs() < 1e-9,
            "{p:?} {m:?}"
        );
        assert!((p[2] - (d * v.sin() + rz)).abs() < 1e-9, "{p:?} {m:?}");
    }
}

#[test]
fn models_have_names_of_their_own_and_the_airy_install_modes_read_back() {
    let mut names: Vec<_> = Model::ALL.iter().map(|m| m.name()).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), Model::ALL.len());
    assert!(names.iter().all(|n| n.starts_with("RS-")), "{names:?}");
    for install in [AiryInstall::Normal, AiryInstall::Side, AiryInstall::AiryM] {
        assert_eq!(AiryInstall::from_byte(install.byte()), install);
    }
}

#[test]
fn only_the_models_of_a_layout_of_their_own_are_told_by_their_packets() {
    for model in Model::ALL {
        let p = msop(model, (10, 0), 1000, model.halves());
        let unique = matches!(model, Model::Ruby | Model::Airy);
        assert_eq!(wire::model_of(&p), unique.then_some(model), "{model:?}");
        assert_eq!(wire::model_of(&p[..1200]), None);
    }
    assert_eq!(wire::model_of(&difop(Model::Airy, 0)), None);
}

#[test]
fn each_return_is_timed_and_turned_by_its_firing_as_rs_driver() {
    // Two RS-Airy packets 444 us apart, firings every 0.2 degree from 10 degrees: a return
    // of laser `r` in the sweep's `j`-th firing is at time `j`'s packet + its firing in the
    // packet x 111.08 us + the normal table's time of its group of eight, and at the firing's
    // azimuth plus the rotation to the next firing in proportion (the last firing: the step
    // before).
    const NORMAL_US: [f64; 12] = [
        0.0, 5.712, 12.376, 19.040, 25.704, 33.320, 41.888, 50.456, 59.024, 70.448, 81.872, 93.296,
    ];
    // From 359 degrees too, so that the last firing ends within a step of north: the step to
    // its next firing is still the one before, not the way round to azimuth 0.
    let model = Model::Airy;
    let (rx, _) = model.lens_m();
    let mut worst: (f64, f64) = (0.0, 0.0);
    for start in [1000, 35800] {
        let mut dec = decoder(model);
        let mut log = Log::default();
        let _ = feed(&mut dec, &with(&difop(model, 0), AIRY_INSTALL, 0), &mut log);
        for n in 0..2u16 {
            let p = msop(model, (10, 444 * u32::from(n)), start + 80 * n, 2);
            feed(&mut dec, &p, &mut log).unwrap();
        }
        dec.finish(&mut log);
        assert_eq!(log.points.len(), 2 * 8 * 48);
        for (_, p, t, m) in &log.points {
            let (j, fire) = (usize::from(m.column), NORMAL_US[usize::from(m.ring) / 8]);
            let want_t = ((j / 4) as f64 * 444.0 + (j % 4) as f64 * 111.08 + fire) * 1e-6;
            let want_az = f64::from(start) + 20.0 * j as f64 + 20.0 * fire / 111.08;
            // No horizontal offsets: the beam and the lens centre turn with the rotor.
            let v = (f64::from(elevation(model, usize::from(m.ring))) * 0.01).to_radians();
            let rho = 10.0 * v.cos() + rx;
            let az = (-p[1]).atan2(p[0]).to_degrees().rem_euclid(360.0) * 100.0;
            assert!((p[0].hypot(p[1]) - rho).abs() < 1e-9);
            worst.0 = worst.0.max((t - want_t).abs());
            worst.1 = worst.1.max((az - want_az).abs());
        }
    }
    println!(
        "worst |dt| {:.1e} s, |d azimuth| {:.1e} (0.01 deg)",
        worst.0, worst.1
    );
    assert!(worst.0 < 1e-12 && worst.1 < 1e-9, "{worst:?}");
}

#[test]
fn without_a_difop_mode_dual_return_is_told_by_repeated_azimuths() {
    // Angles from a file say no return mode: a Helios packet whose firings repeat their
    // azimuth over two blocks is dual return, one that does not is single; an RS-16's
    // repeated azimuths are its two sequences of one block each, single return.
    for (model, per, seconds) in [
        (Model::Helios, 2, 6 * 32),
        (Model::Helios, 1, 0),
        (Model::Rs16, 2, 0),
    ] {
        let d = difop(model, 0x04);
        let angles = Calibration::from_difop(model, &wire::Difop::new_checked(&d).unwrap());
        let mut dec = Decoder::new(Config {
            model,
            calibration: Some(Calibration {
                dual: None,
                ..angles.unwrap()
            }),
            cut_angle_deg: None,
        })
        .unwrap();
        let mut log = Log::default();
        feed(&mut dec, &msop(model, (10, 0), 1000, per), &mut log).unwrap();
        dec.finish(&mut log);
        let second = log.points.iter().filter(|p| p.3.ret == Return::Second);
        assert_eq!(second.count(), seconds, "{model:?} {per}");
    }
}
