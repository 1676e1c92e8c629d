//! The Hesai decoder (`kiss_odom_sensors::hesai::Decoder::push`) for every model: the first
//! byte's bits 1-2 pick the model (XT32, QT128, Pandar128, OT128), bit 3 whether to seal each
//! 128-channel packet's CRCs again (so that mutated packets get past the CRC checks of protocol
//! 3.2, the QT128's, and 1.4, the Pandar128's and OT128's; unsealed, they reach those checks),
//! bit 0 whether to cut at the angle its bits 4-7 give; the rest is cut into packets, each
//! prefixed by a little-endian u16 length (below 0x8000: the model's usual length, so that the
//! decoding runs). Asserts that nothing panics, every point and time is finite and the sink
//! protocol holds.
#![no_main]

mod sensor_sink;

use kiss_odom_sensors::hesai::{wire128, Calibration, Config, Decoder, Model};
use kiss_odom_sensors::Decode;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&head, mut rest)) = data.split_first() else {
        return;
    };
    let model =
        [Model::Xt32, Model::Qt128, Model::Pandar128, Model::Ot128][usize::from(head >> 1 & 3)];
    let cut = (head & 1 != 0).then_some(f64::from(head >> 4) * 22.5);
    let reseal = head & 8 != 0 && model != Model::Xt32;
    let calibration = (model != Model::Xt32).then(|| {
        let mut c = Calibration::nominal();
        c.channels = model.channels();
        for i in 0..c.channels {
            c.elevation_deg[i] = 52.0 - 0.8 * i as f64;
            c.azimuth_deg[i] = (i % 8) as f64 - 4.0;
        }
        c
    });
    let usual = match model {
        Model::Xt32 => 1080,
        Model::Qt128 => wire128::packet_len(wire128::VERSION_QT, 0x1D),
        _ => wire128::packet_len(wire128::VERSION_128, 0x07),
    };
    let mut dec = Decoder::new(Config {
        model,
        calibration,
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
        let mut sealed = [0u8; 2048];
        let packet = match sealed.get_mut(..packet.len()) {
            Some(copy) if reseal && packet.len() >= 12 => {
                copy.copy_from_slice(packet);
                for (covered, at) in wire128::crc_ranges((copy[2], copy[3]), copy[11]) {
                    if let (Some(bytes), true) = (copy.get(covered), at + 4 <= copy.len()) {
                        let crc = wire128::crc32_mpeg2(bytes);
                        copy[at..at + 4].copy_from_slice(&crc.to_le_bytes());
                    }
                }
                &*copy
            }
            _ => packet,
        };
        sensor_sink::feed(&mut sink, |s| dec.push(packet, s));
        rest = tail;
    }
    dec.finish(&mut sink);
});
