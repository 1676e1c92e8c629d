//! The PandarXT-32's published geometry and timing, the per-channel [`Calibration`] (Hesai's
//! angle correction file) and the decoder's [`Config`].

use super::wire::field;
use crate::error::ConfigError;
use crate::sweep::Return;

/// Channels of the PandarXT-32.
pub const CHANNELS: usize = field::CHANNELS;
/// Metres per distance unit (the header's 4 mm).
pub const DISTANCE_UNIT_M: f64 = 0.004;
/// Time from one firing to the next, ns.
pub const FIRING_NS: i64 = 50_000;
/// Time from a channel's firing to the next channel's within a firing, ns.
pub const CHANNEL_NS: i64 = 1_512;

/// Time of block `block`, channel `channel` after the packet time, ns, for a packet of
/// `returns` returns (the XT32 manual's timing: the last firing starts 5.632 us after the
/// packet time, the firings 50 us apart, and channel `c` fires 0.368 + 1.512 c us after its
/// firing starts). Negative: the packet time stamps its last firing.
pub const fn point_offset_ns(block: usize, channel: usize, returns: usize) -> i64 {
    let returns = if returns == 0 { 1 } else { returns };
    let firings_after = (field::BLOCKS - 1 - block) / returns;
    5_632 - FIRING_NS * firings_after as i64 + 368 + CHANNEL_NS * channel as i64
}

/// How the sensor reports its returns: the return-mode byte.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ReturnMode {
    /// One return per firing.
    Single(Return),
    /// Two returns per firing, in two consecutive blocks: which each of the pair holds.
    Dual(Return, Return),
}

impl ReturnMode {
    /// The mode a return-mode byte names (XT32 manual, protocol 6.1).
    pub const fn from_byte(b: u8) -> Option<Self> {
        Some(match b {
            0x33 => Self::Single(Return::First),
            0x37 => Self::Single(Return::Strongest),
            0x38 => Self::Single(Return::Last),
            0x39 => Self::Dual(Return::Last, Return::Strongest),
            // The XT32 sends the first return before the last (unlike Hesai's other sensors).
            0x3B => Self::Dual(Return::First, Return::Last),
            0x3C => Self::Dual(Return::First, Return::Strongest),
            _ => return None,
        })
    }
    /// Returns per firing: blocks per firing.
    pub const fn returns(self) -> usize {
        match self {
            Self::Single(_) => 1,
            Self::Dual(..) => 2,
        }
    }
}

/// Each channel's angles, from Hesai's angle correction file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration {
    /// Elevation of each channel, degrees (positive up), channel 1 first.
    pub elevation_deg: [f64; CHANNELS],
    /// Added to the block azimuth for each channel, degrees.
    pub azimuth_deg: [f64; CHANNELS],
}

impl Calibration {
    /// The nominal angles: channel `c` (from 0) at `15 - c` degrees, no azimuth offset (the
    /// XT32 manual's channel table; its lasers fire in one vertical line).
    pub const fn nominal() -> Self {
        let mut elevation_deg = [0.0; CHANNELS];
        let mut c = 0;
        while c < CHANNELS {
            elevation_deg[c] = 15.0 - c as f64;
            c += 1;
        }
        Self {
            elevation_deg,
            azimuth_deg: [0.0; CHANNELS],
        }
    }

    /// Whether every angle is finite, elevations within +-90 degrees and azimuth offsets
    /// within +-45.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let ok = self
            .elevation_deg
            .iter()
            .all(|e| e.is_finite() && libm::fabs(*e) <= 90.0)
            && self
                .azimuth_deg
                .iter()
                .all(|a| a.is_finite() && libm::fabs(*a) <= 45.0);
        if ok {
            Ok(())
        } else {
            Err(ConfigError::Calibration)
        }
    }
}

impl Default for Calibration {
    fn default() -> Self {
        Self::nominal()
    }
}

/// Decoder settings.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Config {
    /// Channel angles; `None` uses the nominal ones.
    pub calibration: Option<Calibration>,
    /// Azimuth (degrees, `[0, 360)`) at which sweeps end; `None` ends a sweep once it covers
    /// a full turn from wherever the previous one ended. Sweeps are whole packets.
    pub cut_angle_deg: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn firings_are_50_us_apart_and_the_last_is_stamped() {
        // Single return: block 7 is the stamped firing, block 0 seven firings earlier.
        assert_eq!(point_offset_ns(7, 0, 1), 6_000);
        assert_eq!(point_offset_ns(0, 0, 1), 6_000 - 350_000);
        assert_eq!(point_offset_ns(7, 31, 1), 6_000 + 31 * 1_512);
        // Dual: blocks come in pairs of one firing.
        assert_eq!(point_offset_ns(6, 3, 2), point_offset_ns(7, 3, 2));
        assert_eq!(point_offset_ns(0, 0, 2), 6_000 - 150_000);
        assert_eq!(point_offset_ns(0, 0, 0), point_offset_ns(0, 0, 1));
    }

    #[test]
    fn mode_bytes_and_calibration_checks() {
        assert_eq!(
            ReturnMode::from_byte(0x37),
            Some(ReturnMode::Single(Return::Strongest))
        );
        assert_eq!(
            ReturnMode::from_byte(0x3C).map(ReturnMode::returns),
            Some(2)
        );
        assert_eq!(ReturnMode::from_byte(0x3A), None);
        let nominal = Calibration::nominal();
        assert_eq!(nominal.elevation_deg[0], 15.0);
        assert_eq!(nominal.elevation_deg[31], -16.0);
        assert!(nominal.validate().is_ok());
        let mut bad = nominal;
        bad.elevation_deg[3] = f64::NAN;
        assert_eq!(bad.validate(), Err(ConfigError::Calibration));
        let mut bad = nominal;
        bad.azimuth_deg[3] = 50.0;
        assert_eq!(bad.validate(), Err(ConfigError::Calibration));
    }
}
