//! The Hesai PandarXT-32 decoder (`kiss_odom_sensors::hesai::Decoder::push`): the first byte
//! picks the cut angle, the rest is cut into packets, each prefixed by a little-endian u16
//! length (mostly 1080, so that the decoding runs). Asserts that nothing panics, every point
//! and time is finite and the sink protocol holds.
#![no_main]

mod sensor_sink;

use kiss_odom_sensors::hesai::{Config, Decoder};
use kiss_odom_sensors::Decode;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&head, mut rest)) = data.split_first() else {
        return;
    };
    let cut = (head & 1 != 0).then_some(f64::from(head >> 1) * 2.8125);
    let mut dec = Decoder::new(Config {
        calibration: None,
        cut_angle_deg: cut,
    })
    .expect("valid configuration");
    let mut sink = sensor_sink::Checked::default();
    while rest.len() >= 2 {
        let len = match u16::from_le_bytes([rest[0], rest[1]]) {
            l if l < 0x8000 => 1080,
            l => usize::from(l & 0x7FF),
        };
        let (packet, tail) = rest[2..].split_at(len.min(rest.len() - 2));
        sensor_sink::feed(&mut sink, |s| dec.push(packet, s));
        rest = tail;
    }
    dec.finish(&mut sink);
});
