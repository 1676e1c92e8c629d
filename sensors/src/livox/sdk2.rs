//! The Livox SDK 2 data packet (Mid-360, HAP): a 36-byte header, then the points of one data
//! type, or one IMU sample. All fields little-endian (Livox "Communication Protocol", Mid-360
//! and HAP editions, "Point Cloud & IMU Data Protocol").
//!
//! ```text
//! 0         version (0)
//! 1..3      length: the whole datagram, header included
//! 3..5      time_interval: the packet's points span this, 0.1 us
//! 5..7      dot_num: points in the packet
//! 7..9      udp_cnt: packet counter
//! 9         frame_cnt (not used by non-repetitive scans)
//! 10        data type (below)
//! 11        time type (0 since power-on, 1 gPTP/PTP, 2 GPS; all ns)
//! 12..24    reserved (pack_info)
//! 24..28    CRC-32 of bytes 28.. (timestamp and data)
//! 28..36    timestamp of the first point, ns
//! 36..      points
//! ```
//!
//! | type | point | bytes |
//! |---|---|---|
//! | 0 | IMU: gyroscope x, y, z (f32 rad/s), accelerometer x, y, z (f32 g) | 24 |
//! | 1 | x, y, z (i32 mm), reflectivity, tag | 14 |
//! | 2 | x, y, z (i16, 10 mm), reflectivity, tag | 8 |
//! | 3 | depth (u32 mm), zenith, azimuth (u16, 0.01 deg), reflectivity, tag | 10 |
//! | 0x11 | two returns of x, y, z (i32 mm), reflectivity, tag | 28 |
//!
//! The CRC is the common CRC-32 (polynomial 0x04C11DB7 reflected, initial value and final
//! XOR 0xFFFFFFFF), as the protocol's "CRC Algorithm" section gives it.

use super::{at, byte, spherical, u16_at, ImuSample, Return};
use crate::error::PacketError;

/// Byte ranges of the header.
pub mod field {
    use core::ops::Range;
    /// Protocol version.
    pub const VERSION: usize = 0;
    /// Length of the datagram.
    pub const LENGTH: Range<usize> = 1..3;
    /// Time the packet's points span, 0.1 us.
    pub const TIME_INTERVAL: Range<usize> = 3..5;
    /// Points in the packet.
    pub const DOT_NUM: Range<usize> = 5..7;
    /// Packet counter.
    pub const UDP_CNT: Range<usize> = 7..9;
    /// Frame counter.
    pub const FRAME_CNT: usize = 9;
    /// Data type.
    pub const DATA_TYPE: usize = 10;
    /// Timestamp type.
    pub const TIME_TYPE: usize = 11;
    /// CRC-32 of the timestamp and the points.
    pub const CRC32: Range<usize> = 24..28;
    /// Timestamp of the first point, ns.
    pub const TIMESTAMP: Range<usize> = 28..36;
    /// Where the points begin.
    pub const DATA: usize = 36;
}

/// Protocol version of SDK 2 data packets.
pub const VERSION: u8 = 0;
/// The IMU data type.
pub const IMU: u8 = 0;
/// The dual-return Cartesian data type.
pub const DUAL: u8 = 0x11;
/// The last time type the protocol defines (2, GPS).
pub const LAST_TIME_TYPE: u8 = 2;
/// Points the Mid-360 sends in a packet.
pub const MID360_POINTS: usize = 96;

/// Bytes per point of a data type.
pub const fn point_size(data_type: u8) -> Option<usize> {
    Some(match data_type {
        IMU => 24,
        1 => 14,
        2 => 8,
        3 => 10,
        DUAL => 28,
        _ => return None,
    })
}

/// Bytes of a packet of a data type holding `points` points, header included.
pub const fn packet_len(data_type: u8, points: usize) -> Option<usize> {
    match point_size(data_type) {
        Some(size) => Some(field::DATA + size * points),
        None => None,
    }
}

const CRC_TABLE: [u32; 256] = {
    let mut table = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
            k += 1;
        }
        table[i] = c;
        i += 1;
    }
    table
};

/// CRC-32 of `bytes` (the common one: zlib's, Ethernet's).
pub fn crc32(bytes: &[u8]) -> u32 {
    !bytes.iter().fold(!0u32, |c, &b| {
        CRC_TABLE[usize::from((c as u8) ^ b)] ^ (c >> 8)
    })
}

/// A checked view of a data packet: version, data type, `dot_num`, length field and datagram
/// length agree, the CRC holds, the time type is one this crate reads and a point packet's
/// points span a time (`time_interval` above 0). The CRC does not cover the header, so its
/// fields are checked against each other.
#[derive(Clone, Copy, Debug)]
pub struct Packet<'a> {
    buf: &'a [u8],
}

impl<'a> Packet<'a> {
    /// Checks version, data type, lengths, CRC, time type and point interval, in that order.
    pub fn new_checked(bytes: &'a [u8]) -> Result<Self, PacketError> {
        if bytes.len() < field::DATA {
            return Err(PacketError::Truncated);
        }
        if byte(bytes, field::VERSION) != VERSION {
            return Err(PacketError::Version);
        }
        let data_type = byte(bytes, field::DATA_TYPE);
        let dot_num = u16_at(bytes, field::DOT_NUM.start);
        let len = packet_len(data_type, usize::from(dot_num)).ok_or(PacketError::PacketType)?;
        let stated = u16_at(bytes, field::LENGTH.start);
        if data_type == IMU && dot_num != 1 {
            return Err(PacketError::ImuPoints { dot_num });
        }
        if usize::from(stated) != len {
            // The length field and the datagram agree: the data type or `dot_num` is wrong.
            if usize::from(stated) == bytes.len() {
                return Err(PacketError::PointsLength {
                    data_type,
                    points: dot_num,
                    len: stated,
                });
            }
            return Err(PacketError::LengthField {
                stated,
                expected: u16::try_from(len).unwrap_or(u16::MAX),
            });
        }
        if bytes.len() < len {
            return Err(PacketError::Truncated);
        }
        if bytes.len() > len {
            return Err(PacketError::Length);
        }
        let crc = u32::from_le_bytes(at(bytes, field::CRC32.start));
        if crc32(&bytes[field::TIMESTAMP.start..]) != crc {
            return Err(PacketError::Checksum);
        }
        let kind = byte(bytes, field::TIME_TYPE);
        if kind > LAST_TIME_TYPE {
            return Err(PacketError::TimeType { kind });
        }
        if data_type != IMU && u16_at(bytes, field::TIME_INTERVAL.start) == 0 {
            return Err(PacketError::PointInterval);
        }
        Ok(Self { buf: bytes })
    }

    /// The data type.
    pub fn data_type(&self) -> u8 {
        byte(self.buf, field::DATA_TYPE)
    }
    /// The timestamp type.
    pub fn time_type(&self) -> u8 {
        byte(self.buf, field::TIME_TYPE)
    }
    /// The packet counter: one more on each packet the sensor sends.
    pub fn udp_cnt(&self) -> u16 {
        u16_at(self.buf, field::UDP_CNT.start)
    }
    /// The frame counter.
    pub fn frame_cnt(&self) -> u8 {
        byte(self.buf, field::FRAME_CNT)
    }
    /// Firings in the packet (points, or pairs of returns for the dual type).
    pub fn firings(&self) -> usize {
        if self.data_type() == IMU {
            0
        } else {
            usize::from(u16_at(self.buf, field::DOT_NUM.start))
        }
    }
    /// Returns each firing reports: 2 for the dual type.
    pub fn returns(&self) -> usize {
        if self.data_type() == DUAL {
            2
        } else {
            1
        }
    }
    /// Time the packet's points span, ns: `time_interval`.
    pub fn span_ns(&self) -> f64 {
        f64::from(u16_at(self.buf, field::TIME_INTERVAL.start)) * 100.0
    }
    /// Time from one firing to the next, ns: the span over the points, as the Livox ROS
    /// driver spaces them.
    pub fn firing_ns(&self) -> f64 {
        match self.firings() {
            0 => 0.0,
            n => self.span_ns() / n as f64,
        }
    }
    /// Time of the first point, ns on the sensor's clock.
    pub fn time_ns(&self) -> u64 {
        u64::from_le_bytes(at(self.buf, field::TIMESTAMP.start))
    }
    /// Return `r` (0, or 1 for the dual type) of firing `k`.
    pub fn point(&self, k: usize, r: usize) -> Return {
        let size = point_size(self.data_type())?;
        let base = field::DATA + k * size;
        let b = self.buf;
        let i32_at = |o: usize| f64::from(i32::from_le_bytes(at(b, base + o))) * 1e-3;
        let i16_at = |o: usize| f64::from(i16::from_le_bytes(at(b, base + o))) * 1e-2;
        let seen = |xyz: [f64; 3], o: usize| {
            (xyz != [0.0; 3]).then_some((xyz, byte(b, base + o), byte(b, base + o + 1)))
        };
        match (self.data_type(), r) {
            (1 | DUAL, 0) => seen([i32_at(0), i32_at(4), i32_at(8)], 12),
            (DUAL, 1) => seen([i32_at(14), i32_at(18), i32_at(22)], 26),
            (2, 0) => seen([i16_at(0), i16_at(2), i16_at(4)], 6),
            (3, 0) => {
                let depth = f64::from(u32::from_le_bytes(at(b, base))) * 1e-3;
                let zenith = f64::from(u16_at(b, base + 4)) * 0.01;
                let azimuth = f64::from(u16_at(b, base + 6)) * 0.01;
                let xyz = spherical(depth, zenith, azimuth);
                (depth > 0.0).then_some((xyz, byte(b, base + 8), byte(b, base + 9)))
            }
            _ => None,
        }
    }
    /// The IMU sample of a data type 0 packet.
    pub fn imu(&self) -> Option<ImuSample> {
        if self.data_type() != IMU {
            return None;
        }
        Some(ImuSample::read(self.buf, field::DATA))
    }
}
