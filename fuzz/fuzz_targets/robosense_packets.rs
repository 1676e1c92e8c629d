//! The Robosense decoders (`kiss_odom_sensors::robosense::Decoder::push`, and with the first
//! byte's top bit the RS-M1's): the first byte picks the model, whether the angles are given
//! (else the decoder waits for a DIFOP packet among the input) and the cut angle; the rest is
//! cut into packets, each prefixed by a little-endian u16 length (mostly 1248, MSOP or DIFOP;
//! the M1's 1210). Asserts that nothing panics, every
//! point and time is finite and the sink protocol holds.
#![no_main]

mod sensor_sink;

use kiss_odom_sensors::heapless;
use kiss_odom_sensors::robosense::{AiryInstall, Calibration, Config, Decoder, Laser, Model};
use kiss_odom_sensors::Decode;
use libfuzzer_sys::fuzz_target;

/// Feeds `rest`, cut as the module doc says, to `dec`.
fn feed_all<D: Decode>(dec: &mut D, mut rest: &[u8], len: usize) {
    let mut sink = sensor_sink::Checked::default();
    while rest.len() >= 2 {
        let len = match u16::from_le_bytes([rest[0], rest[1]]) {
            l if l < 0x8000 => len,
            l => usize::from(l & 0x7FF),
        };
        let (packet, tail) = rest[2..].split_at(len.min(rest.len() - 2));
        sensor_sink::feed(&mut sink, |s| dec.push(packet, s));
        rest = tail;
    }
    dec.finish(&mut sink);
}

fuzz_target!(|data: &[u8]| {
    let Some((&head, rest)) = data.split_first() else {
        return;
    };
    if head & 0x80 != 0 {
        use kiss_odom_sensors::robosense::solid::{Decoder, Model};
        let model = if head & 0x40 != 0 {
            Model::E1r
        } else {
            Model::M1
        };
        feed_all(&mut Decoder::new(model), rest, model.packet_len());
        return;
    }
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
        Calibration {
            lasers,
            dual: None,
            install: AiryInstall::from_byte((head >> 5) & 3),
        }
    });
    let cut = (head & 16 != 0).then_some(f64::from((head >> 5) & 3) * 90.0);
    let mut dec = Decoder::new(Config {
        model,
        calibration,
        cut_angle_deg: cut,
    })
    .expect("valid configuration");
    feed_all(&mut dec, rest, 1248);
});
