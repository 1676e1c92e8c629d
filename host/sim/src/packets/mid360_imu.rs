//! The Mid-360's IMU as the simulator sends it: one Livox SDK 2 datagram of the IMU data type
//! per sample (angular rate in rad/s, then acceleration in g, six f32), stamped in
//! nanoseconds on the clock the point packets are stamped with, to the host's IMU port.

use crate::imu::{ImuSample, GRAVITY};
use kiss_odom_sensors::livox::sdk2::{self, field};

/// The datagram of `sample`, the `count`th IMU packet, read at `time_ns` on the sensor's
/// clock.
pub fn packet(sample: &ImuSample, time_ns: u64, count: u64) -> Vec<u8> {
    let len = sdk2::packet_len(sdk2::IMU, 1).unwrap_or(field::DATA);
    let mut buf = vec![0u8; len];
    buf[field::VERSION] = sdk2::VERSION;
    buf[field::LENGTH].copy_from_slice(&(len as u16).to_le_bytes());
    buf[field::DOT_NUM].copy_from_slice(&1u16.to_le_bytes());
    buf[field::UDP_CNT].copy_from_slice(&(count as u16).to_le_bytes());
    buf[field::DATA_TYPE] = sdk2::IMU;
    buf[field::TIMESTAMP].copy_from_slice(&time_ns.to_le_bytes());
    let accel = sample.accel.map(|a| a / GRAVITY);
    let values = sample.gyro.iter().chain(&accel);
    for (bytes, x) in buf[field::DATA..].chunks_exact_mut(4).zip(values) {
        bytes.copy_from_slice(&(*x as f32).to_le_bytes());
    }
    let crc = sdk2::crc32(&buf[field::TIMESTAMP.start..]);
    buf[field::CRC32].copy_from_slice(&crc.to_le_bytes());
    buf
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_packet_decodes_to_its_sample_within_f32() {
        let sample = ImuSample {
            time: 7.000_123_456,
            gyro: [-0.731, 2.25e-3, 4.5],
            accel: [1.2, -0.034, 9.91],
        };
        let ns = 7_000_123_456;
        let bytes = packet(&sample, ns, 70_001);
        let p = sdk2::Packet::new_checked(&bytes).unwrap();
        assert_eq!(
            (p.time_ns(), p.udp_cnt(), p.firings()),
            (ns, (70_001u64 % 65_536) as u16, 0)
        );
        let s = p.imu().unwrap();
        let gyro = s.gyro.map(f64::from);
        let accel = s.accel_g.map(|a| f64::from(a) * GRAVITY);
        crate::packets::tests::assert_imu_decodes_to(&sample, gyro, accel);
    }
}
