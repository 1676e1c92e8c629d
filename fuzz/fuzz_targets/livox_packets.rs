//! The Livox SDK 1 decoder (`kiss_odom_sensors::livox::Decoder::push`): the first byte picks
//! the model and frame period, the rest is cut into packets, each prefixed by a little-endian
//! u16 length (mostly 1362, data type 2, so that the decoding runs). Asserts that nothing
//! panics, every point and time is finite and the sink protocol holds.
#![no_main]

mod sensor_sink;

use kiss_odom_sensors::livox::{Config, Decoder, Model};
use kiss_odom_sensors::Decode;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&head, mut rest)) = data.split_first() else {
        return;
    };
    let model = if head & 1 == 0 { Model::Horizon } else { Model::Mid40 };
    let mut dec = Decoder::new(Config {
        model,
        frame_period_ns: 1_000_000 * (1 + u64::from(head >> 1)),
    })
    .expect("valid configuration");
    let mut sink = sensor_sink::Checked::default();
    while rest.len() >= 2 {
        let len = match u16::from_le_bytes([rest[0], rest[1]]) {
            l if l < 0x8000 => 1362,
            l => usize::from(l & 0x7FF),
        };
        let (packet, tail) = rest[2..].split_at(len.min(rest.len() - 2));
        sensor_sink::feed(&mut sink, |s| dec.push(packet, s));
        rest = tail;
    }
    dec.finish(&mut sink);
});
