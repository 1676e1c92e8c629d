//! The Robosense decoder (`kiss_odom_sensors::robosense::Decoder::push`): the first byte picks
//! the model, whether the angles are given (else the decoder waits for a DIFOP packet among
//! the input) and the cut angle; the rest is cut into packets, each prefixed by a
//! little-endian u16 length (mostly 1248, MSOP or DIFOP). Asserts that nothing panics, every
//! point and time is finite and the sink protocol holds.
#![no_main]

mod sensor_sink;

use kiss_odom_sensors::heapless;
use kiss_odom_sensors::robosense::{Calibration, Config, Decoder, Laser, Model};
use kiss_odom_sensors::Decode;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&head, mut rest)) = data.split_first() else {
        return;
    };
    let model = Model::ALL[usize::from(head & 7) % Model::ALL.len()];
    let calibration = (head & 8 != 0).then(|| {
        let mut lasers = heapless::Vec::new();
        for i in 0..model.lasers() {
            let laser = Laser {
                vertical_deg: -25.0 + 40.0 * i as f64 / model.lasers() as f64,
                horizontal_deg: f64::from(i as u8 % 5) - 2.0,
            };
            let _ = lasers.push(laser);
        }
        Calibration { lasers, dual: None }
    });
    let cut = (head & 16 != 0).then_some(f64::from(head >> 5) * 45.0);
    let mut dec = Decoder::new(Config {
        model,
        calibration,
        cut_angle_deg: cut,
    })
    .expect("valid configuration");
    let mut sink = sensor_sink::Checked::default();
    while rest.len() >= 2 {
        let len = match u16::from_le_bytes([rest[0], rest[1]]) {
            l if l < 0x8000 => 1248,
            l => usize::from(l & 0x7FF),
        };
        let (packet, tail) = rest[2..].split_at(len.min(rest.len() - 2));
        sensor_sink::feed(&mut sink, |s| dec.push(packet, s));
        rest = tail;
    }
    dec.finish(&mut sink);
});
