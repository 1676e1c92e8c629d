//! The Hesai decoder (`kiss_odom_sensors::hesai::Decoder::push`) for the fixed-layout models:
//! the first byte's bits 1-3 pick the model (Pandar40P, Pandar64, PandarQT64, XT16, XT32M,
//! AT128; the rest wrap around), bit 0 whether to cut at the angle its bits 4-7 give (not the
//! AT128, whose sweeps are its mirror frames); the rest is cut into packets, each prefixed by
//! a little-endian u16 length (below 0x8000: the model's usual length, so that the decoding
//! runs). The AT128 decodes with a correction of three frames covering the turn. Asserts that
//! nothing panics, every point and time is finite and the sink protocol holds;
//! `hesai::identify` runs on every packet too.
#![no_main]

mod sensor_sink;

use kiss_odom_sensors::hesai::{identify, At128Correction, Calibration, Config, Decoder, Model};
use kiss_odom_sensors::Decode;
use libfuzzer_sys::fuzz_target;

const MODELS: [Model; 6] = [
    Model::Pandar40P,
    Model::Pandar64,
    Model::PandarQT64,
    Model::Xt16,
    Model::Xt32m,
    Model::At128,
];

/// Three frames of 120 degrees from 20 degrees, angles and adjustments of every sign.
fn correction() -> At128Correction {
    let mut c = At128Correction::empty();
    c.frames = 3;
    c.start[..3].copy_from_slice(&[512_000, 3_584_000, 6_656_000]);
    c.end[..3].copy_from_slice(&[3_584_000, 6_656_000, 512_000]);
    for ch in 0..128 {
        c.azimuth[ch] = (ch as i32 % 5 - 2) * 30_000;
        c.elevation[ch] = 330_000 - 5_160 * ch as i32;
        for i in 0..180 {
            c.azimuth_adjust[ch][i] = (i as i32 * 7 - 600) as i8;
            c.elevation_adjust[ch][i] = (ch as i32 - i as i32) as i8;
        }
    }
    c.adjust_unit = 2;
    c
}

fn run<D: Decode>(mut dec: D, mut rest: &[u8], usual: usize) {
    let mut sink = sensor_sink::Checked::default();
    while rest.len() >= 2 {
        let len = match u16::from_le_bytes([rest[0], rest[1]]) {
            l if l < 0x8000 => usual,
            l => usize::from(l & 0x7FF),
        };
        let (packet, tail) = rest[2..].split_at(len.min(rest.len() - 2));
        let _ = identify(packet);
        sensor_sink::feed(&mut sink, |s| dec.push(packet, s));
        rest = tail;
    }
    dec.finish(&mut sink);
}

fuzz_target!(|data: &[u8]| {
    let Some((&head, rest)) = data.split_first() else {
        return;
    };
    let model = MODELS[usize::from(head >> 1 & 7) % MODELS.len()];
    let usual = model.fixed_format().map_or(0, |f| f.default_len());
    if model == Model::At128 {
        let dec = Decoder::at128(&correction()).expect("valid correction");
        return run(dec, rest, usual);
    }
    let cut = (head & 1 != 0).then_some(f64::from(head >> 4) * 22.5);
    let mut c = Calibration::nominal();
    c.channels = model.channels();
    for i in 0..c.channels {
        c.elevation_deg[i] = 52.0 - 1.6 * i as f64;
        c.azimuth_deg[i] = (i % 8) as f64 - 4.0;
    }
    let dec = Decoder::new(Config {
        model,
        calibration: Some(c),
        cut_angle_deg: cut,
    })
    .expect("valid configuration");
    run(dec, rest, usual);
});
