//! Every Hesai layout's header and tail fields, each corrupted alone in a packet the decoder
//! takes: the refusal names that field (its variant, and its text), not another one. Before
//! the first packet fixes the return mode and after it.

use kiss_odom_sensors::hesai::{self, wire::field, Model};
use kiss_odom_sensors::{Decode, PacketError};
mod common;
#[path = "common/hesai_fixed.rs"]
mod fixed_layout;
#[path = "common/hesai_wide.rs"]
mod wide;
#[path = "common/hesai_xt32.rs"]
mod xt32;

use common::{feed, with, Log};
use fixed_layout::DEG;

/// The packet of `model` every row corrupts: as the model's own tests build it, 600 rpm, single
/// return (the XT32's with its sequence number, the QT128's with every part flagged).
fn good(model: Model) -> Vec<u8> {
    match model {
        Model::Xt32 => xt32::packet(&xt32::Spec {
            sequence: Some(1),
            ..xt32::Spec::new(100, 0)
        }),
        Model::Qt128 => wide::packet(&wide::Spec::qt(100, 0)),
        Model::Pandar128 | Model::Ot128 => wide::packet(&wide::Spec::p128(100, 0)),
        Model::At128 => fixed_layout::packet(&fixed_layout::Spec::new(40 * DEG, 0, 0)),
        Model::PandarQT64 => fixed_layout::fixed(model, 0x38, 1),
        _ => fixed_layout::fixed(model, 0x37, 1),
    }
}

/// `model`'s good packet with byte `at` set to `v`.
fn set(model: Model, at: usize, v: u8) -> Vec<u8> {
    with(&good(model), at, v)
}

/// `model`'s good packet with the u16 at `at` set to `v`.
fn set16(model: Model, at: usize, v: u16) -> Vec<u8> {
    let mut b = good(model);
    b[at..at + 2].copy_from_slice(&v.to_le_bytes());
    b
}

/// A protocol 3.2 or 1.4 packet with byte `at` set to `v` and its CRCs computed again: what
/// the byte says is checked, not the CRC.
fn sealed(model: Model, at: usize, v: u8) -> Vec<u8> {
    wide::seal(&mut set(model, at, v))
}

/// Why a decoder of `model` refuses `bytes`, fresh or after its good packet (`warm`).
fn refusal(model: Model, warm: bool, bytes: &[u8]) -> PacketError {
    match model {
        Model::Xt32 => refused_by(xt32::decoder(), model, warm, bytes),
        Model::Qt128 | Model::Pandar128 | Model::Ot128 => {
            refused_by(wide::decoder(model), model, warm, bytes)
        }
        Model::At128 => refused_by(fixed_layout::decoder(), model, warm, bytes),
        _ => {
            let mut calibration = wide::calibration();
            calibration.channels = model.channels();
            let config = hesai::Config {
                model,
                calibration: Some(calibration),
                cut_angle_deg: None,
            };
            refused_by(hesai::Decoder::new(config).unwrap(), model, warm, bytes)
        }
    }
}

fn refused_by<D: Decode>(mut dec: D, model: Model, warm: bool, bytes: &[u8]) -> PacketError {
    let mut log = Log::default();
    if warm {
        let first = feed(&mut dec, &good(model), &mut log);
        assert!(first.is_ok(), "{model:?}: the good packet {first:?}");
    }
    match dec.push(bytes, &mut log) {
        Err(e) => e,
        Ok(p) => panic!("{model:?}: decoded ({p:?})"),
    }
}

/// A fresh decoder, or one the good packet has fixed the return mode of.
const FRESH: bool = false;
const AFTER: bool = true;

fn rc(count: u8, mode: u8) -> PacketError {
    PacketError::ReturnCount { count, mode }
}

fn hf(flags: u8, announced: u16, len: u16) -> PacketError {
    PacketError::HeaderFlags {
        flags,
        announced,
        len,
    }
}

#[test]
fn each_corrupted_header_field_is_refused_by_its_own_name() {
    use Model::*;
    use PacketError::*;
    let f = |m: Model| m.fixed_format().unwrap();
    let (qt, p128) = (wide::Spec::qt(0, 0), wide::Spec::p128(0, 0));
    let (qt_mode, qt_month) = (wide::tail_at(&qt) + 12, wide::tail_at(&qt) + 16);
    let (p128_az, p128_state) = (wide::tail_at(&p128) + 10, wide::tail_at(&p128) + 11);
    let p128_mode = wide::tail_at(&p128) + 12;
    let p40_mode = f(Pandar40P).tail_at() + f(Pandar40P).return_mode;
    let at_mode = f(At128).tail_at() + f(At128).return_mode;
    let at_us = f(At128).tail_at() + f(At128).micros + 3;
    let (mode, flags, returns) = (field::RETURN_MODE, field::FLAGS, field::RETURNS);
    let (lasers, blocks, unit) = (field::LASERS, field::BLOCK_COUNT, field::DISTANCE_UNIT);
    let minor = field::VERSION_MINOR;
    let motor = set16(Xt32, field::MOTOR_SPEED.start, 1200);
    let p40_block3 = f(Pandar40P).block_at(3);
    let at_azimuth = f(At128).block_at(0) + 1;
    let fs = |operational, azimuth| FiringState {
        operational,
        azimuth,
    };
    // (model, field, packet, decoder, refusal, what its text names)
    #[rustfmt::skip]
    let rows = vec![
        // Protocol 6.1 (XT32).
        (Xt32, "start", set(Xt32, 0, 0xEF), FRESH, StartBytes, "start bytes"),
        (Xt32, "version", set(Xt32, field::VERSION_MAJOR, 4), FRESH, Version, "protocol version"),
        (Xt32, "lasers", set(Xt32, lasers, 16), FRESH, Header, "laser count"),
        (Xt32, "blocks", set(Xt32, blocks, 6), FRESH, Header, "block count"),
        (Xt32, "unit", set(Xt32, unit, 2), FRESH, Header, "distance unit"),
        (Xt32, "returns", set(Xt32, returns, 3), FRESH, rc(3, 0x37), "return count 3"),
        (Xt32, "flags", set(Xt32, flags, 0), FRESH, hf(0, 1076, 1080), "header flags 0x00"),
        (Xt32, "azimuth", set(Xt32, 12 + 130 * 3 + 1, 0x8D), FRESH, Azimuth, "azimuth"),
        (Xt32, "mode", set(Xt32, mode, 0x3A), FRESH, UnknownReturnMode, "return-mode"),
        (Xt32, "mode", set(Xt32, mode, 0x3A), AFTER, UnknownReturnMode, "return-mode"),
        (Xt32, "mode", set(Xt32, mode, 0x3D), AFTER, TripleReturn, "triple return"),
        (Xt32, "mode", set(Xt32, mode, 0x39), AFTER, rc(1, 0x39), "return-mode byte 0x39"),
        // A mode the model has, in a packet that agrees with itself: another sensor's.
        (Xt32, "mode", set(Xt32, mode, 0x38), AFTER, OtherSensor, "another sensor"),
        (Xt32, "motor", motor, FRESH, FiringStep { step: 18, expected: 36 }, "motor speed"),
        (Xt32, "month", set(Xt32, field::DATE_TIME.start + 1, 13), FRESH, DateTime, "date"),
        (Xt32, "us", set(Xt32, field::MICROSECONDS.start + 3, 0x10), FRESH, DateTime, "date"),
        // Protocols 3.2 (QT128) and 1.4 (Pandar128, OT128): the header is under no CRC; a
        // tail field is changed with the CRCs computed again.
        (Qt128, "version", set(Qt128, minor, 3), FRESH, Version, "protocol version"),
        (Qt128, "unit", set(Qt128, unit, 2), FRESH, Header, "distance unit"),
        (Qt128, "returns", set(Qt128, returns, 3), FRESH, rc(3, 0x37), "return count 3"),
        (Qt128, "flags", set(Qt128, flags, 0x15), FRESH, hf(0x15, 1095, 1127), "header flags 0x15"),
        (Qt128, "mode", sealed(Qt128, qt_mode, 0x3A), AFTER, UnknownReturnMode, "return-mode"),
        (Qt128, "month", sealed(Qt128, qt_month, 13), FRESH, DateTime, "date"),
        (Ot128, "flags", set(Ot128, flags, 0x03), FRESH, hf(3, 844, 861), "header flags 0x03"),
        (Ot128, "state", sealed(Ot128, p128_state, 1), FRESH, fs(1, 0), "operational state 1"),
        (Ot128, "azimuth state", sealed(Ot128, p128_az, 0x90), FRESH, fs(2, 2), "azimuth state 2"),
        (Pandar128, "mode", sealed(Pandar128, p128_mode, 0x39), AFTER, rc(1, 0x39), "count 1"),
        (Ot128, "mode", sealed(Ot128, p128_mode, 0xFF), AFTER, UnknownReturnMode, "return-mode"),
        // The fixed layouts (the 12-byte header is the XT32's, the Pandar64's 8 bytes have the
        // lasers at 2 and the unit at 5); the 40P has no header: it starts with block 0's flag.
        (Pandar40P, "block 0 flag", set(Pandar40P, 0, 0), FRESH, BlockFlag, "block flag"),
        (Pandar40P, "block 3 flag", set(Pandar40P, p40_block3, 0), FRESH, BlockFlag, "block flag"),
        (Pandar40P, "mode", set(Pandar40P, p40_mode, 0xFF), AFTER, UnknownReturnMode, "mode byte"),
        (Pandar40P, "mode", set(Pandar40P, p40_mode, 0x38), AFTER, OtherSensor, "another sensor"),
        (Pandar64, "lasers", set(Pandar64, 2, 32), FRESH, Header, "laser count"),
        (Pandar64, "unit", set(Pandar64, 5, 0), FRESH, Header, "distance unit"),
        (PandarQT64, "version", set(PandarQT64, minor, 2), FRESH, Version, "protocol version"),
        (PandarQT64, "returns", set(PandarQT64, returns, 2), FRESH, rc(2, 0x38), "return count 2"),
        (PandarQT64, "flags", set(PandarQT64, flags, 0), FRESH, hf(0, 1068, 1072), "header flags"),
        (Xt16, "lasers", set(Xt16, lasers, 32), FRESH, Header, "laser count"),
        (Xt16, "flags", set(Xt16, flags, 0x02), FRESH, hf(2, 564, 568), "header flags 0x02"),
        (Xt32m, "returns", set(Xt32m, returns, 4), FRESH, rc(4, 0x37), "return count 4"),
        (Xt32m, "flags", set(Xt32m, flags, 0), FRESH, hf(0, 816, 820), "header flags 0x00"),
        (At128, "blocks", set(At128, blocks, 4), FRESH, Header, "block count"),
        (At128, "returns", set(At128, returns, 0), FRESH, rc(0, 0x37), "return count 0"),
        (At128, "azimuth", set(At128, at_azimuth, 0xFF), FRESH, Azimuth, "azimuth"),
        (At128, "us", set(At128, at_us, 1), FRESH, DateTime, "date"),
        (At128, "mode", set(At128, at_mode, 0x3A), AFTER, UnknownReturnMode, "return-mode"),
    ];
    for (model, name, bytes, warm, want, names) in &rows {
        let got = refusal(*model, *warm, bytes);
        let row = format!("{model:?} {name} (after a good packet: {warm})");
        assert_eq!(got, *want, "{row}");
        let text = got.to_string();
        assert!(
            text.contains(names),
            "{row}: \"{text}\" does not name {names}"
        );
    }
}
