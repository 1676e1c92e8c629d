//! The Velodyne decoder on the models that need their calibration file (HDL-64E S2/S3,
//! VLS-128, VLP-32A/B): the first byte picks the model, the dual-return reading of the
//! HDL-64E (the first packet's azimuths) and the cut angle, the second the calibration's
//! near-point distance offsets; the rest is cut into packets, each prefixed by a
//! little-endian u16 length (mostly 1206). Asserts that nothing panics, every point and time
//! is finite and the sink protocol holds.
#![no_main]

mod sensor_sink;

use kiss_odom_sensors::heapless;
use kiss_odom_sensors::velodyne::{Calibration, Config, Decoder, Laser, Model};
use kiss_odom_sensors::Decode;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&[head, near], mut rest)) = data.split_first_chunk::<2>() else {
        return;
    };
    let model = [
        Model::Hdl64eS2,
        Model::Hdl64eS3,
        Model::Vls128,
        Model::Vlp32ab,
    ][usize::from(head & 3)];
    let cut = (head & 4 != 0).then_some(f64::from(head >> 3) * 11.25);
    let mut lasers = heapless::Vec::new();
    for i in 0..model.lasers() {
        let laser = Laser {
            vertical_deg: -25.0 + 40.0 * i as f64 / model.lasers() as f64,
            azimuth_offset_deg: f64::from(i as u8 % 9) - 4.0,
            distance_offset_m: 1.5,
            vertical_offset_m: 0.2,
            horizontal_offset_m: 0.026,
            near_distance_offset_m: (near & 1 != 0).then_some([f64::from(near >> 1) * 0.01, 1.4]),
        };
        let _ = lasers.push(laser);
    }
    let calibration = Calibration {
        lasers,
        distance_resolution_m: model.distance_resolution_m(),
    };
    let mut dec = Decoder::new(Config {
        model: Some(model),
        calibration: Some(calibration),
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
