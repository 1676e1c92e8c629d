//! A checked Hesai packet of any of the three layouts (protocol 6.1, protocols 3.2 and 1.4,
//! the fixed layouts), read the same way by the decoder: what its header, blocks and tail say,
//! and whether the header's return count fits the mode.

use super::model::{Firing, Model, ReturnMode, DISTANCE_UNIT_M};
use super::wire::Packet;
use super::{wire128, wire_fixed};
use crate::error::PacketError;

/// A checked packet of either layout.
#[derive(Clone, Copy)]
pub(super) enum View<'a> {
    Xt32(Packet<'a>),
    Wide(wire128::Packet<'a>),
    Fixed(wire_fixed::Packet<'a>),
}

impl<'a> View<'a> {
    /// Checks `bytes` as a packet of `model`'s protocol.
    pub(super) fn new_checked(model: Model, bytes: &'a [u8]) -> Result<Self, PacketError> {
        if let Some((format, _)) = model.fixed() {
            return wire_fixed::Packet::new_checked(format, bytes).map(Self::Fixed);
        }
        let version = match model {
            Model::Xt32 => return Packet::new_checked(bytes).map(Self::Xt32),
            Model::Qt128 => wire128::VERSION_QT,
            _ => wire128::VERSION_128,
        };
        let p = wire128::Packet::new_checked(bytes)?;
        if p.version() != version {
            return Err(PacketError::Version);
        }
        Ok(Self::Wide(p))
    }
    /// Whether the header's return count fits `mode`. Where the count is the mode's (QT64,
    /// QT128, Pandar128, OT128: their manuals' "1 single, 2 dual"; the QT64's capture says 2
    /// in dual) it must equal it. Protocol 6.1 (XT32, XT16, XT32M) and the AT128 may state
    /// the most returns the unit sends instead (the XT manual's later edition: "0x02, each
    /// channel can generate two returns maximum"; the XT32M's capture says 3 in dual mode):
    /// the count must be at least the mode's and at most that maximum. The 40P has no header
    /// and the Pandar64's has no count: bytes 6 and 7 are reserved (nebula's `Header8B`, the
    /// manual) and its "first block's return" byte 4 reads 0, single, in all 2,400 packets of
    /// its dual-return capture, so neither can be checked.
    pub(super) fn returns_fit(&self, model: Model, mode: ReturnMode) -> Result<(), PacketError> {
        let n = mode.returns();
        let (count, exact) = match self {
            Self::Xt32(p) => (p.returns(), false),
            Self::Wide(p) => (p.returns(), true),
            Self::Fixed(p) => match p.header_returns() {
                Some(r) => (r, model == Model::PandarQT64),
                None => return Ok(()),
            },
        };
        let most = if model == Model::Xt32m { 3 } else { 2 };
        let fits = if exact {
            usize::from(count) == n
        } else {
            (n..=most).contains(&usize::from(count))
        };
        if fits {
            Ok(())
        } else {
            Err(PacketError::ReturnCount {
                count,
                mode: self.return_mode(),
            })
        }
    }
    /// Motor speed, rpm.
    pub(super) fn motor_rpm(&self) -> u16 {
        match self {
            Self::Xt32(p) => p.motor_rpm(),
            Self::Wide(p) => p.motor_rpm(),
            Self::Fixed(p) => p.motor_rpm(),
        }
    }
    /// Metres per distance unit.
    pub(super) fn distance_unit_m(&self) -> f64 {
        match self {
            Self::Fixed(p) => f64::from(p.distance_unit_mm()) * 1e-3,
            _ => DISTANCE_UNIT_M,
        }
    }
    pub(super) fn return_mode(&self) -> u8 {
        match self {
            Self::Xt32(p) => p.return_mode(),
            Self::Wide(p) => p.return_mode(),
            Self::Fixed(p) => p.return_mode(),
        }
    }
    pub(super) fn azimuth(&self, k: usize) -> u16 {
        match self {
            Self::Xt32(p) => p.azimuth(k),
            Self::Wide(p) => p.azimuth(k),
            Self::Fixed(p) => p.azimuth(k),
        }
    }
    /// Block `k`'s azimuth in 1/25,600 degree (the AT128's fine byte; the others' hundredths
    /// times 256).
    pub(super) fn fine_azimuth(&self, k: usize) -> u32 {
        match self {
            Self::Fixed(p) => p.fine_azimuth(k),
            _ => u32::from(self.azimuth(k)) << 8,
        }
    }
    pub(super) fn channel(&self, k: usize, c: usize) -> (u16, u8) {
        match self {
            Self::Xt32(p) => p.channel(k, c),
            Self::Wide(p) => p.channel(k, c),
            Self::Fixed(p) => p.channel(k, c),
        }
    }
    pub(super) fn unix_ns(&self) -> Option<u64> {
        match self {
            Self::Xt32(p) => p.unix_ns(),
            Self::Wide(p) => p.unix_ns(),
            Self::Fixed(p) => p.unix_ns(),
        }
    }
    pub(super) fn udp_sequence(&self) -> Option<u32> {
        match self {
            Self::Xt32(p) => p.udp_sequence(),
            Self::Wide(p) => p.udp_sequence(),
            Self::Fixed(p) => p.udp_sequence(),
        }
    }
    /// Block `k`'s firing state, for a mode of `returns` returns.
    pub(super) fn firing(&self, k: usize, returns: usize) -> Firing {
        match self {
            Self::Xt32(_) | Self::Fixed(_) => Firing {
                returns,
                ..Firing::default()
            },
            Self::Wide(p) => Firing {
                returns,
                mode_flag: p.mode_flag(),
                operational_state: p.operational_state(),
                azimuth_state: p.azimuth_state(k),
                near: false,
            },
        }
    }
}
