//! The Velodyne decoder (`kiss_odom_sensors::velodyne::Decoder::push`): the first byte picks
//! the configuration (model forced or read from packets, cut angle), the rest is cut into
//! packets, each prefixed by a little-endian u16 length (mostly 1206, so that the decoding
//! runs). Asserts that nothing panics, every point and time is finite and the sink protocol
//! holds.
#![no_main]

mod sensor_sink;

use kiss_odom_sensors::velodyne::{Config, Decoder, Model};
use kiss_odom_sensors::Decode;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&head, mut rest)) = data.split_first() else {
        return;
    };
    let model = [
        None,
        Some(Model::Vlp16),
        Some(Model::Vlp32c),
        Some(Model::Hdl32e),
    ][usize::from(head & 3)];
    let cut = (head & 4 != 0).then_some(f64::from(head >> 3) * 11.25);
    let mut dec = Decoder::new(Config {
        model,
        calibration: None,
        cut_angle_deg: cut,
    })
    .expect("valid configuration");
    let mut sink = sensor_sink::Checked::default();
    while rest.len() >= 2 {
        let len = match u16::from_le_bytes([rest[0], rest[1]]) {
            l if l < 0x8000 => 1206,
            l => usize::from(l & 0x7FF),
        };
        let (packet, tail) = rest[2..].split_at(len.min(rest.len() - 2));
        sensor_sink::feed(&mut sink, |s| dec.push(packet, s));
        rest = tail;
    }
    dec.finish(&mut sink);
});
