//! The Ouster decoder (`kiss_odom_sensors::ouster::Decoder::push`): the first byte picks the
//! profile and beam count of a small sensor (64 columns, 4 a packet, arbitrary angles from the
//! next bytes), the rest is cut into packets of the layout's length (a length byte can make one
//! shorter or longer). Asserts that nothing panics, every point and time is finite and the sink
//! protocol holds.
#![no_main]

mod sensor_sink;

use kiss_odom_sensors::heapless::Vec;
use kiss_odom_sensors::ouster::{Decoder, Profile, SensorInfo};
use kiss_odom_sensors::Decode;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.len() < 4 {
        return;
    }
    let profile = [
        Profile::Legacy,
        Profile::Rng19Rfl8Sig16Nir16,
        Profile::Rng19Rfl8Sig16Nir16Dual,
        Profile::Rng15Rfl8Nir8,
    ][usize::from(data[0] & 3)];
    let beams = [1usize, 2, 8, 16][usize::from(data[0] >> 2 & 3)];
    let angle = |b: u8| f64::from(b as i8) * 0.5;
    let mut m = [0.0; 16];
    (m[0], m[5], m[10], m[15], m[3]) = (1.0, 1.0, 1.0, 1.0, f64::from(data[3] / 2));
    let info = SensorInfo {
        profile,
        columns_per_frame: 64,
        columns_per_packet: 4,
        column_window: (u16::from(data[1] & 63), u16::from(data[2] & 63)),
        beam_altitude_deg: (0..beams)
            .map(|i| angle(data[1].wrapping_add(i as u8)))
            .collect(),
        beam_azimuth_deg: (0..beams)
            .map(|i| angle(data[2].wrapping_mul(i as u8)) / 2.0)
            .collect(),
        pixel_shift_by_row: Vec::new(),
        beam_to_lidar: m,
        lidar_to_sensor: m,
        initialization_id: (data[0] & 0x40 != 0).then_some(5),
        serial: None,
        // A rate of 1000 Hz or none: the column-spacing check both ways.
        frequency_hz: (data[0] & 0x80 != 0).then_some(1000),
    };
    let mut dec = Decoder::new(&info).expect("valid metadata");
    let len = info.layout().packet_len();
    let mut sink = sensor_sink::Checked::default();
    let mut rest = &data[4..];
    while let Some((&k, tail)) = rest.split_first() {
        let n = match k {
            0..=0xEF => len,
            _ => usize::from(k & 0x0F) * len / 8,
        };
        let (packet, tail) = tail.split_at(n.min(tail.len()));
        sensor_sink::feed(&mut sink, |s| dec.push(packet, s));
        rest = tail;
    }
    dec.finish(&mut sink);
});
