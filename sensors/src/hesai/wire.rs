//! The Hesai point cloud packet of UDP protocol 6.1 (PandarXT-32): 1076 bytes of UDP payload,
//! 1080 with the UDP sequence number the header's flags announce. A 12-byte header, eight
//! 130-byte blocks, a 24-byte tail. All fields little-endian.
//!
//! ```text
//! 0..2      start of packet, EE FF
//! 2, 3      protocol version, major 6 and minor 1
//! 6         lasers (32)
//! 7         blocks (8)
//! 9         distance unit, mm (4)
//! 10        returns (1 single, 2 dual)
//! 11        flags: bit 0, a UDP sequence number follows the tail
//! block k (k = 0..8) at 12 + 130 k:  azimuth (0.01 deg) | 32 x (distance u16, reflectivity u8, reserved u8)
//! 1062      return mode (0x33 first, 0x37 strongest, 0x38 last; dual 0x39, 0x3B, 0x3C)
//! 1063..65  motor speed, rpm
//! 1065..71  UTC date and time: year - 1900, month, day, hour, minute, second
//! 1071..75  microseconds in the second
//! 1075      factory information
//! 1076..80  UDP sequence number (when flagged)
//! ```

use crate::error::PacketError;

/// Byte ranges of the packet.
pub mod field {
    use core::ops::Range;
    /// Start of packet, `EE FF`.
    pub const START: Range<usize> = 0..2;
    /// Protocol version, major.
    pub const VERSION_MAJOR: usize = 2;
    /// Protocol version, minor.
    pub const VERSION_MINOR: usize = 3;
    /// Lasers a block holds.
    pub const LASERS: usize = 6;
    /// Blocks in the packet.
    pub const BLOCK_COUNT: usize = 7;
    /// Millimetres per distance unit.
    pub const DISTANCE_UNIT: usize = 9;
    /// Returns a firing reports (1 or 2).
    pub const RETURNS: usize = 10;
    /// Flags; bit 0: a UDP sequence number follows the tail.
    pub const FLAGS: usize = 11;
    /// Where the blocks begin.
    pub const BODY: usize = 12;
    /// Blocks in a packet.
    pub const BLOCKS: usize = 8;
    /// Bytes of a block.
    pub const BLOCK_LEN: usize = 130;
    /// Channels (lasers) in a block.
    pub const CHANNELS: usize = 32;
    /// Bytes of a channel.
    pub const CHANNEL_LEN: usize = 4;
    /// Within a block: azimuth in hundredths of a degree.
    pub const AZIMUTH: Range<usize> = 0..2;
    /// Within a block: the channels.
    pub const DATA: Range<usize> = 2..130;
    /// Within a channel: distance in distance units; 0 means no return.
    pub const DISTANCE: Range<usize> = 0..2;
    /// Within a channel: reflectivity.
    pub const REFLECTIVITY: usize = 2;
    /// Return mode byte.
    pub const RETURN_MODE: usize = 1062;
    /// Motor speed, rpm.
    pub const MOTOR_SPEED: Range<usize> = 1063..1065;
    /// UTC date and time to the second: year - 1900, month, day, hour, minute, second.
    pub const DATE_TIME: Range<usize> = 1065..1071;
    /// Microseconds within the second of [`DATE_TIME`].
    pub const MICROSECONDS: Range<usize> = 1071..1075;
    /// UDP sequence number, when the flags say it is there.
    pub const UDP_SEQUENCE: Range<usize> = 1076..1080;
    /// The packet without the sequence number.
    pub const LEN: usize = 1076;
    /// The packet with the sequence number.
    pub const LEN_WITH_SEQUENCE: usize = 1080;
}

/// The start of packet bytes.
pub const START: [u8; 2] = [0xEE, 0xFF];
/// Protocol version decoded here (major, minor).
pub const VERSION: (u8, u8) = (6, 1);
/// Azimuth units per turn (hundredths of a degree).
pub const AZIMUTH_UNITS: u16 = 36000;
/// Flag bit: a UDP sequence number follows the tail.
pub const FLAG_UDP_SEQUENCE: u8 = 1;

/// A checked view of a point cloud packet: every accessor reads within the packet, and the
/// header, azimuths and time were validated by [`Packet::new_checked`].
#[derive(Clone, Copy, Debug)]
pub struct Packet<'a> {
    buf: &'a [u8],
}

pub(super) fn u16_at(b: &[u8], at: usize) -> u16 {
    match (b.get(at), b.get(at + 1)) {
        (Some(&lo), Some(&hi)) => u16::from_le_bytes([lo, hi]),
        _ => 0,
    }
}

pub(super) fn u32_at(b: &[u8], at: usize) -> u32 {
    match b.get(at..at + 4) {
        Some(&[a, b, c, d]) => u32::from_le_bytes([a, b, c, d]),
        _ => 0,
    }
}

pub(super) fn byte(b: &[u8], at: usize) -> u8 {
    b.get(at).copied().unwrap_or(0)
}

impl<'a> Packet<'a> {
    /// Checks the start bytes, version, layout, length, azimuths and time.
    pub fn new_checked(bytes: &'a [u8]) -> Result<Self, PacketError> {
        if bytes.len() < field::BODY {
            return Err(PacketError::Truncated);
        }
        let p = Self { buf: bytes };
        if bytes.get(field::START) != Some(&START[..]) {
            return Err(PacketError::StartBytes);
        }
        if p.version() != VERSION {
            return Err(PacketError::Version);
        }
        let layout = (
            byte(bytes, field::LASERS),
            byte(bytes, field::BLOCK_COUNT),
            byte(bytes, field::DISTANCE_UNIT),
        );
        if layout != (field::CHANNELS as u8, field::BLOCKS as u8, 4) {
            return Err(PacketError::Header);
        }
        let (len, other) = if p.flags() & FLAG_UDP_SEQUENCE != 0 {
            (field::LEN_WITH_SEQUENCE, field::LEN)
        } else {
            (field::LEN, field::LEN_WITH_SEQUENCE)
        };
        if bytes.len() != len {
            return Err(length_error(
                p.flags(),
                len,
                bytes.len(),
                bytes.len() == other,
            ));
        }
        if !matches!(p.returns(), 1 | 2) {
            return Err(PacketError::ReturnCount {
                count: p.returns(),
                mode: p.return_mode(),
            });
        }
        for k in 0..field::BLOCKS {
            if p.azimuth(k) >= AZIMUTH_UNITS {
                return Err(PacketError::Azimuth);
            }
        }
        if p.unix_ns().is_none() {
            return Err(PacketError::DateTime);
        }
        Ok(p)
    }

    /// Protocol version (major, minor).
    pub fn version(&self) -> (u8, u8) {
        (
            byte(self.buf, field::VERSION_MAJOR),
            byte(self.buf, field::VERSION_MINOR),
        )
    }
    /// Returns a firing reports: 1 or 2 after `new_checked`.
    pub fn returns(&self) -> u8 {
        byte(self.buf, field::RETURNS)
    }
    /// The header's flags.
    pub fn flags(&self) -> u8 {
        byte(self.buf, field::FLAGS)
    }
    fn block_at(k: usize) -> usize {
        field::BODY + k * field::BLOCK_LEN
    }
    /// Block `k`'s azimuth in hundredths of a degree (below 36000 after `new_checked`).
    pub fn azimuth(&self, k: usize) -> u16 {
        u16_at(self.buf, Self::block_at(k) + field::AZIMUTH.start)
    }
    /// Block `k`, channel `c`: raw distance (4 mm units) and reflectivity.
    pub fn channel(&self, k: usize, c: usize) -> (u16, u8) {
        let at = Self::block_at(k) + field::DATA.start + c * field::CHANNEL_LEN;
        let d = u16_at(self.buf, at + field::DISTANCE.start);
        (d, byte(self.buf, at + field::REFLECTIVITY))
    }
    /// The return-mode byte.
    pub fn return_mode(&self) -> u8 {
        byte(self.buf, field::RETURN_MODE)
    }
    /// Motor speed, rpm.
    pub fn motor_rpm(&self) -> u16 {
        u16_at(self.buf, field::MOTOR_SPEED.start)
    }
    /// The UDP sequence number, if the packet carries one.
    pub fn udp_sequence(&self) -> Option<u32> {
        (self.flags() & FLAG_UDP_SEQUENCE != 0).then(|| u32_at(self.buf, field::UDP_SEQUENCE.start))
    }
    /// The packet time (UTC, ns since the Unix epoch), `None` for a date that does not exist
    /// or microseconds beyond the second.
    pub fn unix_ns(&self) -> Option<u64> {
        let d = self.buf.get(field::DATE_TIME)?;
        utc_ns(d, u32_at(self.buf, field::MICROSECONDS.start))
    }
}

/// Why a packet of `len` bytes is refused where its header `flags` announce `announced`:
/// [`PacketError::HeaderFlags`] if `len` is a length the flags could announce (`other`: the
/// flags are what is wrong), else [`PacketError::Truncated`] or [`PacketError::Length`].
pub(super) fn length_error(flags: u8, announced: usize, len: usize, other: bool) -> PacketError {
    if other {
        PacketError::HeaderFlags {
            flags,
            announced: u16::try_from(announced).unwrap_or(u16::MAX),
            len: u16::try_from(len).unwrap_or(u16::MAX),
        }
    } else if len < announced {
        PacketError::Truncated
    } else {
        PacketError::Length
    }
}

/// A Hesai tail's time, ns since the Unix epoch: `date` is year - 1900, month, day, hour,
/// minute and second, `us` the microseconds within that second. `None` for a date that does
/// not exist or microseconds beyond the second.
pub(super) fn utc_ns(date: &[u8], us: u32) -> Option<u64> {
    let &[year, month, day, hour, minute, second] = date else {
        return None;
    };
    let days = crate::time::days_from_civil_checked(1900 + i64::from(year), month, day)?;
    if hour > 23 || minute > 59 || second > 60 || us >= 1_000_000 {
        return None;
    }
    let s = days * 86_400 + i64::from(hour) * 3600 + i64::from(minute) * 60 + i64::from(second);
    u64::try_from(s)
        .ok()?
        .checked_mul(1_000_000_000)?
        .checked_add(u64::from(us) * 1000)
}
