//! The Livox decoder (`kiss_odom_sensors::livox::Decoder::push`), SDK 1 and SDK 2: the first
//! byte picks the model (bits 0-1: Horizon, Mid-40, Mid-360), whether SDK 2 packets get their
//! CRC-32 written before the push (bit 2: so that mutations reach past the CRC check) and the
//! frame period; the rest is cut into packets, each prefixed by a little-endian u16 length
//! (below 0x8000: the model's usual packet, 1362 or 1380 bytes; else the low 11 bits). Asserts
//! that nothing panics, every point and time is finite, the sink protocol holds and no sweep
//! counts more packets lost than its packets' time steps can hold: each step is at most the
//! frame gap (`GAP_NS`) and a packet spans at least 100 ns (SDK 2's unit of `time_interval`).
#![no_main]

mod sensor_sink;

use kiss_odom_sensors::livox::{sdk2, Config, Decoder, Model, GAP_NS};
use kiss_odom_sensors::Decode;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&head, mut rest)) = data.split_first() else {
        return;
    };
    let (model, usual) = match head & 3 {
        0 => (Model::Horizon, 1362),
        1 => (Model::Mid40, 1362),
        _ => (Model::Mid360, 1380),
    };
    let seal = head & 4 != 0;
    let mut dec = Decoder::new(Config {
        model,
        frame_period_ns: 1_000_000 * (1 + u64::from(head >> 3)),
    })
    .expect("valid configuration");
    let mut sink = sensor_sink::Checked::with_lost_per_packet(GAP_NS / 100);
    let mut packet = Vec::new();
    while rest.len() >= 2 {
        let len = match u16::from_le_bytes([rest[0], rest[1]]) {
            l if l < 0x8000 => usual,
            l => usize::from(l & 0x7FF),
        };
        let (bytes, tail) = rest[2..].split_at(len.min(rest.len() - 2));
        packet.clear();
        packet.extend_from_slice(bytes);
        if seal && model == Model::Mid360 && packet.len() >= sdk2::field::DATA {
            let crc = sdk2::crc32(&packet[sdk2::field::TIMESTAMP.start..]);
            packet[sdk2::field::CRC32].copy_from_slice(&crc.to_le_bytes());
        }
        sensor_sink::feed(&mut sink, |s| dec.push(&packet, s));
        rest = tail;
    }
    dec.finish(&mut sink);
});
