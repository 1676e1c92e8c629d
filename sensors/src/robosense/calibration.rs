//! A Robosense unit's per-laser angles: from its DIFOP packet, or from the `angle.csv` the
//! vendor ships (one `vertical,horizontal` line in degrees a laser, rs_driver's
//! `ChanAngles::loadFromFile`), which the host parses into the same numbers.

use super::model::{AiryInstall, Model, AIRY_INSTALL, MAX_LASERS};
use super::wire::Difop;
use crate::error::ConfigError;

/// Largest angle a laser may have, degrees (rs_driver's `angleCheck` allows +-90 degrees).
pub const MAX_ANGLE_DEG: f64 = 90.0;

/// One laser's angles.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Laser {
    /// Elevation, degrees (positive up).
    pub vertical_deg: f64,
    /// Added to the interpolated azimuth, degrees (Robosense's azimuth grows clockwise seen
    /// from above, as Velodyne's).
    pub horizontal_deg: f64,
}

/// A unit's angles and, from its DIFOP packet, its return mode.
#[derive(Clone, Debug, PartialEq)]
pub struct Calibration {
    /// One entry per laser, in channel order.
    pub lasers: heapless::Vec<Laser, MAX_LASERS>,
    /// Dual-return mode, when a DIFOP packet said (`None` from an angle file: the 32- and
    /// 128-laser models show it by repeated block azimuths; the 16-laser ones are read as
    /// single return).
    pub dual: Option<bool>,
    /// The RS-Airy's firing table, from its DIFOP packet's install mode (the default, the
    /// Airy M's, from an angle file); the other models ignore it.
    pub install: AiryInstall,
}

impl Calibration {
    /// The angles and return mode of `model`'s DIFOP packet.
    pub fn from_difop(model: Model, d: &Difop<'_>) -> Result<Self, ConfigError> {
        let at = model.difop();
        let mut lasers = heapless::Vec::new();
        for i in 0..model.lasers() {
            let laser = match at.horizontal {
                Some(h) => Laser {
                    vertical_deg: f64::from(
                        d.angle(at.vertical + 3 * i)
                            .ok_or(ConfigError::Calibration)?,
                    ) * 0.01,
                    horizontal_deg: f64::from(d.angle(h + 3 * i).ok_or(ConfigError::Calibration)?)
                        * 0.01,
                },
                // RS-16: 0.0001 degree, lasers 0-7 below the horizon (rs_driver
                // `RS16DifopPkt2Adapter`).
                None => {
                    let v = d.u24(at.vertical + 3 * i).ok_or(ConfigError::Calibration)?;
                    let deg = f64::from(v) * 1e-4;
                    Laser {
                        vertical_deg: if i < 8 { -deg } else { deg },
                        horizontal_deg: 0.0,
                    }
                }
            };
            lasers.push(laser).map_err(|_| ConfigError::Calibration)?;
        }
        let c = Self {
            lasers,
            dual: model.dual_mode(d.byte(at.return_mode)),
            install: AiryInstall::from_byte(d.byte(AIRY_INSTALL)),
        };
        c.validate(model)?;
        Ok(c)
    }

    /// Whether there is one finite angle within +-90 degrees per laser of `model`.
    pub fn validate(&self, model: Model) -> Result<(), ConfigError> {
        let ok = self.lasers.len() == model.lasers()
            && self.lasers.iter().all(|l| {
                [l.vertical_deg, l.horizontal_deg]
                    .iter()
                    .all(|v| v.is_finite() && v.abs() <= MAX_ANGLE_DEG)
            });
        if ok {
            Ok(())
        } else {
            Err(ConfigError::Calibration)
        }
    }
}

/// Decoder settings.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    /// The model: Robosense packets do not tell the RS-16, RS-32 and Bpearl apart.
    pub model: Model,
    /// The unit's angles; `None` takes them from the first DIFOP packet pushed.
    pub calibration: Option<Calibration>,
    /// Azimuth (degrees, `[0, 360)`) at which sweeps end; `None` ends a sweep once it covers a
    /// full turn.
    pub cut_angle_deg: Option<f64>,
}
