//! Robosense MSOP (points) and DIFOP (device information) packets: 1248 bytes of UDP payload
//! each, multi-byte fields big-endian.
//!
//! ```text
//! MSOP   header (42 bytes; RS-Ruby 80) | blocks | tail
//!          id 55 AA 05 0A 5A A5 50 A0 (RS-16, RS-32, Bpearl) or 55 AA 05 5A (Helios, Ruby,
//!          Airy)
//!          timestamp at 20 (Ruby: 10), 10 bytes: YMD (RS-16, RS-32, Bpearl) or UTC s + us
//!          Airy: data type at 16 (0: points), return mode at 17 (0x03 dual), channel mode
//!          at 32 (0x02: 96)
//!        block: flag FF EE (Ruby: FE, return id) | azimuth u16 (0.01 deg) |
//!               channels x (distance u16 in the model's unit, intensity u8)
//! DIFOP  id A5 FF 00 5A 11 11 55 55 | rpm u16 at 8 | Airy install mode at 289 |
//!        return mode at 300 |
//!        angles at 468: (sign u8, value u16 in 0.01 deg) a laser, vertical then horizontal
//!        (RS-16: 16 vertical values of 3 bytes in 0.0001 deg at 1165, lasers 0-7 negative)
//! ```
//! (rs_driver `decoder.hpp` `RSMsopHeaderV1`/`V2`, `basic_attr.hpp`, and the per-model packet
//! structs; the layout per model is [`super::Model::layout`].)

use super::model::{Model, Stamp, AIRY_96, AIRY_CHANNEL_MODE, AIRY_DATA_TYPE, AIRY_RETURN_MODE};
use crate::error::PacketError;
use crate::time::days_from_civil_checked;

/// Bytes of every MSOP and DIFOP packet.
pub const LEN: usize = 1248;
/// The DIFOP packet's first bytes.
pub const DIFOP_ID: [u8; 8] = [0xA5, 0xFF, 0x00, 0x5A, 0x11, 0x11, 0x55, 0x55];
/// DIFOP: rotation speed, rpm (u16 BE).
pub const DIFOP_RPM: usize = 8;
/// Azimuth units a turn (hundredths of a degree).
pub const AZIMUTH_UNITS: u16 = 36000;

fn be16(b: &[u8], at: usize) -> u16 {
    match (b.get(at), b.get(at + 1)) {
        (Some(&h), Some(&l)) => u16::from_be_bytes([h, l]),
        _ => 0,
    }
}

/// A 10-byte UTC stamp (6 bytes of seconds, 4 of microseconds, big-endian) in microseconds
/// since the Unix epoch; `None` when the microseconds reach a second or the time (48 bits of
/// seconds hold 2^48) does not fit a `u64` of nanoseconds, the unit of the sweeps (the year
/// 2554).
pub(super) fn utc_us(t: &[u8]) -> Option<u64> {
    let (secs, us) = (t.get(..6)?, t.get(6..10)?);
    let secs = secs.iter().fold(0u64, |a, &b| a << 8 | u64::from(b));
    let us = us.iter().fold(0u64, |a, &b| a << 8 | u64::from(b));
    if us >= 1_000_000 {
        return None;
    }
    let t = secs.checked_mul(1_000_000)?.checked_add(us)?;
    t.checked_mul(1000).map(|_| t)
}

/// The model whose MSOP packet `bytes` is, when no other model writes that layout (the
/// RS-Ruby's and the RS-Airy's); `None` for the others (the RS-16, RS-32 and Bpearl send
/// alike, as do the Helios and Helios-16P) and for anything else.
pub fn model_of(bytes: &[u8]) -> Option<Model> {
    if bytes.len() != LEN {
        return None;
    }
    let mut writers = Model::ALL.iter().filter(|m| m.writes(bytes));
    match (writers.next(), writers.next()) {
        (Some(&m), None) => Some(m),
        _ => None,
    }
}

fn fixed(bytes: &[u8]) -> Result<&[u8; LEN], PacketError> {
    match bytes.try_into() {
        Ok(b) => Ok(b),
        Err(_) if bytes.len() < LEN => Err(PacketError::Truncated),
        Err(_) => Err(PacketError::Length),
    }
}

/// A checked MSOP packet of one model: id, block flags, azimuths and timestamp validated.
#[derive(Clone, Copy, Debug)]
pub struct Msop<'a> {
    buf: &'a [u8; LEN],
    model: Model,
    /// The model's [`Model::distance_mask`].
    mask: u16,
}

impl<'a> Msop<'a> {
    /// Checks length, the model's id and block flags, azimuths and the timestamp. A DIFOP
    /// packet or another family's MSOP answers [`PacketError::StartBytes`]; another Robosense
    /// model's block flag (another model on the port) [`PacketError::OtherSensor`]; a flag no
    /// model writes [`PacketError::BlockFlag`].
    pub fn new_checked(bytes: &'a [u8], model: Model) -> Result<Self, PacketError> {
        let buf = fixed(bytes)?;
        let l = model.layout();
        if !buf.starts_with(l.id) {
            return Err(PacketError::StartBytes);
        }
        let p = Self {
            buf,
            model,
            mask: model.distance_mask(),
        };
        for k in 0..l.blocks {
            let at = l.header + k * l.block_len();
            if buf.get(at..).is_none_or(|b| !b.starts_with(l.block_id)) {
                return Err(if Model::ALL.iter().any(|&m| m.lays_out(buf, l)) {
                    PacketError::OtherSensor
                } else {
                    PacketError::BlockFlag
                });
            }
            if p.azimuth(k) >= AZIMUTH_UNITS {
                return Err(PacketError::Azimuth);
            }
        }
        p.time_us().ok_or(PacketError::DateTime)?;
        if model == Model::Airy {
            if buf[AIRY_DATA_TYPE] != 0 {
                return Err(PacketError::PacketType);
            }
            if buf[AIRY_CHANNEL_MODE] != AIRY_96 {
                return Err(PacketError::Header);
            }
        }
        Ok(p)
    }

    /// The RS-Airy's return-mode byte: dual return (0x03) or not.
    pub fn airy_dual(&self) -> bool {
        self.buf[AIRY_RETURN_MODE] == 0x03
    }

    fn block_at(&self, k: usize) -> usize {
        let l = self.model.layout();
        l.header + k * l.block_len()
    }

    /// Block `k`'s azimuth, hundredths of a degree.
    pub fn azimuth(&self, k: usize) -> u16 {
        be16(self.buf, self.block_at(k) + self.model.layout().azimuth_at)
    }

    /// Block `k`, channel `c`: raw distance (its distance bits, [`Model::distance_mask`]) and
    /// intensity.
    pub fn channel(&self, k: usize, c: usize) -> (u16, u8) {
        let at = self.block_at(k) + self.model.layout().azimuth_at + 2 + 3 * c;
        (
            be16(self.buf, at) & self.mask,
            self.buf.get(at + 2).copied().unwrap_or(0),
        )
    }

    /// The packet's time, microseconds since the Unix epoch (`None` for a date that does not
    /// exist).
    pub fn time_us(&self) -> Option<u64> {
        let (at, kind) = self.model.layout().stamp;
        let t = self.buf.get(at..at + 10)?;
        match kind {
            Stamp::Ymd => {
                let days = days_from_civil_checked(2000 + i64::from(t[0]), t[1], t[2])?;
                let (h, m, s) = (u64::from(t[3]), u64::from(t[4]), u64::from(t[5]));
                let (ms, us) = (u64::from(be16(t, 6)), u64::from(be16(t, 8)));
                if h > 23 || m > 59 || s > 60 || ms > 999 || us > 999 {
                    return None;
                }
                let secs = u64::try_from(days).ok()?.checked_mul(86_400)? + h * 3600 + m * 60 + s;
                secs.checked_mul(1_000_000)?.checked_add(ms * 1000 + us)
            }
            Stamp::Utc => utc_us(t),
        }
    }
}

/// A checked DIFOP packet.
#[derive(Clone, Copy, Debug)]
pub struct Difop<'a> {
    buf: &'a [u8; LEN],
}

impl<'a> Difop<'a> {
    /// Checks length and id.
    pub fn new_checked(bytes: &'a [u8]) -> Result<Self, PacketError> {
        let buf = fixed(bytes)?;
        if !buf.starts_with(&DIFOP_ID) {
            return Err(PacketError::StartBytes);
        }
        Ok(Self { buf })
    }

    /// Rotation speed, rpm.
    pub fn rpm(&self) -> u16 {
        be16(self.buf, DIFOP_RPM)
    }

    /// The return-mode byte at `at`.
    pub fn byte(&self, at: usize) -> u8 {
        self.buf.get(at).copied().unwrap_or(0)
    }

    /// A signed angle entry (sign byte, u16 BE) at `at`, hundredths of a degree; `None` for an
    /// unset entry (sign 0xFF, as rs_driver refuses it).
    pub fn angle(&self, at: usize) -> Option<i32> {
        let sign = *self.buf.get(at)?;
        if sign == 0xFF {
            return None;
        }
        let v = i32::from(be16(self.buf, at + 1));
        Some(if sign != 0 { -v } else { v })
    }

    /// A 3-byte big-endian value at `at`.
    pub fn u24(&self, at: usize) -> Option<u32> {
        let b = self.buf.get(at..at + 3)?;
        Some(u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]))
    }
}
