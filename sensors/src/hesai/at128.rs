//! The PandarAT128's angles: a mirror with three faces turns the beams, and the unit's angle
//! correction file (the `.dat`, which the host reads into [`At128Correction`]) says, per mirror
//! frame and channel, where each return points.
//!
//! A block's azimuth is the motor's, in 1/25,600 degree (the hundredths and the packet's fine
//! byte). Motor angles from `start[i]` to `end[i]` (both included, the first frame that holds
//! the angle wins) belong to frame `i`. A return of channel `c` at motor angle `a` in frame `i`
//! points at
//!
//! ```text
//! azimuth   = 2 (a - start[i]) - azimuth[c] + azimuth_adjust(c, a)
//! elevation = elevation[c] + elevation_adjust(c, a)
//! ```
//!
//! where the adjustments interpolate linearly, along the motor angle, a per-channel table of
//! 180 entries 2 degrees apart (entry 179 to 180 wraps to entry 0). Seen from above the azimuth
//! turns clockwise; 90 degrees is straight ahead, the middle of the unit's 30 to 150 degree
//! field: `x = d cos(el) sin(az)` forward, `y = d cos(el) cos(az)` left, `z = d sin(el)` up.
//!
//! Sources: TIER IV nebula's `AngleCorrectorCorrectionBased` (`get_corrected_azimuth`,
//! `get_corrected_elevation`, `find_field`), `HesaiCorrection::get_azimuth_adjust_v3` and the
//! point's `x = xy sin(az), y = xy cos(az)` in `hesai_decoder.hpp` (nebula commit 606ac41f);
//! Hesai's SDK 2.0 (`Udp4_3Parser::ComputeXYZI`, `ATCorrections::getAzimuthAdjust`) computes
//! the same. Nebula rounds an interpolated adjustment to 0.01 degree; Hesai's SDK and this
//! module do not (a difference of at most 0.005 degree).

use crate::error::ConfigError;

/// Channels of the AT128 and of its correction file.
pub const AT128_CHANNELS: usize = 128;
/// Frames a correction file may describe: its header's `frame_config` has 8 bytes, and
/// nebula's `HesaiCorrection` holds 8 start and end angles.
pub const MAX_FRAMES: usize = 8;
/// Azimuth units per degree: hundredths with a fine byte of 1/256 (nebula's
/// `PacketAT128E2X::degree_subdivisions = 100 * 256`; the SDK's `AZIMUTH_UNIT 25600`).
pub const UNITS_PER_DEG: u32 = 25_600;
/// Units in a turn.
pub const TURN_UNITS: u32 = 360 * UNITS_PER_DEG;
/// Entries of an adjustment table per channel (the SDK's `CORRECTION_AZIMUTH_NUM 180`).
pub const ADJUST_STEPS: usize = 180;
/// Motor angle from one adjustment entry to the next, units: 2 degrees (nebula's
/// `g_step3 = 200 * 256`; the SDK's `CORRECTION_AZIMUTH_STEP 200`, in hundredths).
pub const ADJUST_STEP_UNITS: u32 = 200 * 256;

/// An AT128 unit's angle correction (the `.dat` file's version 1.5 tables), with every angle
/// already multiplied by the file's resolution.
#[derive(Clone, Debug, PartialEq)]
pub struct At128Correction {
    /// Frames (mirror faces) described: the first this many `start` and `end` are used.
    pub frames: usize,
    /// Motor angle where each frame begins, units ([`UNITS_PER_DEG`]).
    pub start: [u32; MAX_FRAMES],
    /// Motor angle where each frame ends, units.
    pub end: [u32; MAX_FRAMES],
    /// Subtracted from twice the motor angle into the frame, per channel, units.
    pub azimuth: [i32; AT128_CHANNELS],
    /// Elevation of each channel, units, positive up.
    pub elevation: [i32; AT128_CHANNELS],
    /// Azimuth adjustment per channel and 2-degree motor step, in `adjust_unit` hundredths of
    /// a degree (the file's signed bytes).
    pub azimuth_adjust: [[i8; ADJUST_STEPS]; AT128_CHANNELS],
    /// Elevation adjustment, as `azimuth_adjust`.
    pub elevation_adjust: [[i8; ADJUST_STEPS]; AT128_CHANNELS],
    /// Hundredths of a degree per adjustment step: the file's resolution byte.
    pub adjust_unit: u8,
}

impl At128Correction {
    /// A correction with no frames and every angle zero, for the reader to fill.
    pub const fn empty() -> Self {
        Self {
            frames: 0,
            start: [0; MAX_FRAMES],
            end: [0; MAX_FRAMES],
            azimuth: [0; AT128_CHANNELS],
            elevation: [0; AT128_CHANNELS],
            azimuth_adjust: [[0; ADJUST_STEPS]; AT128_CHANNELS],
            elevation_adjust: [[0; ADJUST_STEPS]; AT128_CHANNELS],
            adjust_unit: 1,
        }
    }

    /// Whether it can decode: 1 to [`MAX_FRAMES`] frames whose bounds lie within a turn, an
    /// adjustment unit, channel azimuths within +-45 degrees and elevations within +-90.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let frames = self
            .start
            .get(..self.frames)
            .zip(self.end.get(..self.frames));
        let bounds_ok = frames
            .is_some_and(|(s, e)| self.frames > 0 && s.iter().chain(e).all(|&a| a < TURN_UNITS));
        let within = |v: &[i32], deg: i32| {
            v.iter()
                .all(|&a| a.unsigned_abs() <= (deg as u32) * UNITS_PER_DEG)
        };
        if bounds_ok
            && self.adjust_unit > 0
            && within(&self.azimuth, 45)
            && within(&self.elevation, 90)
        {
            Ok(())
        } else {
            Err(ConfigError::Calibration)
        }
    }

    /// The frame a motor angle (units, below a turn) lies in, if any.
    pub fn frame_of(&self, motor: u32) -> Option<usize> {
        let mut frames = self.start.iter().zip(&self.end).take(self.frames);
        frames.position(|(&s, &e)| between(s, e, motor))
    }

    /// Channel `channel`'s (azimuth, elevation) in degrees at motor angle `motor` (units) of
    /// frame `frame`: the module doc's formula, the azimuth not wrapped.
    pub fn angles_deg(&self, motor: u32, frame: usize, channel: usize) -> (f64, f64) {
        let start = self.start.get(frame).copied().unwrap_or(0);
        let into = (i64::from(motor) - i64::from(start)).rem_euclid(i64::from(TURN_UNITS));
        let units = |u: i64| u as f64 / f64::from(UNITS_PER_DEG);
        let az = units(2 * into - i64::from(self.azimuth.get(channel).copied().unwrap_or(0)))
            + self.adjust_deg(&self.azimuth_adjust, motor, channel);
        let el = units(i64::from(self.elevation.get(channel).copied().unwrap_or(0)))
            + self.adjust_deg(&self.elevation_adjust, motor, channel);
        (az, el)
    }

    /// An adjustment table's value for `channel` at motor angle `motor`, degrees.
    fn adjust_deg(
        &self,
        table: &[[i8; ADJUST_STEPS]; AT128_CHANNELS],
        motor: u32,
        channel: usize,
    ) -> f64 {
        let Some(row) = table.get(channel) else {
            return 0.0;
        };
        let i = (motor / ADJUST_STEP_UNITS) as usize % ADJUST_STEPS;
        let k = f64::from(motor % ADJUST_STEP_UNITS) / f64::from(ADJUST_STEP_UNITS);
        let at = |j: usize| f64::from(row.get(j % ADJUST_STEPS).copied().unwrap_or(0));
        let hundredths = (1.0 - k) * at(i) + k * at(i + 1);
        hundredths * f64::from(self.adjust_unit) * 0.01
    }
}

/// Whether `angle` lies from `start` to `end` (both included), wrapping past a turn when `end`
/// is below `start` (nebula's `angle_is_between`).
fn between(start: u32, end: u32, angle: u32) -> bool {
    if start <= end {
        start <= angle && angle <= end
    } else {
        angle <= end || start <= angle
    }
}

/// The point of a return `d` metres away at (azimuth, elevation) degrees, in the AT128's frame
/// (module doc).
pub(super) fn point((az_deg, el_deg): (f64, f64), d: f64) -> [f64; 3] {
    let (az, el) = (az_deg.to_radians(), el_deg.to_radians());
    let xy = d * libm::cos(el);
    [xy * libm::sin(az), xy * libm::cos(az), d * libm::sin(el)]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> At128Correction {
        let mut c = At128Correction::empty();
        c.frames = 3;
        let deg = |d: f64| (d * f64::from(UNITS_PER_DEG)) as u32;
        c.start[..3].copy_from_slice(&[deg(20.0), deg(140.0), deg(260.0)]);
        c.end[..3].copy_from_slice(&[deg(140.0), deg(260.0), deg(20.0)]);
        c.azimuth[5] = -61_440; // -2.4 degrees
        c.elevation[5] = 256_000; // 10 degrees
        c.azimuth_adjust[5][20] = 40;
        c.azimuth_adjust[5][21] = 20;
        c.elevation_adjust[5][20] = -10;
        c.adjust_unit = 2;
        c
    }

    #[test]
    fn frames_include_both_bounds_and_wrap_past_a_turn() {
        let c = sample();
        let deg = |d: f64| (d * f64::from(UNITS_PER_DEG)) as u32;
        assert_eq!(c.frame_of(deg(20.0)), Some(0));
        assert_eq!(c.frame_of(deg(140.0)), Some(0));
        assert_eq!(c.frame_of(deg(140.01)), Some(1));
        assert_eq!(c.frame_of(deg(300.0)), Some(2));
        assert_eq!(c.frame_of(deg(5.0)), Some(2));
        let mut two = c.clone();
        two.frames = 2;
        assert_eq!(two.frame_of(deg(300.0)), None);
        assert!(c.validate().is_ok());
        two.frames = 0;
        assert_eq!(two.validate(), Err(ConfigError::Calibration));
        let mut far = c.clone();
        far.elevation[0] = 91 * UNITS_PER_DEG as i32;
        assert_eq!(far.validate(), Err(ConfigError::Calibration));
    }

    #[test]
    fn corrected_angles_follow_the_formula() {
        let c = sample();
        // Motor 41 degrees: entry 20 (40 degrees) halfway to entry 21; frame 0 from 20 degrees.
        let motor = 41 * UNITS_PER_DEG;
        let (az, el) = c.angles_deg(motor, 0, 5);
        // 2 x 21 + 2.4 + (40 + 20) / 2 x 2 hundredths.
        assert!((az - (42.0 + 2.4 + 0.6)).abs() < 1e-12, "{az}");
        assert!((el - (10.0 - 0.1)).abs() < 1e-12, "{el}");
        // Frame 2 wraps: motor 5 degrees is 105 degrees into it.
        let (az, _) = c.angles_deg(5 * UNITS_PER_DEG, 2, 0);
        assert!((az - 210.0).abs() < 1e-12);
        // Straight ahead at azimuth 90: x forward.
        let p = point((90.0, 0.0), 10.0);
        assert!((p[0] - 10.0).abs() < 1e-12 && p[1].abs() < 1e-12 && p[2] == 0.0);
        // Out of range indices read as zero, never panic.
        assert_eq!(c.angles_deg(motor, 99, 999), (82.0, 0.0));
    }
}
