//! The Velodyne models that need their calibration file (VLS-128, HDL-64E) on bad input: a
//! missing or wrong calibration, packets of another model or return mode on the port, a
//! truncated packet. Each is refused with its reason and counted, never decoded wrongly. And
//! each field of a VLP-16's and a VLS-128's packet corrupted alone: refused naming that field.

mod common;

use common::{feed, with, Log};
use kiss_odom_sensors::velodyne::{
    wire::field, Calibration, Config, Decoder, Laser, Model, BANK_FLAGS,
};
use kiss_odom_sensors::{heapless, ConfigError, Decode, PacketError};

fn calibration(model: Model) -> Calibration {
    let mut lasers = heapless::Vec::new();
    for i in 0..model.lasers() {
        let laser = Laser {
            vertical_deg: -25.0 + 40.0 * i as f64 / model.lasers() as f64,
            ..Laser::default()
        };
        lasers.push(laser).unwrap();
    }
    Calibration {
        lasers,
        distance_resolution_m: model.distance_resolution_m(),
    }
}

/// A single-return packet of `model` at `us` past the hour, its groups from azimuth `az`.
fn packet(model: Model, us: u32, az: u16) -> Vec<u8> {
    let banks = model.banks();
    let mut b = vec![0u8; field::LEN];
    for k in 0..field::BLOCKS {
        let at = k * field::BLOCK_LEN;
        b[at..at + 2].copy_from_slice(&BANK_FLAGS[k % banks].to_le_bytes());
        let group = (k / banks) as u16;
        b[at + 2..at + 4].copy_from_slice(&(az + 20 * group).to_le_bytes());
        for c in 0..32 {
            let d = at + 4 + 3 * c;
            b[d..d + 2].copy_from_slice(&(2500u16 + c as u16).to_le_bytes());
        }
    }
    b[1200..1204].copy_from_slice(&us.to_le_bytes());
    if let Some(p) = model.product() {
        b[1204] = 0x37;
        b[1205] = p;
    }
    b
}

fn config(model: Model) -> Config {
    Config {
        model: Some(model),
        calibration: Some(calibration(model)),
        cut_angle_deg: None,
    }
}

#[test]
fn a_model_that_needs_its_calibration_refuses_to_start_without_it() {
    for model in [
        Model::Vls128,
        Model::Hdl64eS2,
        Model::Hdl64eS3,
        Model::Vlp32ab,
    ] {
        let no_file = Config {
            calibration: None,
            ..config(model)
        };
        assert_eq!(Decoder::new(no_file).err(), Some(ConfigError::Calibration));
        // A file of another model's laser count.
        let wrong = Config {
            calibration: Some(calibration(Model::Vlp16)),
            ..config(model)
        };
        assert_eq!(Decoder::new(wrong).err(), Some(ConfigError::Calibration));
    }
    // A VLS-128 found by its product byte, with no file: every packet refused with the reason.
    let mut dec = Decoder::new(Config::default()).unwrap();
    let mut log = Log::default();
    let e = feed(&mut dec, &packet(Model::Vls128, 1000, 100), &mut log);
    assert_eq!(e, Err(PacketError::NoCalibration));
    dec.finish(&mut log);
    assert_eq!(dec.between_sweeps().bad_packets, 1);
    assert!(log.points.is_empty());
}

#[test]
fn another_models_packets_on_the_port_are_counted_and_skipped() {
    let mut dec = Decoder::new(config(Model::Vls128)).unwrap();
    let mut log = Log::default();
    let step = Model::Vls128.packet_us(false) as u32;
    feed(&mut dec, &packet(Model::Vls128, 1000, 100), &mut log).unwrap();
    // A VLP-16's packet (every block of the first bank) and an HDL-64E's (upper/lower pairs,
    // no product byte) between two of the VLS-128's.
    let vlp16 = packet(Model::Vlp16, 1000 + step / 2, 130);
    assert_eq!(
        feed(&mut dec, &vlp16, &mut log),
        Err(PacketError::OtherSensor)
    );
    let hdl = packet(Model::Hdl64eS3, 1000 + step / 2, 130);
    assert_eq!(
        feed(&mut dec, &hdl, &mut log),
        Err(PacketError::OtherSensor)
    );
    feed(&mut dec, &packet(Model::Vls128, 1000 + step, 160), &mut log).unwrap();
    dec.finish(&mut log);
    let s = log.ends.last().unwrap();
    assert_eq!((s.packets, s.other_sensor, s.lost_packets), (2, 2, 0));
    assert_eq!(log.points.len(), 2 * 12 * 32);
}

#[test]
fn a_return_mode_flipped_midway_is_another_sensor() {
    // VLS-128 single return, then the same packet marked dual.
    let mut dec = Decoder::new(config(Model::Vls128)).unwrap();
    let mut log = Log::default();
    feed(&mut dec, &packet(Model::Vls128, 1000, 100), &mut log).unwrap();
    let mut dual = packet(Model::Vls128, 1200, 160);
    dual[1204] = 0x39;
    assert_eq!(
        feed(&mut dec, &dual, &mut log),
        Err(PacketError::OtherSensor)
    );
    // HDL-64E: single return from its azimuths, then a packet whose pairs repeat one azimuth
    // (its dual-return layout).
    let mut dec = Decoder::new(config(Model::Hdl64eS3)).unwrap();
    let mut log = Log::default();
    feed(&mut dec, &packet(Model::Hdl64eS3, 1000, 100), &mut log).unwrap();
    let mut flipped = packet(Model::Hdl64eS3, 1400, 300);
    for k in [2, 3] {
        flipped[k * 100 + 2..k * 100 + 4].copy_from_slice(&300u16.to_le_bytes());
    }
    assert_eq!(
        feed(&mut dec, &flipped, &mut log),
        Err(PacketError::OtherSensor)
    );
}

#[test]
fn truncated_and_corrupted_packets_are_refused_with_the_reason() {
    let mut dec = Decoder::new(config(Model::Hdl64eS2)).unwrap();
    let mut log = Log::default();
    let p = packet(Model::Hdl64eS2, 1000, 100);
    assert_eq!(
        feed(&mut dec, &p[..1000], &mut log),
        Err(PacketError::Truncated)
    );
    let bad = with(&p, 301, 0x12);
    assert_eq!(feed(&mut dec, &bad, &mut log), Err(PacketError::BlockFlag));
    feed(&mut dec, &p, &mut log).unwrap();
    dec.finish(&mut log);
    let s = log.ends.last().unwrap();
    assert_eq!((s.packets, s.bad_packets), (1, 2));
    // The upper block's lasers are 0-31, the lower's 32-63: 64 rings a firing.
    let rings: std::collections::BTreeSet<u16> = log.points.iter().map(|p| p.3.ring).collect();
    assert_eq!(rings.len(), 64);
}

#[test]
fn each_corrupted_header_field_is_refused_by_its_own_name() {
    use PacketError::*;
    // A VLP-16 found by its product byte, a VLS-128 given with its calibration; `after`: the
    // corrupted packet follows a good one, which fixed the model and return mode.
    let vlp16 = || Decoder::new(Config::default()).unwrap();
    let vls128 = || Decoder::new(config(Model::Vls128)).unwrap();
    let refusal = |model: Model, after: bool, bytes: &[u8]| {
        let mut dec = if model == Model::Vlp16 {
            vlp16()
        } else {
            vls128()
        };
        let mut log = Log::default();
        if after {
            feed(&mut dec, &packet(model, 1000, 100), &mut log).unwrap();
        }
        dec.push(bytes, &mut log)
    };
    let set = |model: Model, at: usize, v: u8| with(&packet(model, 3000, 500), at, v);
    let (vlp, vls) = (Model::Vlp16, Model::Vls128);
    let (mode, product) = (field::RETURN_MODE, field::PRODUCT);
    let (fresh, after) = (false, true);
    let late_hour = {
        let mut b = packet(vlp, 3000, 500);
        b[field::TIMESTAMP].copy_from_slice(&3_600_000_000u32.to_le_bytes());
        b
    };
    // (model, field, packet, after a good one, refusal, what its text names)
    #[rustfmt::skip]
    let rows = vec![
        (vlp, "length", packet(vlp, 3000, 500)[..1000].to_vec(), fresh, Truncated, "shorter"),
        (vlp, "block 5 flag", set(vlp, 501, 0x12), fresh, BlockFlag, "block flag"),
        (vlp, "block 5 flag", set(vlp, 501, 0x12), after, BlockFlag, "block flag"),
        // Another bank's flag where the VLP-16 has its one bank: another model's packet.
        (vlp, "block 5 flag", set(vlp, 501, 0xDD), after, OtherSensor, "another sensor"),
        (vlp, "azimuth", set(vlp, 503, 0x99), fresh, Azimuth, "azimuth"),
        (vlp, "timestamp", late_hour, fresh, Timestamp, "timestamp"),
        (vlp, "product", set(vlp, product, 0x99), fresh, UnknownModel, "product byte"),
        (vlp, "product", set(vlp, product, 0x99), after, UnknownModel, "product byte"),
        // A model the byte names: another sensor's.
        (vlp, "product", set(vlp, product, 0x28), after, OtherSensor, "another sensor"),
        (vlp, "mode", set(vlp, mode, 0x3A), fresh, UnknownReturnMode, "return-mode"),
        (vlp, "mode", set(vlp, mode, 0x3A), after, UnknownReturnMode, "return-mode"),
        (vlp, "mode", set(vlp, mode, 0x39), after, OtherSensor, "another sensor"),
        (vls, "block 2 flag", set(vls, 201, 0x12), after, BlockFlag, "block flag"),
        (vls, "product", set(vls, product, 0x99), after, UnknownModel, "product byte"),
        (vls, "mode", set(vls, mode, 0xFF), after, UnknownReturnMode, "return-mode"),
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
