//! The PandarAT128 decoder on synthetic packets: each return where its mirror-frame
//! correction says (recomputed here from the correction's integers), at its firing time; sweeps
//! that are the mirror frames; and what it refuses. Also the return-mode rules the fixed-layout
//! models share with it: the header's return count, and the XT32M's triple return.

use kiss_odom_sensors::hesai::wire_fixed::PANDARAT128;
use kiss_odom_sensors::hesai::{self, At128Correction, Calibration, Firing, Model};
use kiss_odom_sensors::{Decode, PacketError, Pushed, Return, SweepEnd};
mod common;
#[path = "common/hesai_fixed.rs"]
mod fixed_layout;

use common::{feed, with, Log};
use fixed_layout::{correction, decoder, fixed, packet, Spec, DEG, EPOCH_S};

/// The direction of channel `ch` at motor angle `motor` (units) in frame `frame`, degrees:
/// the correction's formula, written out here.
fn expected_deg(c: &At128Correction, motor: u32, frame: usize, ch: usize) -> (f64, f64) {
    let into = (i64::from(motor) - i64::from(c.start[frame])).rem_euclid(360 * i64::from(DEG));
    let i = (motor / (200 * 256)) as usize;
    let k = f64::from(motor % (200 * 256)) / f64::from(200 * 256);
    let lerp = |t: &[i8; 180]| {
        ((1.0 - k) * f64::from(t[i % 180]) + k * f64::from(t[(i + 1) % 180])) * 2.0 / 100.0
    };
    let az =
        (2 * into - i64::from(c.azimuth[ch])) as f64 / f64::from(DEG) + lerp(&c.azimuth_adjust[ch]);
    let el = f64::from(c.elevation[ch]) / f64::from(DEG) + lerp(&c.elevation_adjust[ch]);
    (az, el)
}

#[test]
fn each_return_points_where_its_mirror_frame_correction_says_at_its_firing_time() {
    let c = correction();
    let mut dec = decoder();
    let mut log = Log::default();
    // Frame 1 (motor 140 to 260 degrees), 60.3 degrees into it.
    let motor = 200 * DEG + 7_777;
    let s = Spec::new(motor, 500_000, 7);
    assert_eq!(feed(&mut dec, &packet(&s), &mut log), Ok(Pushed::Decoded));
    dec.finish(&mut log);
    assert_eq!(log.points.len(), 2 * 127);
    let t0 = (EPOCH_S * 1_000_000 + s.us) * 1000;
    let start = log.starts[0].start_ns;
    let single = Firing {
        returns: 1,
        ..Firing::default()
    };
    let mut worst = 0f64;
    for &(_, p, t, m) in &log.points {
        let (ch, k) = (usize::from(m.ring), usize::from(m.column));
        let d = (1000 * (k + 1) + ch) as f64 * 0.004;
        let (az, el) = expected_deg(&c, motor + 1_280 * k as u32, 1, ch);
        let (az, el) = (az.to_radians(), el.to_radians());
        let want = [
            d * el.cos() * az.sin(),
            d * el.cos() * az.cos(),
            d * el.sin(),
        ];
        let e = (0..3).map(|i| (p[i] - want[i]).powi(2)).sum::<f64>().sqrt();
        worst = worst.max(e);
        let offset = Model::At128.point_offset_ns(k, ch, &single);
        assert_eq!(t, (t0 as i64 + offset - start as i64) as f64 * 1e-9);
        assert_eq!(m.ret, Return::Strongest);
    }
    println!("AT128: worst |dxyz| {worst:.2e} m against the formula (tolerance 1e-9 m)");
    assert!(worst < 1e-9);
    // The middle of the field looks forward: channels 0 and 1 of block 0 are near azimuth 120.
    let (_, p, _, _) = log.points[0];
    assert!(p[0] > 0.0 && p[1] < 0.0, "{p:?}");
}

#[test]
fn sweeps_are_its_mirror_frames_and_losses_come_from_sequence_numbers() {
    let mut dec = decoder();
    let mut log = Log::default();
    // Frame 0: three packets, the third after a lost one; then frame 1.
    for (i, (motor, us, seq)) in [(40, 0, 0), (41, 84, 1), (43, 250, 3)].iter().enumerate() {
        let r = feed(
            &mut dec,
            &packet(&Spec::new(motor * DEG, *us, *seq)),
            &mut log,
        );
        assert_eq!(r, Ok(Pushed::Decoded), "packet {i}");
    }
    let next = packet(&Spec::new(160 * DEG, 334, 4));
    assert_eq!(dec.push(&next, &mut log), Ok(Pushed::Again));
    assert_eq!(log.ends.len(), 1);
    assert_eq!(log.ends[0].end, SweepEnd::Complete);
    assert_eq!((log.ends[0].packets, log.ends[0].lost_packets), (3, 1));
    assert_eq!(dec.push(&next, &mut log), Ok(Pushed::Decoded));
    dec.finish(&mut log);
    assert_eq!(log.ends.len(), 2);
    assert_eq!((log.ends[1].packets, log.ends[1].lost_packets), (1, 0));
}

#[test]
fn packets_it_cannot_decode_are_refused_with_the_reason() {
    let good = Spec::new(40 * DEG, 0, 0);
    let refused = |b: &[u8]| decoder().push(b, &mut Log::default()).unwrap_err();
    // A block azimuth in no frame of the correction.
    let mut two = correction();
    two.frames = 2;
    let mut dec = hesai::Decoder::at128(&two).unwrap();
    let outside = packet(&Spec::new(300 * DEG, 0, 0));
    assert_eq!(
        dec.push(&outside, &mut Log::default()),
        Err(PacketError::MirrorFrame)
    );
    // Modes the AT128 does not list, and a header that counts fewer returns than the mode.
    let dual = |mode| Spec {
        mode,
        returns: 2,
        ..Spec::new(40 * DEG, 0, 0)
    };
    assert_eq!(
        refused(&packet(&dual(0x3B))),
        PacketError::UnknownReturnMode
    );
    let tail = PANDARAT128.tail_at() + PANDARAT128.return_mode;
    assert_eq!(
        refused(&with(&packet(&dual(0x39)), 10, 1)),
        PacketError::ReturnCount {
            count: 1,
            mode: 0x39
        }
    );
    // A single-return packet whose header counts the two returns the unit can send: decoded.
    let mut log = Log::default();
    assert!(feed(&mut decoder(), &with(&packet(&good), 10, 2), &mut log).is_ok());
    // Dual last + strongest: block 0 the last.
    let mut log2 = Log::default();
    let mut dec = decoder();
    assert!(feed(&mut dec, &packet(&dual(0x39)), &mut log2).is_ok());
    dec.finish(&mut log2);
    assert!(log2.points.iter().any(|p| p.3.ret == Return::Last));
    assert_eq!(packet(&dual(0x39))[tail], 0x39);
    // Cut, or microseconds beyond the second.
    assert_eq!(refused(&packet(&good)[..1000]), PacketError::Truncated);
    let micros = PANDARAT128.tail_at() + PANDARAT128.micros;
    assert_eq!(
        refused(&with(&packet(&good), micros + 3, 1)),
        PacketError::DateTime
    );
    let date = PANDARAT128.tail_at() + PANDARAT128.date;
    // A civil date (a nonzero first byte, Hesai's SDK): 2024-01-01 00:00:00 read as such.
    let mut civil = packet(&good);
    civil[date..date + 6].copy_from_slice(&[124, 1, 1, 0, 0, 0]);
    let mut log3 = Log::default();
    assert!(feed(&mut decoder(), &civil, &mut log3).is_ok());
    assert_eq!(log3.starts[0].start_ns, log.starts[0].start_ns);
}

#[test]
fn an_at128_needs_its_correction_and_a_correction_is_checked() {
    let config = hesai::Config {
        model: Model::At128,
        calibration: Some(Calibration::nominal()),
        cut_angle_deg: None,
    };
    assert!(hesai::Decoder::new(config).is_err());
    let mut bad = correction();
    bad.azimuth[3] = 46 * DEG as i32;
    assert!(hesai::Decoder::at128(&bad).is_err());
    bad = correction();
    bad.start[1] = 360 * DEG;
    assert!(hesai::Decoder::at128(&bad).is_err());
}

#[test]
fn the_xt32ms_triple_return_is_refused_as_such_and_its_header_counts_its_most() {
    let decoder = || {
        let mut c = Calibration::nominal();
        c.channels = 32;
        hesai::Decoder::new(hesai::Config {
            model: Model::Xt32m,
            calibration: Some(c),
            cut_angle_deg: None,
        })
        .unwrap()
    };
    assert_eq!(
        decoder().push(&fixed(Model::Xt32m, 0x3D, 3), &mut Log::default()),
        Err(PacketError::TripleReturn)
    );
    assert!(PacketError::TripleReturn
        .to_string()
        .contains("triple return (0x3D)"));
    // Its recorded capture: dual (0x3C) with a header count of 3, the most it sends.
    assert!(feed(
        &mut decoder(),
        &fixed(Model::Xt32m, 0x3C, 3),
        &mut Log::default()
    )
    .is_ok());
    assert!(feed(
        &mut decoder(),
        &fixed(Model::Xt32m, 0x37, 3),
        &mut Log::default()
    )
    .is_ok());
    // More than it can send, or fewer than the mode's: a damaged header.
    for (mode, count) in [(0x3C, 4), (0x3C, 1)] {
        assert_eq!(
            decoder().push(&fixed(Model::Xt32m, mode, count), &mut Log::default()),
            Err(PacketError::ReturnCount { count, mode }),
            "{mode:#x} {count}"
        );
    }
}
