//! The Hesai point cloud packets of UDP protocols 3.2 (PandarQT128) and 1.4 (Pandar128,
//! OT128). Both begin with the same 12-byte header; its flags byte says which optional parts
//! follow, so the layout is computed from the header and the length checked against it. All
//! fields little-endian.
//!
//! ```text
//! 0..2      start of packet, EE FF
//! 2, 3      protocol version: 3.2 or 1.4
//! 6         lasers (128)
//! 7         blocks (2)
//! 9         distance unit, mm (4)
//! 10        returns (1 single, 2 dual)
//! 11        flags: bit 0 UDP sequence, 1 IMU (1.4 only), 2 functional safety,
//!           3 signature, 4 confidence byte (1.4: bit 5 weight, bit 6 light bytes too)
//! 12..      blocks: azimuth (0.01 deg) | lasers x (distance u16, reflectivity u8, [extra bytes])
//! +4        body CRC
//! +17       functional safety, when flagged
//! tail (26 bytes), from its start:
//!   +5      3.2: mode flag (bit 0: which firing loop comes first)
//!   +9..11  1.4: azimuth state, two bits a block from bit 15 down
//!   +11     1.4: operational state (0 high resolution, 1 shutdown, 2 standard, 3 energy saving)
//!   +12     return mode
//!   +13..15 motor speed, rpm
//!   +15..21 UTC date and time: year - 1900, month, day, hour, minute, second
//!   +21..25 microseconds in the second
//!   +25     factory information
//! then      UDP sequence u32 (when flagged), IMU 22 bytes (1.4, when flagged), tail CRC u32,
//!           signature 32 bytes (when flagged)
//! ```

use super::wire::{byte, length_error, u16_at, u32_at, utc_ns, AZIMUTH_UNITS, START};
use crate::error::PacketError;

/// Byte ranges and sizes shared by both protocols. The 12-byte header and a block's and a
/// channel unit's leading fields are the XT32's ([`super::wire::field`]).
pub mod field {
    pub use super::super::wire::field::{
        AZIMUTH, BLOCK_COUNT, BODY, DISTANCE, DISTANCE_UNIT, FLAGS, LASERS, REFLECTIVITY, RETURNS,
        START,
    };
    use core::ops::Range;
    /// Protocol version, major then minor.
    pub const VERSION: Range<usize> = 2..4;
    /// The body CRC after the blocks.
    pub const BODY_CRC_LEN: usize = 4;
    /// The functional safety part.
    pub const SAFETY_LEN: usize = 17;
    /// Within the tail: the 3.2 mode flag.
    pub const MODE_FLAG: usize = 5;
    /// Within the tail: the 1.4 azimuth states.
    pub const AZIMUTH_STATE: Range<usize> = 9..11;
    /// Within the tail: the 1.4 operational state.
    pub const OPERATIONAL_STATE: usize = 11;
    /// Within the tail: the return mode byte.
    pub const RETURN_MODE: usize = 12;
    /// Within the tail: motor speed, rpm.
    pub const MOTOR_SPEED: Range<usize> = 13..15;
    /// Within the tail: UTC date and time to the second.
    pub const DATE_TIME: Range<usize> = 15..21;
    /// Within the tail: microseconds within the second.
    pub const MICROSECONDS: Range<usize> = 21..25;
    /// The fixed part of the tail.
    pub const TAIL_LEN: usize = 26;
    /// The UDP sequence number.
    pub const SEQUENCE_LEN: usize = 4;
    /// The 1.4 IMU sample.
    pub const IMU_LEN: usize = 22;
    /// The tail CRC.
    pub const TAIL_CRC_LEN: usize = 4;
    /// The signature.
    pub const SIGNATURE_LEN: usize = 32;
}

/// Flag bits of the header.
pub mod flag {
    /// A UDP sequence number follows the tail.
    pub const SEQUENCE: u8 = 1;
    /// An IMU sample follows (protocol 1.4).
    pub const IMU: u8 = 2;
    /// The functional safety part follows the body.
    pub const SAFETY: u8 = 4;
    /// A 32-byte signature ends the packet.
    pub const SIGNATURE: u8 = 8;
    /// Each channel unit carries a confidence byte.
    pub const CONFIDENCE: u8 = 0x10;
    /// Protocol 1.4: each channel unit carries a weight factor byte.
    pub const WEIGHT: u8 = 0x20;
    /// Protocol 1.4: each channel unit carries an ambient light byte.
    pub const LIGHT: u8 = 0x40;
}

/// Protocol 3.2, the PandarQT128's.
pub const VERSION_QT: (u8, u8) = (3, 2);
/// Protocol 1.4, the Pandar128's and OT128's.
pub const VERSION_128: (u8, u8) = (1, 4);
/// Lasers of both protocols' sensors.
pub const LASERS: usize = 128;
/// Blocks in a packet of both.
pub const BLOCKS: usize = 2;

/// Where the parts of a packet lie, computed from its header (for readers and writers of
/// these packets alike).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Bytes of a channel unit: distance, reflectivity and the flagged extra bytes.
    pub unit_len: usize,
    /// Bytes of a block: its azimuth and the units.
    pub block_len: usize,
    /// Where the body CRC lies: the blocks end there.
    pub body_crc: usize,
    /// Where the tail begins, after the body CRC and the functional safety part if flagged.
    pub tail: usize,
    /// Where the UDP sequence number lies, if flagged.
    pub sequence: Option<usize>,
    /// Where the tail CRC lies: the tail, sequence number and IMU sample end there.
    pub tail_crc: usize,
    /// The packet's length.
    pub len: usize,
}

impl Layout {
    /// The layout of a packet of `version` with header `flags`.
    pub fn of(version: (u8, u8), flags: u8) -> Self {
        let has = |bit: u8| flags & bit != 0;
        let extra_unit_bytes = if version == VERSION_128 {
            [flag::CONFIDENCE, flag::WEIGHT, flag::LIGHT]
                .iter()
                .filter(|b| has(**b))
                .count()
        } else {
            usize::from(has(flag::CONFIDENCE))
        };
        let unit_len = 3 + extra_unit_bytes;
        let block_len = field::AZIMUTH.end + LASERS * unit_len;
        let body_crc = field::BODY + BLOCKS * block_len;
        let mut at = body_crc + field::BODY_CRC_LEN;
        if has(flag::SAFETY) {
            at += field::SAFETY_LEN;
        }
        let tail = at;
        at += field::TAIL_LEN;
        let sequence = has(flag::SEQUENCE).then_some(at);
        if has(flag::SEQUENCE) {
            at += field::SEQUENCE_LEN;
        }
        if version == VERSION_128 && has(flag::IMU) {
            at += field::IMU_LEN;
        }
        let tail_crc = at;
        at += field::TAIL_CRC_LEN;
        if has(flag::SIGNATURE) {
            at += field::SIGNATURE_LEN;
        }
        Self {
            unit_len,
            block_len,
            body_crc,
            tail,
            sequence,
            tail_crc,
            len: at,
        }
    }
}

/// CRC-32/MPEG-2 (polynomial 0x04C11DB7, not reflected, initial value all ones, no final XOR):
/// the body and tail CRCs of these packets.
pub fn crc32_mpeg2(bytes: &[u8]) -> u32 {
    bytes.iter().fold(!0u32, |c, &b| {
        (c << 8) ^ CRC_TABLE[usize::from((c >> 24) as u8 ^ b)]
    })
}

const CRC_TABLE: [u32; 256] = {
    let mut table = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = (i as u32) << 24;
        let mut k = 0;
        while k < 8 {
            c = if c & (1 << 31) != 0 {
                (c << 1) ^ 0x04C1_1DB7
            } else {
                c << 1
            };
            k += 1;
        }
        table[i] = c;
        i += 1;
    }
    table
};

/// Where the body and tail CRCs of a packet of `version` with header `flags` lie, and the
/// ranges they cover: `(covered, at)` for the body, then for the tail.
pub fn crc_ranges(version: (u8, u8), flags: u8) -> [(core::ops::Range<usize>, usize); 2] {
    Layout::of(version, flags).crc_ranges()
}

impl Layout {
    /// The body's and the tail's CRC: `(covered, at)` each.
    pub fn crc_ranges(&self) -> [(core::ops::Range<usize>, usize); 2] {
        [
            (field::BODY..self.body_crc, self.body_crc),
            (self.tail..self.tail_crc, self.tail_crc),
        ]
    }
}

/// The header's protocol version (major, minor).
fn version_of(b: &[u8]) -> (u8, u8) {
    (
        byte(b, field::VERSION.start),
        byte(b, field::VERSION.start + 1),
    )
}

/// The length of a packet of `version` with header `flags`.
pub fn packet_len(version: (u8, u8), flags: u8) -> usize {
    Layout::of(version, flags).len
}

/// A checked view of a protocol 3.2 or 1.4 point cloud packet: every accessor reads within
/// the packet, and the header, azimuths and time were validated by [`Packet::new_checked`].
#[derive(Clone, Copy, Debug)]
pub struct Packet<'a> {
    buf: &'a [u8],
    layout: Layout,
}

impl<'a> Packet<'a> {
    /// Checks the start bytes, version, layout, length, the body and tail CRCs, returns,
    /// azimuths and time.
    pub fn new_checked(bytes: &'a [u8]) -> Result<Self, PacketError> {
        if bytes.len() < field::BODY {
            return Err(PacketError::Truncated);
        }
        if bytes.get(field::START) != Some(&START[..]) {
            return Err(PacketError::StartBytes);
        }
        let version = version_of(bytes);
        if version != VERSION_QT && version != VERSION_128 {
            return Err(PacketError::Version);
        }
        let shape = (
            byte(bytes, field::LASERS),
            byte(bytes, field::BLOCK_COUNT),
            byte(bytes, field::DISTANCE_UNIT),
        );
        if shape != (LASERS as u8, BLOCKS as u8, 4) {
            return Err(PacketError::Header);
        }
        let flags = byte(bytes, field::FLAGS);
        let p = Self {
            buf: bytes,
            layout: Layout::of(version, flags),
        };
        if bytes.len() != p.layout.len {
            let other = (0..=u8::MAX).any(|f| Layout::of(version, f).len == bytes.len());
            return Err(length_error(flags, p.layout.len, bytes.len(), other));
        }
        if !p.crcs_hold() {
            return Err(PacketError::Checksum);
        }
        if !matches!(p.returns(), 1 | 2) {
            return Err(PacketError::ReturnCount {
                count: p.returns(),
                mode: p.return_mode(),
            });
        }
        if (0..BLOCKS).any(|k| p.azimuth(k) >= AZIMUTH_UNITS) {
            return Err(PacketError::Azimuth);
        }
        if p.unix_ns().is_none() {
            return Err(PacketError::DateTime);
        }
        Ok(p)
    }

    /// Whether the body CRC (over the blocks) and the tail CRC (over the tail, sequence number
    /// and IMU sample) match: CRC-32/MPEG-2, as a recorded QT128 computes them. Protocol 1.4
    /// has the same two (the Pandar128E3X manual: "CRC 1: CRC-32 checksum of the Body", "CRC
    /// 3: CRC-32 checksum of the Tail", the tail running from its first byte through the
    /// sequence number and IMU sample), of the same CRC (Hesai's SDK 2.0 computes every
    /// protocol's with one CRC-32/MPEG-2, `GeneralParser::CRCCalc`).
    fn crcs_hold(&self) -> bool {
        self.layout.crc_ranges().into_iter().all(|(covered, at)| {
            self.buf.get(covered).map(crc32_mpeg2) == Some(u32_at(self.buf, at))
        })
    }

    /// Protocol version (major, minor): [`VERSION_QT`] or [`VERSION_128`].
    pub fn version(&self) -> (u8, u8) {
        version_of(self.buf)
    }
    /// Returns a firing reports: 1 or 2 after `new_checked`.
    pub fn returns(&self) -> u8 {
        byte(self.buf, field::RETURNS)
    }
    fn block_at(&self, k: usize) -> usize {
        field::BODY + k * self.layout.block_len
    }
    /// Block `k`'s azimuth in hundredths of a degree (below 36000 after `new_checked`).
    pub fn azimuth(&self, k: usize) -> u16 {
        u16_at(self.buf, self.block_at(k) + field::AZIMUTH.start)
    }
    /// Block `k`, channel `c` (from 0): raw distance (distance units) and reflectivity.
    pub fn channel(&self, k: usize, c: usize) -> (u16, u8) {
        let at = self.block_at(k) + field::AZIMUTH.end + c * self.layout.unit_len;
        (
            u16_at(self.buf, at + field::DISTANCE.start),
            byte(self.buf, at + field::REFLECTIVITY),
        )
    }
    fn tail(&self, at: usize) -> u8 {
        byte(self.buf, self.layout.tail + at)
    }
    /// The return-mode byte.
    pub fn return_mode(&self) -> u8 {
        self.tail(field::RETURN_MODE)
    }
    /// Protocol 3.2's mode flag: bit 0 says which firing loop the packet's first firing uses.
    pub fn mode_flag(&self) -> u8 {
        self.tail(field::MODE_FLAG)
    }
    /// Protocol 1.4's operational state (0 high resolution, 2 standard, 3 energy saving).
    pub fn operational_state(&self) -> u8 {
        self.tail(field::OPERATIONAL_STATE)
    }
    /// Protocol 1.4: block `k`'s azimuth state (0 to 3), which picks its firing-time column.
    pub fn azimuth_state(&self, k: usize) -> u8 {
        let flags = u16_at(self.buf, self.layout.tail + field::AZIMUTH_STATE.start);
        ((flags >> (14 - 2 * (k as u32 & 7))) & 3) as u8
    }
    /// Motor speed, rpm.
    pub fn motor_rpm(&self) -> u16 {
        u16_at(self.buf, self.layout.tail + field::MOTOR_SPEED.start)
    }
    /// The UDP sequence number, if the packet carries one.
    pub fn udp_sequence(&self) -> Option<u32> {
        self.layout.sequence.map(|at| u32_at(self.buf, at))
    }
    /// The packet time (UTC, ns since the Unix epoch), `None` for a date that does not exist
    /// or microseconds beyond the second.
    pub fn unix_ns(&self) -> Option<u64> {
        let t = self.layout.tail;
        let d = self
            .buf
            .get(t + field::DATE_TIME.start..t + field::DATE_TIME.end)?;
        utc_ns(d, u32_at(self.buf, t + field::MICROSECONDS.start))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_crc_is_crc_32_mpeg_2() {
        // The catalogue's check value for "123456789".
        assert_eq!(crc32_mpeg2(b"123456789"), 0x0376_E6E7);
        assert_eq!(crc32_mpeg2(b""), u32::MAX);
        // QT128C2X with everything flagged: the body's CRC after the blocks, the tail's after
        // the sequence number, then the signature.
        let [(body, at), (tail, tail_at)] = crc_ranges(VERSION_QT, 0x1D);
        assert_eq!((body, at), (12..12 + 2 * 514, 1040));
        assert_eq!((tail, tail_at), (1061..1091, 1091));
        let [_, (tail, tail_at)] = crc_ranges(VERSION_128, 0x07);
        assert_eq!((tail, tail_at), (805..857, 857));
    }

    #[test]
    fn layouts_of_the_published_packet_sizes() {
        // QT128C2X with sequence, safety, signature and confidence: 1127 bytes.
        assert_eq!(packet_len(VERSION_QT, 0x1D), 1127);
        // Without the signature and the confidence byte.
        assert_eq!(packet_len(VERSION_QT, 0x05), 1127 - 32 - 2 * 128);
        // Pandar128E3X / OT128 with sequence, IMU and safety: 861 bytes.
        assert_eq!(packet_len(VERSION_128, 0x07), 861);
        assert_eq!(packet_len(VERSION_128, 0x0F), 893);
        // Protocol 1.4 counts the weight and light bytes; 3.2 has no such bits.
        assert_eq!(packet_len(VERSION_128, 0x77), 861 + 3 * 256);
        assert_eq!(packet_len(VERSION_QT, 0x65), packet_len(VERSION_QT, 0x05));
        // The IMU bit means nothing in protocol 3.2.
        assert_eq!(packet_len(VERSION_QT, 0x07), packet_len(VERSION_QT, 0x05));
    }
}
