//! The Velodyne data packet (every model decoded here): 1206 bytes of UDP payload, twelve
//! 100-byte blocks, then a timestamp and two factory bytes. All fields little-endian.
//!
//! ```text
//! block k (k = 0..12) at 100 k:  flag | azimuth (0.01 deg) | 32 x (distance u16, reflectivity u8)
//! 1200..1204  microseconds past the hour
//! 1204        return mode (0x37 strongest, 0x38 last, 0x39 dual); HDL-64E: status type
//! 1205        product id (0x21 HDL-32E, 0x22 VLP-16, 0x23 VLP-32A/B, 0x24 Puck Hi-Res,
//!             0x28 VLP-32C, 0xA1 VLS-128); HDL-64E: status value
//! ```
//!
//! The flag names the block's bank of 32 lasers: `FF EE` (lasers 0-31, the only one of the
//! 16- and 32-laser models), `FF DD` (32-63, the HDL-64E's lower block), `FF CC` and `FF BB`
//! (the VLS-128's third and fourth banks). A flag of zero marks a block the packet does not
//! use (the VLS-128's last four in dual-return mode); which blocks a model reads is its
//! layout's business.

use super::model::BANK_FLAGS;
use crate::error::PacketError;

/// Byte ranges of the packet.
pub mod field {
    use core::ops::Range;
    /// Data blocks in a packet.
    pub const BLOCKS: usize = 12;
    /// Bytes of a block.
    pub const BLOCK_LEN: usize = 100;
    /// Channels (distance, reflectivity) in a block.
    pub const CHANNELS: usize = 32;
    /// Bytes of a channel.
    pub const CHANNEL_LEN: usize = 3;
    /// Within a block: the flag, `0xFFEE` (bytes `FF EE`).
    pub const FLAG: Range<usize> = 0..2;
    /// Within a block: azimuth in hundredths of a degree.
    pub const AZIMUTH: Range<usize> = 2..4;
    /// Within a block: the channels.
    pub const DATA: Range<usize> = 4..100;
    /// Within a channel: distance in the model's unit (2 or 4 mm); 0 means no return.
    pub const DISTANCE: Range<usize> = 0..2;
    /// Within a channel: calibrated reflectivity.
    pub const REFLECTIVITY: usize = 2;
    /// Microseconds past the hour of the first firing of block 0.
    pub const TIMESTAMP: Range<usize> = 1200..1204;
    /// Return mode byte.
    pub const RETURN_MODE: usize = 1204;
    /// Product id byte.
    pub const PRODUCT: usize = 1205;
    /// Whole packet.
    pub const LEN: usize = 1206;
}

/// Block flag value of the first bank (little-endian `FF EE`).
pub const BLOCK_FLAG: u16 = 0xEEFF;
/// Flag of a block the packet leaves unused.
pub const UNUSED_FLAG: u16 = 0;
/// Azimuth units per turn (hundredths of a degree).
pub const AZIMUTH_UNITS: u16 = 36000;
/// Microseconds in the hour the timestamp counts.
pub const HOUR_US: u32 = 3_600_000_000;

/// A checked view of a data packet: every accessor reads within [`field::LEN`] bytes, and
/// flags, azimuths and timestamp were validated by [`Packet::new_checked`].
#[derive(Clone, Copy, Debug)]
pub struct Packet<'a> {
    buf: &'a [u8; field::LEN],
}

fn u16_at(b: &[u8], at: usize) -> u16 {
    match (b.get(at), b.get(at + 1)) {
        (Some(&lo), Some(&hi)) => u16::from_le_bytes([lo, hi]),
        _ => 0,
    }
}

impl<'a> Packet<'a> {
    /// Checks length, block flags, azimuths and the timestamp.
    pub fn new_checked(bytes: &'a [u8]) -> Result<Self, PacketError> {
        let buf: &[u8; field::LEN] = match bytes.try_into() {
            Ok(b) => b,
            Err(_) if bytes.len() < field::LEN => return Err(PacketError::Truncated),
            Err(_) => return Err(PacketError::Length),
        };
        let p = Self { buf };
        for k in 0..field::BLOCKS {
            let flag = p.flag(k);
            if flag == UNUSED_FLAG {
                continue;
            }
            if !BANK_FLAGS.contains(&flag) {
                return Err(PacketError::BlockFlag);
            }
            if p.azimuth(k) >= AZIMUTH_UNITS {
                return Err(PacketError::Azimuth);
            }
        }
        if p.timestamp_us() >= HOUR_US {
            return Err(PacketError::Timestamp);
        }
        Ok(p)
    }

    fn block_at(k: usize) -> usize {
        k * field::BLOCK_LEN
    }

    /// Block `k`'s flag.
    pub fn flag(&self, k: usize) -> u16 {
        u16_at(self.buf, Self::block_at(k) + field::FLAG.start)
    }
    /// Block `k`'s azimuth in hundredths of a degree (below 36000 after `new_checked`).
    pub fn azimuth(&self, k: usize) -> u16 {
        u16_at(self.buf, Self::block_at(k) + field::AZIMUTH.start)
    }
    /// Block `k`'s azimuth, or `None` past the last block.
    pub fn azimuth_checked(&self, k: usize) -> Option<u16> {
        (k < field::BLOCKS).then(|| self.azimuth(k))
    }
    /// Block `k`, channel `c`: raw distance and reflectivity.
    pub fn channel(&self, k: usize, c: usize) -> (u16, u8) {
        let at = Self::block_at(k) + field::DATA.start + c * field::CHANNEL_LEN;
        let d = u16_at(self.buf, at + field::DISTANCE.start);
        let r = self.buf.get(at + field::REFLECTIVITY).copied().unwrap_or(0);
        (d, r)
    }
    /// Microseconds past the hour (below one hour after `new_checked`).
    pub fn timestamp_us(&self) -> u32 {
        let t = &self.buf[field::TIMESTAMP];
        u32::from_le_bytes([t[0], t[1], t[2], t[3]])
    }
    /// The return-mode byte.
    pub fn return_mode(&self) -> u8 {
        self.buf[field::RETURN_MODE]
    }
    /// The product-id byte.
    pub fn product(&self) -> u8 {
        self.buf[field::PRODUCT]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn packet() -> [u8; field::LEN] {
        let mut b = [0u8; field::LEN];
        for k in 0..field::BLOCKS {
            b[k * 100] = 0xFF;
            b[k * 100 + 1] = 0xEE;
            b[k * 100 + 2..k * 100 + 4].copy_from_slice(&(k as u16 * 20).to_le_bytes());
        }
        b[1200..1204].copy_from_slice(&123_456u32.to_le_bytes());
        b[1204] = 0x37;
        b[1205] = 0x22;
        b
    }

    #[test]
    fn fields_read_where_the_manual_puts_them() {
        let mut b = packet();
        b[100 + 4 + 3 * 5..100 + 4 + 3 * 5 + 3].copy_from_slice(&[0x34, 0x12, 77]);
        let p = Packet::new_checked(&b).unwrap();
        assert_eq!(p.azimuth(3), 60);
        assert_eq!(p.channel(1, 5), (0x1234, 77));
        assert_eq!(p.timestamp_us(), 123_456);
        assert_eq!((p.return_mode(), p.product()), (0x37, 0x22));
    }

    #[test]
    fn short_long_and_corrupted_packets_are_refused() {
        let b = packet();
        assert_eq!(
            Packet::new_checked(&b[..1205]).unwrap_err(),
            PacketError::Truncated
        );
        assert_eq!(
            Packet::new_checked(&[]).unwrap_err(),
            PacketError::Truncated
        );
        let mut long = [0u8; 1212];
        long[..1206].copy_from_slice(&b);
        assert_eq!(Packet::new_checked(&long).unwrap_err(), PacketError::Length);
        let mut flag = b;
        flag[700] = 0xDE;
        assert_eq!(
            Packet::new_checked(&flag).unwrap_err(),
            PacketError::BlockFlag
        );
        let mut az = b;
        az[502..504].copy_from_slice(&36000u16.to_le_bytes());
        assert_eq!(Packet::new_checked(&az).unwrap_err(), PacketError::Azimuth);
        let mut ts = b;
        ts[1200..1204].copy_from_slice(&HOUR_US.to_le_bytes());
        assert_eq!(
            Packet::new_checked(&ts).unwrap_err(),
            PacketError::Timestamp
        );
    }
}
