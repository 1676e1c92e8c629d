//! The Hesai decoder (`kiss_odom_sensors::hesai::Decoder::push`) for the fixed-layout models:
//! the first byte's bits 1-3 pick the model (Pandar40P, Pandar64, PandarQT64, XT16, XT32M; the
//! rest wrap around), bit 0 whether to cut at the angle its bits 4-7 give; the rest is cut
//! into packets, each prefixed by a little-endian u16 length (below 0x8000: the model's usual
//! length, so that the decoding runs). Asserts that nothing panics, every point and time is
//! finite and the sink protocol holds; `hesai::identify` runs on every packet too.
#![no_main]

mod sensor_sink;

use kiss_odom_sensors::hesai::{identify, Calibration, Config, Decoder, Model};
use kiss_odom_sensors::Decode;
use libfuzzer_sys::fuzz_target;

const MODELS: [Model; 5] = [
    Model::Pandar40P,
    Model::Pandar64,
    Model::PandarQT64,
    Model::Xt16,
    Model::Xt32m,
];

fuzz_target!(|data: &[u8]| {
    let Some((&head, mut rest)) = data.split_first() else {
        return;
    };
    let model = MODELS[usize::from(head >> 1 & 7) % MODELS.len()];
    let cut = (head & 1 != 0).then_some(f64::from(head >> 4) * 22.5);
    let mut c = Calibration::nominal();
    c.channels = model.channels();
    for i in 0..c.channels {
        c.elevation_deg[i] = 52.0 - 1.6 * i as f64;
        c.azimuth_deg[i] = (i % 8) as f64 - 4.0;
    }
    let usual = model.fixed_format().map_or(0, |f| f.default_len());
    let mut dec = Decoder::new(Config {
        model,
        calibration: Some(c),
        cut_angle_deg: cut,
    })
    .expect("valid configuration");
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
});
