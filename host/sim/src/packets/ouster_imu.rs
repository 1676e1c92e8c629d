//! The OS1's IMU as the simulator sends it: one legacy 48-byte IMU packet per sample
//! (`udp_profile_imu` `LEGACY`, to the metadata's `udp_port_imu`), acceleration in g and
//! angular velocity in degrees a second as f32, the three read times in nanoseconds on the
//! clock the lidar columns are stamped with.

use crate::imu::{ImuSample, GRAVITY};
use kiss_odom_sensors::ouster::imu::field;

/// The packet of `sample`, read at `time_ns` on the sensor's clock.
pub fn packet(sample: &ImuSample, time_ns: u64) -> Vec<u8> {
    let mut buf = vec![0u8; field::LEN];
    for range in [field::SYS_TS, field::ACCEL_TS, field::GYRO_TS] {
        buf[range].copy_from_slice(&time_ns.to_le_bytes());
    }
    let accel = sample.accel.map(|a| a / GRAVITY);
    let gyro = sample.gyro.map(f64::to_degrees);
    for (range, v) in [(field::ACCEL, accel), (field::GYRO, gyro)] {
        for (bytes, x) in buf[range].chunks_exact_mut(4).zip(v) {
            bytes.copy_from_slice(&(x as f32).to_le_bytes());
        }
    }
    buf
}

#[cfg(test)]
mod tests {
    use super::*;
    use kiss_odom_sensors::ouster::ImuPacket;

    #[test]
    fn a_packet_decodes_to_its_sample_within_f32() {
        let sample = ImuSample {
            time: 12.345_678_901,
            gyro: [0.731, -2.25e-3, 4.5],
            accel: [-1.2, 0.034, 9.91],
        };
        let ns = 12_345_678_901;
        let bytes = packet(&sample, ns);
        let p = ImuPacket::new_checked(&bytes).unwrap();
        assert_eq!([p.sys_ts(), p.accel_ts(), p.gyro_ts()], [ns; 3]);
        let gyro = p.gyro_deg_s().map(|w| f64::from(w).to_radians());
        let accel = p.accel_g().map(|a| f64::from(a) * GRAVITY);
        crate::packets::tests::assert_imu_decodes_to(&sample, gyro, accel);
    }
}
