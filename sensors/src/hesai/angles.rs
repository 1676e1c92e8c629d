//! Where a Hesai return points: each channel's angles added to its block's azimuth (every model
//! but the AT128, [`ChannelAngles`]), or the AT128's mirror-frame correction
//! ([`MirrorAngles`]). The decoder is generic over the two, so that a decoder of the spinning
//! models does not carry the AT128's 46 KB of tables.

use super::at128::{self, At128Correction};
use super::model::{Calibration, MAX_CHANNELS};
use crate::error::ConfigError;

mod sealed {
    pub trait Sealed {}
}

/// How the decoder turns a block's azimuth and a channel into a direction.
pub trait Angles: sealed::Sealed {
    /// The frame of a block at `fine_azimuth` (1/25,600 degree): always 0 for the spinning
    /// models, the mirror frame for the AT128; `None` where the correction has no frame (the
    /// packet is refused).
    fn frame(&self, fine_azimuth: u32) -> Option<usize>;
    /// The point `d` metres along channel `channel` of a block at `fine_azimuth` in `frame`.
    fn point(&self, fine_azimuth: u32, frame: usize, channel: usize, d: f64) -> [f64; 3];
    /// Whether a sweep is one mirror frame (AT128) rather than a turn cut by azimuth.
    fn sweeps_are_frames(&self) -> bool;
}

/// One channel, ready to use.
#[derive(Clone, Copy, Debug, Default)]
struct Beam {
    cos_e: f64,
    sin_e: f64,
    azimuth_deg: f64,
}

/// Each channel's elevation and azimuth offset ([`Calibration`]), the offset added to the
/// block's azimuth. Points in the ROS convention: x forward (azimuth 0), y left, z up; the
/// azimuth turns clockwise seen from above.
#[derive(Clone, Debug)]
pub struct ChannelAngles {
    beams: [Beam; MAX_CHANNELS],
}

impl ChannelAngles {
    /// The angles of a checked calibration.
    pub(super) fn new(calibration: &Calibration) -> Self {
        let mut beams = [Beam::default(); MAX_CHANNELS];
        let rows = calibration
            .elevation_deg
            .iter()
            .zip(&calibration.azimuth_deg);
        for (b, (e, a)) in beams.iter_mut().zip(rows).take(calibration.channels) {
            let e = e.to_radians();
            *b = Beam {
                cos_e: libm::cos(e),
                sin_e: libm::sin(e),
                azimuth_deg: *a,
            };
        }
        Self { beams }
    }
}

impl sealed::Sealed for ChannelAngles {}

impl Angles for ChannelAngles {
    fn frame(&self, _: u32) -> Option<usize> {
        Some(0)
    }
    fn point(&self, fine_azimuth: u32, _: usize, channel: usize, d: f64) -> [f64; 3] {
        let beam = self.beams.get(channel).copied().unwrap_or_default();
        // The spinning models' azimuths have no fine byte: whole hundredths.
        let block_deg = f64::from(fine_azimuth >> 8) * 0.01;
        let theta = (block_deg + beam.azimuth_deg).to_radians();
        let xy = d * beam.cos_e;
        [
            xy * libm::cos(theta),
            -xy * libm::sin(theta),
            d * beam.sin_e,
        ]
    }
    fn sweeps_are_frames(&self) -> bool {
        false
    }
}

/// The AT128's angles from its mirror-frame correction (see `at128.rs`), in its own frame: x
/// forward (the middle of its field), y left, z up.
#[derive(Clone, Debug)]
pub struct MirrorAngles {
    correction: At128Correction,
}

impl MirrorAngles {
    /// The angles of a correction, checked.
    pub(super) fn new(correction: &At128Correction) -> Result<Self, ConfigError> {
        correction.validate()?;
        Ok(Self {
            correction: correction.clone(),
        })
    }
}

impl sealed::Sealed for MirrorAngles {}

impl Angles for MirrorAngles {
    fn frame(&self, fine_azimuth: u32) -> Option<usize> {
        self.correction.frame_of(fine_azimuth)
    }
    fn point(&self, fine_azimuth: u32, frame: usize, channel: usize, d: f64) -> [f64; 3] {
        at128::point(self.correction.angles_deg(fine_azimuth, frame, channel), d)
    }
    fn sweeps_are_frames(&self) -> bool {
        true
    }
}
