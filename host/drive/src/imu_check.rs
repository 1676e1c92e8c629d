//! The IMU consistency check: on each frame the gyroscope prior predicted, the rotation the
//! gyroscope measured over the frame is compared with the rotation ICP registered, before the
//! map takes the frame. ICP aligns the scan with the map whatever the prior said, so the
//! registration measures how wrong the prior is. A correct gyroscope disagrees with ICP by its
//! noise and bias over one frame (a few thousandths of a radian) plus ICP's rotation error
//! (about a tenth of a degree); a gyroscope in deg/s, with a flipped axis, dead or another
//! recording's disagrees by a large part of the frame's rotation. Such a frame is registered
//! again from the constant-velocity model, as without the prior
//! (`Odometry::register_frame_checked`), so a wrong prior never reaches the map; a frame whose
//! rates are beyond any gyroscope's range is not given the prior at all (a lone corrupt sample
//! is left out instead, see [`corrupt_samples`]). Either rejects the
//! IMU: the next frames are predicted and deskewed without it while the gyroscope's rotation,
//! still measured, disagrees; the first rejection warns once, with the likely cause read from
//! it and the frames after it. The prior comes back after enough frames that turn and agree.
//!
//! The driver runs it only with the prior on: a run without an IMU never reaches this module.

use crate::outcome::FrameMeta;
use kiss_odom_core::ImuSample;
use nalgebra::{UnitQuaternion, Vector3};

/// Disagreement (rad) a correct gyroscope stays under on a frame that does not turn: white
/// noise of 2.6e-4 rad/s/sqrt(Hz) integrates to 1e-4 rad over a 0.1 s sweep, a 0.01 rad/s
/// turn-on bias (before the prior learns it) to 1e-3 rad, and ICP's rotation error per frame
/// is a few thousandths; 0.02 rad (1.1 degrees) is several times their sum.
pub const FLOOR_RAD: f64 = 0.02;
/// The first measured frame's floor (rad): a sweep's turn at 1 rad/s and 10 Hz, which ICP
/// on a map of one undeskewed scan may miss entirely (a generated drone's right gyroscope
/// turned 0.03 rad over its first frame while that registration turned about none).
pub const FIRST_FLOOR_RAD: f64 = 0.1;
/// The part of the frame's rotation a correct gyroscope may add to the disagreement: scale
/// errors of a few percent and a clock offset of a few milliseconds on a fast turn.
pub const SCALE: f64 = 0.2;
/// Rotation over a frame (rad) from which a wrong gyroscope shows: a dead one disagrees by
/// the whole rotation, beyond `FLOOR_RAD + SCALE * rotation` from 0.025 rad; frames that turn
/// less tell nothing either way.
pub const TELLING_RAD: f64 = 0.05;
/// Frames that turn by at least [`TELLING_RAD`] and agree, in a row, before a rejected
/// gyroscope predicts again; doubled at each new rejection, so that an IMU that keeps
/// disagreeing stays out.
pub const RESUME_FRAMES: u32 = 10;
/// A rate no gyroscope in use measures (rad/s): 2000 degrees/s, the usual full scale.
pub const FULL_SCALE: f64 = 35.0;

/// What one frame gave the check: the gyroscope's rotation and ICP's over the frame, and the
/// samples' mean rate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured {
    /// The gyroscope's rotation vector over the frame (rad, LiDAR axes, less the bias).
    pub gyro: Vector3<f64>,
    /// ICP's registered rotation vector over the frame (rad).
    pub icp: Vector3<f64>,
    /// The frame's interval (s).
    pub dt: f64,
    /// The mean of the samples' rates as given, in LiDAR axes (rad/s): unlike `gyro`, not
    /// wrapped past half a turn when the rates are far too large (deg/s read as rad/s).
    pub rate: Vector3<f64>,
}

/// The likely reason a gyroscope disagrees with ICP.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cause {
    /// Rates about 57.3 times ICP's: degrees per second.
    Degrees,
    /// Rates beyond any gyroscope's range on every frame, not 57.3 times ICP's: corrupt data.
    BeyondRange,
    /// No rotation while ICP turns.
    Dead,
    /// One axis (0 x, 1 y, 2 z, LiDAR axes) turning the other way.
    FlippedAxis(usize),
    /// Two axes turning the other way: a rotation by 180 degrees about the third.
    Rotated180(usize),
    /// None of these.
    Unknown,
}

impl Cause {
    /// The cause as a user reads it.
    pub fn describe(self) -> String {
        const AXIS: [&str; 3] = ["x", "y", "z"];
        match self {
            Self::Degrees => "its rates are about 57.3 times ICP's: a gyroscope in degrees per \
                              second, where rad/s is expected"
                .into(),
            Self::BeyondRange => format!(
                "its rates are beyond {FULL_SCALE} rad/s on every frame, more than any \
                 gyroscope measures, and not 57.3 times ICP's: corrupt data, or a scale other \
                 than rad/s or deg/s"
            ),
            Self::Dead => "it measures no rotation while ICP turns: a dead gyroscope".into(),
            Self::FlippedAxis(a) => format!(
                "its {} axis (LiDAR axes) turned opposite to ICP's: a flipped axis in the data \
                 or in the extrinsic, or another recording's IMU",
                AXIS[a]
            ),
            Self::Rotated180(a) => format!(
                "two of its axes turned opposite to ICP's: an extrinsic off by 180 degrees about \
                 {}, or another recording's IMU",
                AXIS[a]
            ),
            Self::Unknown => "it turns otherwise than ICP: another recording's IMU, a wrong \
                              extrinsic or a clock offset"
                .into(),
        }
    }
}

/// Whether a sample's rates (rad/s) are within what a gyroscope measures: finite and below
/// [`FULL_SCALE`].
pub fn plausible(gyro: &[f64; 3]) -> bool {
    let rate = Vector3::from(*gyro).norm();
    rate.is_finite() && rate <= FULL_SCALE
}

/// The angle (rad) between the gyroscope's rotation and ICP's over a frame.
pub fn disagreement(gyro: &Vector3<f64>, icp: &Vector3<f64>) -> f64 {
    let g = UnitQuaternion::from_scaled_axis(*gyro);
    let r = UnitQuaternion::from_scaled_axis(*icp);
    g.angle_to(&r)
}

/// The largest disagreement (rad) a correct gyroscope gives on a frame ICP turned by `icp`;
/// on the `first` frame measured, registered against a first scan that nothing deskewed (and
/// judged by its registration from the constant-velocity model), [`FIRST_FLOOR_RAD`] and as
/// much again as ICP's rotation: ICP there misses most of the sweep's turn.
pub fn tolerance(icp: &Vector3<f64>, first: bool) -> f64 {
    if first {
        FIRST_FLOOR_RAD + icp.norm()
    } else {
        FLOOR_RAD + SCALE * icp.norm()
    }
}

/// Whether the gyroscope's rotation agrees with ICP's (on the `first` frame measured or a
/// later one).
pub fn agrees(gyro: &Vector3<f64>, icp: &Vector3<f64>, first: bool) -> bool {
    disagreement(gyro, icp) <= tolerance(icp, first)
}

/// Frames registered without the gyroscope after its first rejection from which, with the
/// rejected frame itself (registered again from the constant-velocity model), the warning
/// names the cause: ICP then follows the LiDAR alone.
pub const CAUSE_FRAMES: usize = 5;

/// The likely cause of a disagreement, read from frames registered without the gyroscope
/// (its rotation over each taken from the mean rate, which does not wrap past half a turn):
/// no rotation while ICP turns; rotations along ICP's (a correlation above 0.3) but 30-120
/// times as large (deg/s: 57.3); else, mean rates beyond [`FULL_SCALE`] on every frame; one or
/// two axes whose rotations run against ICP's over the frames (a correlation below -0.3 on an
/// axis that turned); else unknown. ICP's rotations on these frames lag and
/// err (their prediction came from a frame that followed the wrong prior), but keep their
/// signs and rough size: hence sums over the frames, not a frame's agreement.
pub fn cause(frames: &[Measured]) -> Cause {
    let sum = |f: &dyn Fn(&Measured) -> f64| frames.iter().map(f).sum::<f64>();
    let turned = sum(&|m| m.icp.norm_squared());
    if turned < TELLING_RAD * TELLING_RAD {
        return Cause::Unknown;
    }
    let gyro = sum(&|m| (m.rate * m.dt).norm_squared());
    if gyro < 0.04 * turned {
        return Cause::Dead;
    }
    // Rates 30-120 times as large as ICP's (the RMS ratio: 57.3 for deg/s) along its rotations
    // (a correlation above 0.3 over the frames): read before the axes, as ICP's smaller axes
    // can run a frame late on a fast-rocking sensor and look flipped beside a 57-fold gyroscope.
    let both = sum(&|m| (m.rate * m.dt).dot(&m.icp));
    let correlation = both / (gyro * turned).sqrt();
    if correlation > 0.3 && (30.0..120.0).contains(&(gyro / turned).sqrt()) {
        return Cause::Degrees;
    }
    if !frames.iter().any(|m| m.rate.norm() <= FULL_SCALE) {
        return Cause::BeyondRange;
    }
    let against: Vec<usize> = (0..3)
        .filter(|&i| {
            let icp = sum(&|m| m.icp[i] * m.icp[i]);
            let g = sum(&|m| (m.rate[i] * m.dt).powi(2));
            let both = sum(&|m| m.rate[i] * m.dt * m.icp[i]);
            icp >= 0.05 * turned && both < -0.3 * (icp * g).sqrt()
        })
        .collect();
    match against[..] {
        [a] => Cause::FlippedAxis(a),
        [a, b] => Cause::Rotated180(3 - a - b),
        _ => Cause::Unknown,
    }
}

/// Whether a frame's samples hold a corrupt one: a rate beyond any gyroscope's range that
/// stands out from the frame's mean rate (rates in deg/s on a fast turn are all beyond it,
/// none standing out).
pub fn corrupt_samples(samples: &[ImuSample<f64>]) -> bool {
    let peak = samples
        .iter()
        .map(|s| Vector3::from(s.gyro).norm())
        .fold(0.0, f64::max);
    peak > FULL_SCALE && peak > 4.0 * mean_rate(samples).norm()
}

/// The mean of the samples' rates as given (rad/s, IMU axes; zero without samples).
pub fn mean_rate(samples: &[ImuSample<f64>]) -> Vector3<f64> {
    let sum = samples
        .iter()
        .map(|s| Vector3::from(s.gyro))
        .sum::<Vector3<f64>>();
    sum / samples.len().max(1) as f64
}

/// The check's state over a run: see the module doc.
#[derive(Clone, Debug, Default)]
pub struct ImuCheck {
    /// Whether a frame's rotation was measured yet: the first is not judged.
    started: bool,
    rejecting: bool,
    /// Telling frames in a row that agreed while rejecting.
    agreeing: u32,
    /// Rejections so far (each begins when the gyroscope disagrees while in use).
    episodes: u32,
    /// The first rejection (frame, source, disagreement and tolerance), until the frames
    /// after it name its cause.
    first: Option<(usize, String, f64, f64)>,
    /// The first rejected frame and those measured after it, up to [`CAUSE_FRAMES`] more.
    after: Vec<Measured>,
    warning: Option<String>,
    /// Whether a corrupt sample was warned about.
    corrupt_said: bool,
}

impl ImuCheck {
    /// A frame with a corrupt sample (see [`corrupt_samples`]), left out of its samples: one
    /// sample says nothing of the gyroscope's others. Warns on the first, unless a
    /// rejection's warning is due.
    pub fn corrupt_sample(&mut self, meta: &FrameMeta) {
        if self.corrupt_said || self.first.is_some() || self.warning.is_some() {
            return;
        }
        self.corrupt_said = true;
        self.warning = Some(format!(
            "frame {} ({}): an IMU sample beyond {FULL_SCALE} rad/s, more than any gyroscope \
             measures and far from the frame's others: a corrupt sample, left out (the \
             gyroscope prior goes on with the others)",
            meta.index, meta.source
        ));
    }

    /// Whether frames are judged yet (the first measured one is not).
    pub fn judging(&self) -> bool {
        self.started
    }

    /// Whether the next frame is to be predicted without the prior.
    pub fn rejecting(&self) -> bool {
        self.rejecting
    }

    /// The warning of the first rejection, once, when the frames after it named the cause;
    /// at the end of a run (`end`), with what those frames tell.
    pub fn warning(&mut self, end: bool) -> Option<String> {
        if end && self.warning.is_none() {
            self.name_cause();
        }
        self.warning.take()
    }

    fn name_cause(&mut self) {
        let Some((index, source, off, tol)) = self.first.take() else {
            return;
        };
        self.warning = Some(format!(
            "frame {index} ({source}): the gyroscope's rotation over the frame is {off:.3} rad \
             away from the one ICP registered (a correct gyroscope stays within {tol:.3} rad): \
             {}; the next frames are predicted and deskewed without the gyroscope prior while \
             it disagrees (frames.csv imu_prior = rejected, summary.json imu_rejected_frames)",
            cause(&self.after).describe()
        ));
        self.after = Vec::new();
    }

    /// Judges a registered frame whose gyroscope rotation was measured (whether or not it
    /// predicted the frame): returns the disagreement (rad) and whether it agrees, and moves
    /// the state for the next frame. The first such frame is not judged (it agrees): it is
    /// registered against the first scan alone, which no motion deskewed, and a turning
    /// sensor's first scan is smeared by its turn: ICP's rotation then is off by a large
    /// part of the sweep's own (0.087 rad of 0.1 with a correct gyroscope on a generated
    /// drone flight). A frame whose registration the check `refused` before the map took it
    /// (and redid without the prior) disagrees, whatever the redone registration reads.
    pub fn judge(&mut self, meta: &FrameMeta, m: &Measured, refused: bool) -> (f64, bool) {
        let off = disagreement(&m.gyro, &m.icp);
        let first = !core::mem::replace(&mut self.started, true);
        let ok = !refused && off <= tolerance(&m.icp, first) && off.is_finite();
        // The cause is read from the frames from the first rejection on, registered without
        // the gyroscope.
        if self.first.is_some() {
            self.after.push(*m);
            if self.after.len() > CAUSE_FRAMES {
                self.name_cause();
            }
        }
        if !ok {
            self.agreeing = 0;
            if !self.rejecting {
                self.rejecting = true;
                self.episodes += 1;
                if self.episodes == 1 {
                    self.first = Some((
                        meta.index,
                        meta.source.clone(),
                        off,
                        tolerance(&m.icp, first),
                    ));
                    // Redone without the gyroscope, the frame tells the cause too (and a
                    // corrupt sample is in it alone).
                    self.after.push(*m);
                }
            }
        } else if self.rejecting && m.icp.norm() >= TELLING_RAD {
            self.agreeing += 1;
            let needed = RESUME_FRAMES << (self.episodes.saturating_sub(1)).min(6);
            if self.agreeing >= needed {
                self.rejecting = false;
                self.agreeing = 0;
            }
        }
        (off, ok)
    }
}

#[cfg(test)]
mod tests;
