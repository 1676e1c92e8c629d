//! The fixed-layout point cloud packets of the Pandar40P, Pandar64, PandarQT64, PandarXT16,
//! PandarXT32M and PandarAT128: each model's [`Format`] names its header, block and tail byte
//! ranges, and [`Packet::new_checked`] checks a packet against the format it is decoded as,
//! so a packet of another model is refused with the reason. All fields little-endian.
//!
//! The layouts are those of TIER IV nebula's packet structs (`pandar_40.hpp`, `pandar_64.hpp`,
//! `pandar_qt64.hpp`, `pandar_xt16.hpp`, `pandar_xt32m.hpp`, `pandar_at128.hpp`, nebula commit
//! 606ac41f) and agree with the packets of nebula's recorded captures:
//!
//! ```text
//! model     header            blocks                    tail (from its start)              length
//! 40P       none              10 x FF EE|az|40 x 3 B    22: +8 rpm +10 us +14 mode +16 date 1262 (+4 seq)
//! 64        8: EE FF 64 6 . u 6 x az|64 x 3 B           22: as the 40P's                   1194 (+4 seq)
//! QT64      12: EE FF 3 1     4 x az|64 x 4 B           24: +10 rpm +12 us +16 mode +18 date 1072
//! XT16      12: EE FF 6 1     8 x az|16 x 4 B           24: +10 mode +11 rpm +13 date +19 us 568
//! XT32M     12: EE FF 6 1     6 x az|32 x 4 B           24: as the XT16's                  820
//! AT128     12: EE FF 4 3     2 x az|fine|128 x 4 B, CRC 40: +18 rpm +20 us +24 mode +26 s 1086 (+32 sig)
//! ```
//!
//! The 12-byte header is the XT32's ([`super::wire::field`]): version at 2 and 3, lasers at 6,
//! blocks at 7, distance unit (mm) at 9, returns at 10, flags at 11. The 8-byte header has the
//! lasers at 2, blocks at 3 and the distance unit at 5. The 40P has no header: its distance
//! unit is 4 mm (its manual; nebula's `get_dis_unit<Packet40P>`).

use super::wire::{byte, length_error, u16_at, u32_at, utc_ns, AZIMUTH_UNITS, START};
use crate::error::PacketError;

/// A packet's start bytes where it has a header.
pub const HEADER_START: [u8; 2] = START;
/// A 40P block's start bytes.
pub const BLOCK_START: [u8; 2] = [0xFF, 0xEE];

/// How the tail gives the packet's date.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Date {
    /// Year, month, day, hour, minute, second, the year counted from this year.
    Civil(u16),
    /// A zero byte, then seconds since the Unix epoch, 5 bytes big-endian (AT128: nebula's
    /// `SecondsSinceEpoch`); a nonzero first byte is the civil date of the other models, year
    /// counted from 1900 (Hesai's SDK 2.0, `HS_LIDAR_TAIL_ST_V3::GetMicroLidarTimeU64`).
    EpochSeconds,
}

/// The byte layout of one model's point cloud packet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Format {
    /// Header bytes: 0 (40P), 8 (Pandar64) or 12.
    pub header: usize,
    /// The 12-byte header's protocol version.
    pub version: (u8, u8),
    /// Lasers (channels) of a block.
    pub lasers: usize,
    /// Blocks of a packet.
    pub blocks: usize,
    /// Each block starts with [`BLOCK_START`] (40P).
    pub block_start: bool,
    /// The azimuth has a fine byte after it, 1/256 of its 0.01 degree (AT128).
    pub fine_azimuth: bool,
    /// Bytes of a channel unit: distance u16, reflectivity u8 and a reserved or confidence byte.
    pub unit_len: usize,
    /// A 4-byte CRC follows the blocks (AT128).
    pub body_crc: bool,
    /// Bytes of the tail up to its end or the UDP sequence number.
    pub tail_len: usize,
    /// Within the tail: motor speed, rpm.
    pub motor: usize,
    /// Within the tail: microseconds within the second of the date.
    pub micros: usize,
    /// Within the tail: the return mode byte.
    pub return_mode: usize,
    /// Within the tail: the date.
    pub date: usize,
    /// How the date is given.
    pub date_kind: Date,
    /// Bytes after the tail of the models without the 12-byte header's flags (40P, 64) and of
    /// the AT128: the lengths a packet may have beyond its fixed part, with whether a UDP
    /// sequence number is their first 4 bytes. The others' flags bit 0 says whether their
    /// 4-byte sequence number follows.
    pub extra: [(usize, bool); 2],
}

impl Format {
    /// Bytes of a block.
    pub const fn block_len(&self) -> usize {
        let lead = if self.block_start { 2 } else { 0 };
        let az = if self.fine_azimuth { 3 } else { 2 };
        lead + az + self.lasers * self.unit_len
    }
    /// Where block `k` begins.
    pub const fn block_at(&self, k: usize) -> usize {
        self.header + k * self.block_len()
    }
    /// Where the tail begins.
    pub const fn tail_at(&self) -> usize {
        let crc = if self.body_crc { 4 } else { 0 };
        self.block_at(self.blocks) + crc
    }
    /// The packet's length without the optional bytes.
    pub const fn fixed_len(&self) -> usize {
        self.tail_at() + self.tail_len
    }
    /// The length the sensor sends by default (with its sequence number where it has one).
    pub const fn default_len(&self) -> usize {
        self.fixed_len() + self.extra[0].0
    }
}

/// Pandar40P (nebula `Packet40P`, `Tail40P`: date year counted from 2000).
pub const PANDAR40P: Format = Format {
    header: 0,
    version: (0, 0),
    lasers: 40,
    blocks: 10,
    block_start: true,
    fine_azimuth: false,
    unit_len: 3,
    body_crc: false,
    tail_len: 22,
    motor: 8,
    micros: 10,
    return_mode: 14,
    date: 16,
    date_kind: Date::Civil(2000),
    extra: [(0, false), (4, true)],
};

/// Pandar64 (nebula `Packet64`, the 40P's tail). Its date's year counts from 1900: the
/// recorded capture's year byte is 120, 2020 (nebula's shared 40P tail reads it as 2120).
pub const PANDAR64: Format = Format {
    header: 8,
    version: (0, 0),
    lasers: 64,
    blocks: 6,
    block_start: false,
    fine_azimuth: false,
    unit_len: 3,
    body_crc: false,
    tail_len: 22,
    motor: 8,
    micros: 10,
    return_mode: 14,
    date: 16,
    date_kind: Date::Civil(1900),
    extra: [(4, true), (0, false)],
};

/// PandarQT64 (nebula `PacketQT64`, `TailQT64`), protocol 3.1.
pub const PANDARQT64: Format = Format {
    header: 12,
    version: (3, 1),
    lasers: 64,
    blocks: 4,
    block_start: false,
    fine_azimuth: false,
    unit_len: 4,
    body_crc: false,
    tail_len: 24,
    motor: 10,
    micros: 12,
    return_mode: 16,
    date: 18,
    date_kind: Date::Civil(1900),
    extra: [(4, true), (4, true)],
};

/// PandarXT16 (nebula `PacketXT16`, the XT32's tail), protocol 6.1.
pub const PANDARXT16: Format = Format {
    header: 12,
    version: (6, 1),
    lasers: 16,
    blocks: 8,
    block_start: false,
    fine_azimuth: false,
    unit_len: 4,
    body_crc: false,
    tail_len: 24,
    motor: 11,
    micros: 19,
    return_mode: 10,
    date: 13,
    date_kind: Date::Civil(1900),
    extra: [(4, true), (4, true)],
};

/// PandarXT32M (nebula `PacketXT32M2X`, the XT32's tail), protocol 6.1, six blocks.
pub const PANDARXT32M: Format = Format {
    blocks: 6,
    lasers: 32,
    ..PANDARXT16
};

/// PandarAT128E2X (nebula `PacketAT128E2X`, `TailAT128E2X`), protocol 4.3: the tail runs to
/// its sequence number and CRC (40 bytes); a 32-byte signature may follow.
pub const PANDARAT128: Format = Format {
    header: 12,
    version: (4, 3),
    lasers: 128,
    blocks: 2,
    block_start: false,
    fine_azimuth: true,
    unit_len: 4,
    body_crc: true,
    tail_len: 40,
    motor: 18,
    micros: 20,
    return_mode: 24,
    date: 26,
    date_kind: Date::EpochSeconds,
    extra: [(0, false), (32, false)],
};

/// Within the AT128 tail: the UDP sequence number.
pub const AT128_SEQUENCE: usize = 32;

/// A checked view of a fixed-layout packet: the length, header, block starts, azimuths and
/// time were validated by [`Packet::new_checked`]; every accessor reads within the packet.
#[derive(Clone, Copy, Debug)]
pub struct Packet<'a> {
    buf: &'a [u8],
    format: &'static Format,
    sequence: bool,
}

impl<'a> Packet<'a> {
    /// Checks `bytes` as a packet of `format`: its length, header (version, lasers, blocks, a
    /// distance unit), block starts, azimuths and date.
    pub fn new_checked(format: &'static Format, bytes: &'a [u8]) -> Result<Self, PacketError> {
        let f = format;
        if bytes.len() < f.header.max(2) {
            return Err(PacketError::Truncated);
        }
        // The 40P has no header: its first bytes are block 0's flag, checked with the others'.
        // A packet with a header's start bytes is another model's.
        let start = bytes.get(..2) == Some(&HEADER_START[..]);
        if start != (f.header > 0) {
            return Err(PacketError::StartBytes);
        }
        match f.header {
            12 => {
                if (byte(bytes, 2), byte(bytes, 3)) != f.version {
                    return Err(PacketError::Version);
                }
                if (usize::from(byte(bytes, 6)), usize::from(byte(bytes, 7)))
                    != (f.lasers, f.blocks)
                {
                    return Err(PacketError::Header);
                }
            }
            8 if (usize::from(byte(bytes, 2)), usize::from(byte(bytes, 3)))
                != (f.lasers, f.blocks) =>
            {
                return Err(PacketError::Header);
            }
            _ => {}
        }
        let sequence = if f.header == 12 && !f.fine_azimuth {
            // Protocols 3.1 and 6.1: flags bit 0 announces the sequence number, as the XT32's.
            let flags = byte(bytes, 11);
            let seq = flags & 1 != 0;
            let (len, other) = if seq {
                (f.fixed_len() + 4, f.fixed_len())
            } else {
                (f.fixed_len(), f.fixed_len() + 4)
            };
            if bytes.len() != len {
                return Err(length_error(flags, len, bytes.len(), bytes.len() == other));
            }
            seq
        } else {
            let extra = bytes.len().checked_sub(f.fixed_len());
            match extra {
                None => return Err(PacketError::Truncated),
                Some(n) => match f.extra.iter().find(|(len, _)| *len == n) {
                    Some((_, seq)) => *seq,
                    None => return Err(PacketError::Length),
                },
            }
        };
        let p = Self {
            buf: bytes,
            format,
            sequence,
        };
        if p.distance_unit_mm() == 0 {
            return Err(PacketError::Header);
        }
        for k in 0..f.blocks {
            let at = f.block_at(k);
            if f.block_start && bytes.get(at..at + 2) != Some(&BLOCK_START[..]) {
                return Err(PacketError::BlockFlag);
            }
            if p.azimuth(k) >= AZIMUTH_UNITS {
                return Err(PacketError::Azimuth);
            }
        }
        if p.unix_ns().is_none() {
            return Err(PacketError::DateTime);
        }
        Ok(p)
    }

    /// The format the packet was checked as.
    pub fn format(&self) -> &'static Format {
        self.format
    }
    /// Millimetres per distance unit: the header's, 4 for the 40P.
    pub fn distance_unit_mm(&self) -> u8 {
        match self.format.header {
            12 => byte(self.buf, 9),
            8 => byte(self.buf, 5),
            _ => 4,
        }
    }
    /// The 12-byte header's return count, if the packet has one.
    pub fn header_returns(&self) -> Option<u8> {
        (self.format.header == 12).then(|| byte(self.buf, 10))
    }
    fn azimuth_at(&self, k: usize) -> usize {
        self.format.block_at(k) + if self.format.block_start { 2 } else { 0 }
    }
    /// Block `k`'s azimuth in hundredths of a degree (below 36000 after `new_checked`).
    pub fn azimuth(&self, k: usize) -> u16 {
        u16_at(self.buf, self.azimuth_at(k))
    }
    /// Block `k`'s azimuth in 1/25600 degree: the fine byte below the hundredths (AT128), or
    /// the hundredths times 256.
    pub fn fine_azimuth(&self, k: usize) -> u32 {
        let fine = if self.format.fine_azimuth {
            byte(self.buf, self.azimuth_at(k) + 2)
        } else {
            0
        };
        (u32::from(self.azimuth(k)) << 8) | u32::from(fine)
    }
    /// Block `k`, channel `c` (from 0): raw distance (distance units) and reflectivity.
    pub fn channel(&self, k: usize, c: usize) -> (u16, u8) {
        let az = if self.format.fine_azimuth { 3 } else { 2 };
        let at = self.azimuth_at(k) + az + c * self.format.unit_len;
        (u16_at(self.buf, at), byte(self.buf, at + 2))
    }
    fn tail(&self, at: usize) -> usize {
        self.format.tail_at() + at
    }
    /// The return-mode byte.
    pub fn return_mode(&self) -> u8 {
        byte(self.buf, self.tail(self.format.return_mode))
    }
    /// Motor speed, rpm.
    pub fn motor_rpm(&self) -> u16 {
        u16_at(self.buf, self.tail(self.format.motor))
    }
    /// The UDP sequence number, if the packet carries one.
    pub fn udp_sequence(&self) -> Option<u32> {
        if self.format.date_kind == Date::EpochSeconds {
            return Some(u32_at(self.buf, self.tail(AT128_SEQUENCE)));
        }
        self.sequence
            .then(|| u32_at(self.buf, self.format.fixed_len()))
    }
    /// The packet time (UTC, ns since the Unix epoch), `None` for a date that does not exist
    /// or microseconds beyond the second.
    pub fn unix_ns(&self) -> Option<u64> {
        let us = u32_at(self.buf, self.tail(self.format.micros));
        let at = self.tail(self.format.date);
        let date = self.buf.get(at..at + 6)?;
        match self.format.date_kind {
            Date::Civil(1900) => utc_ns(date, us),
            Date::Civil(base) => {
                // Re-base the year on 1900 for `utc_ns`; a year past 2155 does not fit.
                let year =
                    u8::try_from(u16::from(*date.first()?) + base.checked_sub(1900)?).ok()?;
                let mut d = [0u8; 6];
                d.copy_from_slice(date);
                d[0] = year;
                utc_ns(&d, us)
            }
            Date::EpochSeconds if date[0] != 0 => utc_ns(date, us),
            Date::EpochSeconds => {
                if us >= 1_000_000 {
                    return None;
                }
                let s = date[1..].iter().fold(0u64, |s, &b| (s << 8) | u64::from(b));
                s.checked_mul(1_000_000_000)?
                    .checked_add(u64::from(us) * 1000)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_of_the_recorded_packets() {
        // The lengths of the packets in nebula's captures.
        assert_eq!(PANDAR40P.fixed_len(), 1262);
        assert_eq!(PANDAR64.fixed_len() + 4, 1198);
        assert_eq!(PANDARQT64.fixed_len() + 4, 1072);
        assert_eq!(PANDARXT16.fixed_len() + 4, 568);
        assert_eq!(PANDARXT32M.fixed_len() + 4, 820);
        // AT128E2X: 12 + 2 x 515 + 4 + 40, and with its signature.
        assert_eq!(PANDARAT128.fixed_len(), 1086);
        assert_eq!(PANDARAT128.fixed_len() + 32, 1118);
    }

    #[test]
    fn a_packet_of_another_model_is_refused_with_the_reason() {
        let mut xt16 = [0u8; 568];
        xt16[..12].copy_from_slice(&[0xEE, 0xFF, 6, 1, 0, 0, 16, 8, 1, 4, 1, 1]);
        xt16[540 + 13..540 + 19].copy_from_slice(&[124, 1, 2, 3, 4, 5]);
        assert!(Packet::new_checked(&PANDARXT16, &xt16).is_ok());
        // As an XT32M: the header's lasers and blocks are the XT16's.
        assert_eq!(
            Packet::new_checked(&PANDARXT32M, &xt16).unwrap_err(),
            PacketError::Header
        );
        assert_eq!(
            Packet::new_checked(&PANDARQT64, &xt16).unwrap_err(),
            PacketError::Version
        );
        assert_eq!(
            Packet::new_checked(&PANDAR40P, &xt16).unwrap_err(),
            PacketError::StartBytes
        );
        assert_eq!(
            Packet::new_checked(&PANDARXT16, &xt16[..567]).unwrap_err(),
            PacketError::Truncated
        );
    }
}
