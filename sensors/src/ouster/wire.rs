//! Ouster lidar data packets: the legacy layout (firmware up to 2.x, `LEGACY`) and the
//! eUDP profiles (firmware 2.2 on): `RNG19_RFL8_SIG16_NIR16` (single return),
//! `RNG19_RFL8_SIG16_NIR16_DUAL` and `RNG15_RFL8_NIR8` (low bandwidth). All fields
//! little-endian; the layout follows the sensor's firmware user manual.
//!
//! ```text
//! legacy:  columns_per_packet x [header 16 | pixels x 12 bytes | status 4]
//! eUDP:    header 32 | columns_per_packet x [header 12 | pixels x (12|16|4) bytes] | footer 32
//! ```

use crate::error::PacketError;

/// Byte ranges of the packet, its column headers and its pixels.
pub mod field {
    use core::ops::Range;
    /// Legacy column header: timestamp, ns.
    pub const LEGACY_TIMESTAMP: Range<usize> = 0..8;
    /// Legacy column header: measurement id (column in the frame).
    pub const LEGACY_MEASUREMENT_ID: Range<usize> = 8..10;
    /// Legacy column header: frame id.
    pub const LEGACY_FRAME_ID: Range<usize> = 10..12;
    /// Legacy column header: encoder count.
    pub const LEGACY_ENCODER: Range<usize> = 12..16;
    /// Legacy column header length.
    pub const LEGACY_HEADER_LEN: usize = 16;
    /// Legacy column footer: status, `0xFFFFFFFF` when the column is valid.
    pub const LEGACY_STATUS_LEN: usize = 4;

    /// eUDP packet header: packet type (1: lidar data).
    pub const PACKET_TYPE: Range<usize> = 0..2;
    /// eUDP packet header: frame id.
    pub const FRAME_ID: Range<usize> = 2..4;
    /// eUDP packet header: initialisation id (24 bits).
    pub const INIT_ID: Range<usize> = 4..7;
    /// eUDP packet header: serial number (40 bits).
    pub const SERIAL: Range<usize> = 7..12;
    /// eUDP packet header length.
    pub const HEADER_LEN: usize = 32;
    /// eUDP packet footer length.
    pub const FOOTER_LEN: usize = 32;
    /// eUDP column header: timestamp, ns.
    pub const COLUMN_TIMESTAMP: Range<usize> = 0..8;
    /// eUDP column header: measurement id.
    pub const COLUMN_MEASUREMENT_ID: Range<usize> = 8..10;
    /// eUDP column header: status, bit 0 set when the column is valid.
    pub const COLUMN_STATUS: Range<usize> = 10..12;
    /// eUDP column header length.
    pub const COLUMN_HEADER_LEN: usize = 12;

    /// Legacy and single-return pixel: range, mm (legacy 20 bits, RNG19 19 bits).
    pub const RANGE: Range<usize> = 0..4;
    /// Dual-return pixel: second range, mm (19 bits).
    pub const RANGE2: Range<usize> = 4..8;
    /// Legacy pixel: reflectivity (16 bits).
    pub const LEGACY_REFLECTIVITY: Range<usize> = 4..6;
    /// Single-return pixel: reflectivity (8 bits).
    pub const SINGLE_REFLECTIVITY: usize = 4;
    /// Dual-return pixel: first return's reflectivity.
    pub const DUAL_REFLECTIVITY: usize = 3;
    /// Low-bandwidth pixel: range in units of 8 mm (15 bits).
    pub const LB_RANGE: Range<usize> = 0..2;
    /// Low-bandwidth pixel: reflectivity.
    pub const LB_REFLECTIVITY: usize = 2;
}

/// Lidar data packet type in the eUDP header.
pub const LIDAR_PACKET_TYPE: u16 = 1;

fn le(b: &[u8], r: core::ops::Range<usize>) -> u64 {
    b.get(r)
        .map(|s| {
            s.iter()
                .rev()
                .fold(0u64, |acc, &x| (acc << 8) | u64::from(x))
        })
        .unwrap_or(0)
}

/// Sizes of a packet for one profile, beam count and columns per packet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Layout {
    /// The profile.
    pub profile: Profile,
    /// Beams (pixels per column).
    pub beams: usize,
    /// Columns per packet.
    pub columns: usize,
}

impl Layout {
    /// Bytes of one pixel.
    pub fn pixel_len(&self) -> usize {
        match self.profile {
            Profile::Legacy | Profile::Rng19Rfl8Sig16Nir16 => 12,
            Profile::Rng19Rfl8Sig16Nir16Dual => 16,
            Profile::Rng15Rfl8Nir8 => 4,
        }
    }
    fn header_len(&self) -> usize {
        match self.profile {
            Profile::Legacy => 0,
            _ => field::HEADER_LEN,
        }
    }
    fn column_header_len(&self) -> usize {
        match self.profile {
            Profile::Legacy => field::LEGACY_HEADER_LEN,
            _ => field::COLUMN_HEADER_LEN,
        }
    }
    /// Bytes of one column block.
    pub fn column_len(&self) -> usize {
        let footer = match self.profile {
            Profile::Legacy => field::LEGACY_STATUS_LEN,
            _ => 0,
        };
        self.column_header_len() + self.beams * self.pixel_len() + footer
    }
    /// Bytes of the whole packet.
    pub fn packet_len(&self) -> usize {
        let footer = match self.profile {
            Profile::Legacy => 0,
            _ => field::FOOTER_LEN,
        };
        self.header_len() + self.columns * self.column_len() + footer
    }
}

/// A checked lidar data packet: its length is the layout's, so every read is in bounds.
#[derive(Clone, Copy, Debug)]
pub struct Packet<'a> {
    buf: &'a [u8],
    layout: Layout,
}

impl<'a> Packet<'a> {
    /// Checks the length against `layout` and, for eUDP profiles, the packet type.
    pub fn new_checked(bytes: &'a [u8], layout: Layout) -> Result<Self, PacketError> {
        let len = layout.packet_len();
        if bytes.len() < len {
            return Err(PacketError::Truncated);
        }
        if bytes.len() > len {
            return Err(PacketError::Length);
        }
        let p = Self { buf: bytes, layout };
        if layout.profile != Profile::Legacy
            && le(bytes, field::PACKET_TYPE) as u16 != LIDAR_PACKET_TYPE
        {
            return Err(PacketError::PacketType);
        }
        Ok(p)
    }

    /// Frame id (legacy: the first column's).
    pub fn frame_id(&self) -> u16 {
        match self.layout.profile {
            Profile::Legacy => le(self.buf, field::LEGACY_FRAME_ID) as u16,
            _ => le(self.buf, field::FRAME_ID) as u16,
        }
    }
    /// Initialisation id (eUDP only).
    pub fn init_id(&self) -> Option<u32> {
        (self.layout.profile != Profile::Legacy).then(|| le(self.buf, field::INIT_ID) as u32)
    }
    /// Serial number (eUDP only).
    pub fn serial(&self) -> Option<u64> {
        (self.layout.profile != Profile::Legacy).then(|| le(self.buf, field::SERIAL))
    }
    /// Column block `i` (below `layout.columns`).
    pub fn column(&self, i: usize) -> Column<'a> {
        let len = self.layout.column_len();
        let at = self.layout.header_len() + i * len;
        Column {
            buf: self.buf.get(at..at + len).unwrap_or(&[]),
            layout: self.layout,
        }
    }
}

/// One column block of a checked packet.
#[derive(Clone, Copy, Debug)]
pub struct Column<'a> {
    buf: &'a [u8],
    layout: Layout,
}

impl Column<'_> {
    /// Capture time of the column, ns (sensor clock).
    pub fn timestamp_ns(&self) -> u64 {
        match self.layout.profile {
            Profile::Legacy => le(self.buf, field::LEGACY_TIMESTAMP),
            _ => le(self.buf, field::COLUMN_TIMESTAMP),
        }
    }
    /// Measurement id: the column's position in the frame.
    pub fn measurement_id(&self) -> u16 {
        match self.layout.profile {
            Profile::Legacy => le(self.buf, field::LEGACY_MEASUREMENT_ID) as u16,
            _ => le(self.buf, field::COLUMN_MEASUREMENT_ID) as u16,
        }
    }
    /// Frame id written in a legacy column (eUDP: none).
    pub fn frame_id(&self) -> Option<u16> {
        (self.layout.profile == Profile::Legacy)
            .then(|| le(self.buf, field::LEGACY_FRAME_ID) as u16)
    }
    /// Whether the sensor marked the column valid.
    pub fn valid(&self) -> bool {
        match self.layout.profile {
            Profile::Legacy => {
                let at = self.buf.len().saturating_sub(field::LEGACY_STATUS_LEN);
                le(self.buf, at..self.buf.len()) == 0xFFFF_FFFF
            }
            _ => le(self.buf, field::COLUMN_STATUS) & 1 == 1,
        }
    }
    fn pixel(&self, beam: usize) -> &[u8] {
        let len = self.layout.pixel_len();
        let at = self.layout.column_header_len() + beam * len;
        self.buf.get(at..at + len).unwrap_or(&[])
    }
    /// First (or only) return's range of `beam`, mm; 0 for no return.
    pub fn range_mm(&self, beam: usize) -> u32 {
        let px = self.pixel(beam);
        match self.layout.profile {
            Profile::Legacy => le(px, field::RANGE) as u32 & 0x000F_FFFF,
            Profile::Rng19Rfl8Sig16Nir16 | Profile::Rng19Rfl8Sig16Nir16Dual => {
                le(px, field::RANGE) as u32 & 0x0007_FFFF
            }
            Profile::Rng15Rfl8Nir8 => (le(px, field::LB_RANGE) as u32 & 0x7FFF) * 8,
        }
    }
    /// Second return's range of `beam`, mm (dual profile; 0 otherwise).
    pub fn range2_mm(&self, beam: usize) -> u32 {
        match self.layout.profile {
            Profile::Rng19Rfl8Sig16Nir16Dual => {
                le(self.pixel(beam), field::RANGE2) as u32 & 0x0007_FFFF
            }
            _ => 0,
        }
    }
    /// First return's reflectivity of `beam`.
    pub fn reflectivity(&self, beam: usize) -> u16 {
        let px = self.pixel(beam);
        let at = match self.layout.profile {
            Profile::Legacy => return le(px, field::LEGACY_REFLECTIVITY) as u16,
            Profile::Rng19Rfl8Sig16Nir16 => field::SINGLE_REFLECTIVITY,
            Profile::Rng19Rfl8Sig16Nir16Dual => field::DUAL_REFLECTIVITY,
            Profile::Rng15Rfl8Nir8 => field::LB_REFLECTIVITY,
        };
        px.get(at).copied().map(u16::from).unwrap_or(0)
    }
    /// Second return's reflectivity of `beam` (dual profile).
    pub fn reflectivity2(&self, beam: usize) -> u16 {
        match self.layout.profile {
            Profile::Rng19Rfl8Sig16Nir16Dual => {
                self.pixel(beam).get(7).copied().map(u16::from).unwrap_or(0)
            }
            _ => 0,
        }
    }
}

/// The lidar packet profile (`udp_profile_lidar`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Profile {
    /// `LEGACY`: firmware before 2.2, and later firmware configured so.
    Legacy,
    /// `RNG19_RFL8_SIG16_NIR16`: one return.
    Rng19Rfl8Sig16Nir16,
    /// `RNG19_RFL8_SIG16_NIR16_DUAL`: two returns.
    Rng19Rfl8Sig16Nir16Dual,
    /// `RNG15_RFL8_NIR8`: low bandwidth, range in 8 mm units.
    Rng15Rfl8Nir8,
}

impl Profile {
    /// The profile the metadata names (`udp_profile_lidar`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "LEGACY" => Some(Self::Legacy),
            "RNG19_RFL8_SIG16_NIR16" => Some(Self::Rng19Rfl8Sig16Nir16),
            "RNG19_RFL8_SIG16_NIR16_DUAL" => Some(Self::Rng19Rfl8Sig16Nir16Dual),
            "RNG15_RFL8_NIR8" => Some(Self::Rng15Rfl8Nir8),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packet_lengths_match_the_recordings() {
        let l = |profile, beams| Layout {
            profile,
            beams,
            columns: 16,
        };
        assert_eq!(l(Profile::Legacy, 32).packet_len(), 6464);
        assert_eq!(l(Profile::Rng19Rfl8Sig16Nir16Dual, 32).packet_len(), 8448);
        assert_eq!(l(Profile::Rng15Rfl8Nir8, 128).packet_len(), 8448);
        assert_eq!(l(Profile::Legacy, 64).packet_len(), 12608);
        assert_eq!(l(Profile::Rng19Rfl8Sig16Nir16, 64).packet_len(), 12544);
    }

    #[test]
    fn lengths_and_types_are_checked_before_reading() {
        let layout = Layout {
            profile: Profile::Rng15Rfl8Nir8,
            beams: 2,
            columns: 1,
        };
        let mut b = [0u8; 32 + 12 + 8 + 32];
        assert_eq!(
            Packet::new_checked(&b[..50], layout).unwrap_err(),
            PacketError::Truncated
        );
        assert_eq!(
            Packet::new_checked(&b, layout).unwrap_err(),
            PacketError::PacketType
        );
        b[0] = 1;
        b[2..4].copy_from_slice(&513u16.to_le_bytes());
        b[4..7].copy_from_slice(&[1, 2, 3]);
        b[44..46].copy_from_slice(&(0x8000u16 | 100).to_le_bytes());
        b[46] = 9;
        b[32 + 10] = 1;
        let p = Packet::new_checked(&b, layout).unwrap();
        assert_eq!((p.frame_id(), p.init_id()), (513, Some(0x030201)));
        let c = p.column(0);
        // The top bit is a flag, not range; LB ranges count 8 mm.
        assert_eq!(
            (c.range_mm(0), c.reflectivity(0), c.valid()),
            (800, 9, true)
        );
        let mut long = [0u8; 85];
        long[0] = 1;
        assert_eq!(
            Packet::new_checked(&long, layout).unwrap_err(),
            PacketError::Length
        );
    }
}
