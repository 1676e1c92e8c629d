//! Per-laser corrections ([`Calibration`]) and the decoder's settings ([`Config`]).

use super::model::{Model, MAX_LASERS};
use crate::error::ConfigError;

/// One laser's corrections.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Laser {
    /// Elevation, degrees (positive up).
    pub vertical_deg: f64,
    /// Added to the block azimuth, degrees (Velodyne's XML `rotCorrection_` with its sign
    /// flipped; the ROS YAML's `-rot_correction` in degrees).
    pub azimuth_offset_deg: f64,
    /// Added to the distance, metres.
    pub distance_offset_m: f64,
    /// Added to z, metres.
    pub vertical_offset_m: f64,
    /// Offset across the beam in the horizontal plane, metres.
    pub horizontal_offset_m: f64,
    /// The HDL-64E's two-point distance correction: the distance offsets measured at the near
    /// points (2.40 m along x, 1.93 m along y; the XML's `distCorrectionX_`,
    /// `distCorrectionY_`), metres. `distance_offset_m` is the far point's (25.04 m).
    pub near_distance_offset_m: Option<[f64; 2]>,
}

/// Per-laser corrections for one sensor, in firing order.
#[derive(Clone, Debug, PartialEq)]
pub struct Calibration {
    /// One entry per laser.
    pub lasers: heapless::Vec<Laser, MAX_LASERS>,
    /// Metres per distance unit.
    pub distance_resolution_m: f64,
}

impl Calibration {
    /// The manuals' nominal values for `model`: vertical angles, azimuth offsets, beam-origin
    /// heights; no lasers for a model that needs its calibration file
    /// ([`Model::needs_calibration`]).
    pub fn nominal(model: Model) -> Self {
        let mut lasers = heapless::Vec::new();
        for (i, &v) in model.vertical_deg().iter().enumerate() {
            let laser = Laser {
                vertical_deg: v,
                azimuth_offset_deg: model.azimuth_offset_deg(i),
                vertical_offset_m: model.vertical_offset_m(i),
                ..Laser::default()
            };
            // The tables have at most MAX_LASERS entries.
            let _ = lasers.push(laser);
        }
        Self {
            lasers,
            distance_resolution_m: model.distance_resolution_m(),
        }
    }

    /// Whether every number is finite and the laser count is one a supported model fires.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let finite = self.distance_resolution_m.is_finite()
            && self.distance_resolution_m > 0.0
            && self.lasers.iter().all(|l| {
                [
                    l.vertical_deg,
                    l.azimuth_offset_deg,
                    l.distance_offset_m,
                    l.vertical_offset_m,
                    l.horizontal_offset_m,
                ]
                .iter()
                .chain(l.near_distance_offset_m.iter().flatten())
                .all(|v| v.is_finite())
            });
        if !finite || !matches!(self.lasers.len(), 16 | 32 | 64 | 128) {
            return Err(ConfigError::Calibration);
        }
        Ok(())
    }
}

/// Decoder settings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Config {
    /// The model; `None` reads it from the first packet's product-id byte (needed for old
    /// HDL-32E firmware, which leaves the byte 0, and for the HDL-64E, which has none).
    pub model: Option<Model>,
    /// Per-laser corrections; `None` uses the model's nominal values (a model that
    /// [`Model::needs_calibration`] then refuses every packet with
    /// [`crate::PacketError::NoCalibration`]).
    pub calibration: Option<Calibration>,
    /// Azimuth (degrees, `[0, 360)`) at which sweeps end; `None` ends a sweep once it covers
    /// a full turn from wherever the previous one ended (velodyne-decoder's default). Sweeps
    /// are whole packets: the packet whose last block passes the cut ends its sweep.
    pub cut_angle_deg: Option<f64>,
}
