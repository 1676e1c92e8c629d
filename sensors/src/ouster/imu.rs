//! Ouster IMU packets (`udp_profile_imu` `LEGACY`, sent to `udp_port_imu`, 7503 by default):
//! 48 bytes, little-endian, as the firmware user manual lays them out.
//!
//! ```text
//! 0..8      diagnostic system time, ns
//! 8..16     accelerometer read time, ns
//! 16..24    gyroscope read time, ns
//! 24..36    acceleration x, y, z (f32, g)
//! 36..48    angular velocity x, y, z (f32, deg/s)
//! ```

use crate::error::PacketError;

/// Byte ranges of the packet.
pub mod field {
    use core::ops::Range;
    /// Diagnostic system time, ns.
    pub const SYS_TS: Range<usize> = 0..8;
    /// Accelerometer read time, ns.
    pub const ACCEL_TS: Range<usize> = 8..16;
    /// Gyroscope read time, ns.
    pub const GYRO_TS: Range<usize> = 16..24;
    /// Acceleration x, y, z (f32, g).
    pub const ACCEL: Range<usize> = 24..36;
    /// Angular velocity x, y, z (f32, deg/s).
    pub const GYRO: Range<usize> = 36..48;
    /// Packet length.
    pub const LEN: usize = 48;
}

/// A checked IMU packet: exactly [`field::LEN`] bytes.
#[derive(Clone, Copy, Debug)]
pub struct ImuPacket<'a> {
    buf: &'a [u8; field::LEN],
}

impl<'a> ImuPacket<'a> {
    /// Checks the length.
    pub fn new_checked(bytes: &'a [u8]) -> Result<Self, PacketError> {
        match bytes.try_into() {
            Ok(buf) => Ok(Self { buf }),
            Err(_) if bytes.len() < field::LEN => Err(PacketError::Truncated),
            Err(_) => Err(PacketError::Length),
        }
    }

    /// `N` bytes from `from` (the offsets are the constants above, inside the packet).
    fn at<const N: usize>(&self, from: usize) -> [u8; N] {
        let mut out = [0u8; N];
        if let Some(s) = self.buf.get(from..from + N) {
            out.copy_from_slice(s);
        }
        out
    }

    fn u64_at(&self, from: usize) -> u64 {
        u64::from_le_bytes(self.at(from))
    }

    fn f32s(&self, from: usize) -> [f32; 3] {
        core::array::from_fn(|i| f32::from_le_bytes(self.at(from + 4 * i)))
    }

    /// Diagnostic system time, ns.
    pub fn sys_ts(&self) -> u64 {
        self.u64_at(field::SYS_TS.start)
    }
    /// Accelerometer read time, ns (the sensor's clock, as the lidar columns' timestamps).
    pub fn accel_ts(&self) -> u64 {
        self.u64_at(field::ACCEL_TS.start)
    }
    /// Gyroscope read time, ns.
    pub fn gyro_ts(&self) -> u64 {
        self.u64_at(field::GYRO_TS.start)
    }
    /// Acceleration, in g as the sensor sends it.
    pub fn accel_g(&self) -> [f32; 3] {
        self.f32s(field::ACCEL.start)
    }
    /// Angular velocity, degrees a second as the sensor sends it.
    pub fn gyro_deg_s(&self) -> [f32; 3] {
        self.f32s(field::GYRO.start)
    }
}
