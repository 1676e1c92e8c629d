//! The Livox SDK 1 data packet (Mid-40, Mid-70, Horizon, Tele-15, Avia): an 18-byte header,
//! then the points of one data type, or one IMU sample. All fields little-endian.
//!
//! ```text
//! 0         version (5)
//! 1         slot id
//! 2         lidar id
//! 4..8      status code
//! 8         timestamp type (0 since power-on, 1 PTP, 2 reserved, 3 GPS UTC, 4 PPS)
//! 9         data type (below)
//! 10..18    timestamp of the first point: ns (types 0, 1, 2, 4); type 3: year - 2000, month,
//!           day, hour, then microseconds within the hour
//! 18..      points
//! ```
//!
//! | type | point | bytes | points |
//! |---|---|---|---|
//! | 0 | x, y, z (i32 mm), reflectivity | 13 | 100 |
//! | 1 | depth (u32 mm), zenith, azimuth (u16, 0.01 deg), reflectivity | 9 | 100 |
//! | 2 | x, y, z, reflectivity, tag | 14 | 96 |
//! | 3 | depth, zenith, azimuth, reflectivity, tag | 10 | 96 |
//! | 4 | two returns of x, y, z, reflectivity, tag | 28 | 48 |
//! | 5 | zenith, azimuth, two returns of depth, reflectivity, tag | 16 | 48 |
//! | 6 | IMU: gyroscope x, y, z (f32 rad/s), accelerometer x, y, z (f32 g) | 24 | 1 |

use super::{at, byte, spherical, u16_at, ImuSample, Return};
use crate::error::PacketError;

/// Byte ranges of the header.
pub mod field {
    use core::ops::Range;
    /// Protocol version.
    pub const VERSION: usize = 0;
    /// Slot id.
    pub const SLOT: usize = 1;
    /// Lidar id.
    pub const LIDAR: usize = 2;
    /// Status code.
    pub const STATUS: Range<usize> = 4..8;
    /// Timestamp type.
    pub const TIMESTAMP_TYPE: usize = 8;
    /// Data type.
    pub const DATA_TYPE: usize = 9;
    /// Timestamp of the first point.
    pub const TIMESTAMP: Range<usize> = 10..18;
    /// Where the points begin.
    pub const DATA: usize = 18;
}

/// Protocol version of SDK 1 data packets.
pub const VERSION: u8 = 5;
/// The IMU data type.
pub const IMU: u8 = 6;
/// The last timestamp type the protocol defines (4, PPS).
pub const LAST_TIMESTAMP_TYPE: u8 = 4;

/// Bytes per point and points per packet of a point data type.
pub const fn layout(data_type: u8) -> Option<(usize, usize)> {
    Some(match data_type {
        0 => (13, 100),
        1 => (9, 100),
        2 => (14, 96),
        3 => (10, 96),
        4 => (28, 48),
        5 => (16, 48),
        IMU => (24, 1),
        _ => return None,
    })
}

/// Bytes of a packet of a data type, header included.
pub const fn packet_len(data_type: u8) -> Option<usize> {
    match layout(data_type) {
        Some((size, count)) => Some(field::DATA + size * count),
        None => None,
    }
}

/// A checked view of a data packet: the version, data type and length agree, and the
/// timestamp is one this crate reads.
#[derive(Clone, Copy, Debug)]
pub struct Packet<'a> {
    buf: &'a [u8],
    size: usize,
    count: usize,
}

impl<'a> Packet<'a> {
    /// Checks version, data type, length and timestamp (a type the protocol defines, a UTC
    /// date that exists).
    pub fn new_checked(bytes: &'a [u8]) -> Result<Self, PacketError> {
        if bytes.len() < field::DATA {
            return Err(PacketError::Truncated);
        }
        if byte(bytes, field::VERSION) != VERSION {
            return Err(PacketError::Version);
        }
        let data_type = byte(bytes, field::DATA_TYPE);
        let (size, count) = layout(data_type).ok_or(PacketError::PacketType)?;
        let len = field::DATA + size * count;
        if bytes.len() != len {
            // The length of another data type's packet: the data type byte is wrong.
            if (0..=IMU).any(|t| packet_len(t) == Some(bytes.len())) {
                return Err(PacketError::PointsLength {
                    data_type,
                    points: u16::try_from(count).unwrap_or(u16::MAX),
                    len: u16::try_from(bytes.len()).unwrap_or(u16::MAX),
                });
            }
            return Err(if bytes.len() < len {
                PacketError::Truncated
            } else {
                PacketError::Length
            });
        }
        let p = Self {
            buf: bytes,
            size,
            count,
        };
        let kind = p.timestamp_type();
        if kind > LAST_TIMESTAMP_TYPE {
            return Err(PacketError::TimeType { kind });
        }
        if p.time_ns().is_none() {
            return Err(PacketError::DateTime);
        }
        Ok(p)
    }

    /// The data type.
    pub fn data_type(&self) -> u8 {
        byte(self.buf, field::DATA_TYPE)
    }
    /// Slot and lidar id: which sensor sent it.
    pub fn sender(&self) -> (u8, u8) {
        (byte(self.buf, field::SLOT), byte(self.buf, field::LIDAR))
    }
    /// The status code.
    pub fn status(&self) -> u32 {
        u32::from_le_bytes(at(self.buf, field::STATUS.start))
    }
    /// The timestamp type.
    pub fn timestamp_type(&self) -> u8 {
        byte(self.buf, field::TIMESTAMP_TYPE)
    }
    /// Firings in the packet (points, or pairs of returns for the dual types).
    pub fn firings(&self) -> usize {
        if self.data_type() == IMU {
            0
        } else {
            self.count
        }
    }
    /// Returns each firing reports: 2 for the dual types.
    pub fn returns(&self) -> usize {
        if matches!(self.data_type(), 4 | 5) {
            2
        } else {
            1
        }
    }
    /// Time of the first point, ns on the sensor's clock (UTC for GPS time, type 3); `None`
    /// for a UTC date that does not exist.
    pub fn time_ns(&self) -> Option<u64> {
        let raw: [u8; 8] = at(self.buf, field::TIMESTAMP.start);
        if self.timestamp_type() != 3 {
            return Some(u64::from_le_bytes(raw));
        }
        let (year, month, day, hour) = (2000 + i64::from(raw[0]), raw[1], raw[2], raw[3]);
        let us = u32::from_le_bytes([raw[4], raw[5], raw[6], raw[7]]);
        let days = crate::time::days_from_civil_checked(year, month, day)?;
        if hour > 23 || us >= 3_600_000_000 {
            return None;
        }
        let s = u64::try_from(days * 86_400 + i64::from(hour) * 3600).ok()?;
        s.checked_mul(1_000_000_000)?
            .checked_add(u64::from(us) * 1000)
    }
    /// Return `r` (0, or 1 for the dual types) of firing `k`.
    pub fn point(&self, k: usize, r: usize) -> Return {
        let base = field::DATA + k * self.size;
        let b = self.buf;
        let i32_at = |o: usize| f64::from(i32::from_le_bytes(at(b, base + o))) * 1e-3;
        let cartesian = |o: usize| {
            let xyz = [i32_at(o), i32_at(o + 4), i32_at(o + 8)];
            let tag = if self.data_type() == 0 {
                0
            } else {
                byte(b, base + o + 13)
            };
            (xyz != [0.0; 3]).then_some((xyz, byte(b, base + o + 12), tag))
        };
        // Offsets of the zenith (the azimuth follows it), depth, reflectivity and tag.
        let polar = |angles: usize, o: usize, refl: usize, tag: Option<usize>| {
            let depth = f64::from(u32::from_le_bytes(at(b, base + o))) * 1e-3;
            let zenith = f64::from(u16_at(b, base + angles)) * 0.01;
            let azimuth = f64::from(u16_at(b, base + angles + 2)) * 0.01;
            let tag = tag.map_or(0, |t| byte(b, base + t));
            (depth > 0.0).then_some((spherical(depth, zenith, azimuth), byte(b, base + refl), tag))
        };
        match (self.data_type(), r) {
            (0 | 2, 0) => cartesian(0),
            (4, 0) => cartesian(0),
            (4, 1) => cartesian(14),
            (1, 0) => polar(4, 0, 8, None),
            (3, 0) => polar(4, 0, 8, Some(9)),
            (5, 0) => polar(0, 4, 8, Some(9)),
            (5, 1) => polar(0, 10, 14, Some(15)),
            _ => None,
        }
    }
    /// The IMU sample of a data type 6 packet.
    pub fn imu(&self) -> Option<ImuSample> {
        if self.data_type() != IMU {
            return None;
        }
        Some(ImuSample::read(self.buf, field::DATA))
    }
}
