//! The Ouster sensor and packets the tests decode: a small low-bandwidth sensor, 2 beams and
//! 64 columns, 16 a packet.

use kiss_odom_sensors::ouster::{Profile, SensorInfo};

/// A small Ouster: 2 beams, 64 columns, 16 a packet, low-bandwidth profile.
pub fn small_ouster() -> SensorInfo {
    let mut identity = [0.0; 16];
    (identity[0], identity[5], identity[10], identity[15]) = (1.0, 1.0, 1.0, 1.0);
    SensorInfo {
        profile: Profile::Rng15Rfl8Nir8,
        columns_per_frame: 64,
        columns_per_packet: 16,
        column_window: (0, 63),
        beam_altitude_deg: heapless_from(&[10.0, -10.0]),
        beam_azimuth_deg: heapless_from(&[0.0, 0.0]),
        pixel_shift_by_row: heapless_from(&[4, 0]),
        beam_to_lidar: identity,
        lidar_to_sensor: identity,
        initialization_id: Some(77),
        serial: Some(1234),
        frequency_hz: None,
    }
}

fn heapless_from<T: Copy>(v: &[T]) -> kiss_odom_sensors::heapless::Vec<T, 128> {
    kiss_odom_sensors::heapless::Vec::from_slice(v).unwrap()
}

/// Packet `k` (columns 16k..16k+16) of frame `fid`: column m at 100 us x m, ranges 8 m.
pub fn ouster_packet(fid: u16, k: u16, serial: u64) -> Vec<u8> {
    let mut b = vec![0u8; 32 + 16 * (12 + 2 * 4) + 32];
    b[0] = 1;
    b[2..4].copy_from_slice(&fid.to_le_bytes());
    b[4..7].copy_from_slice(&77u32.to_le_bytes()[..3]);
    b[7..12].copy_from_slice(&serial.to_le_bytes()[..5]);
    for i in 0..16u16 {
        let m = 16 * k + i;
        let at = 32 + usize::from(i) * 20;
        let ts = 5_000_000_000u64 + u64::from(fid) * 100_000_000 + u64::from(m) * 100_000;
        b[at..at + 8].copy_from_slice(&ts.to_le_bytes());
        b[at + 8..at + 10].copy_from_slice(&m.to_le_bytes());
        b[at + 10] = 1; // valid
        for u in 0..2 {
            b[at + 12 + 4 * u..at + 14 + 4 * u].copy_from_slice(&1000u16.to_le_bytes());
        }
    }
    b
}
