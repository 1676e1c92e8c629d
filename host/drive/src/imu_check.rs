//! The IMU consistency check: after each frame the gyroscope prior predicted, the rotation the
//! gyroscope measured over the frame is compared with the rotation ICP registered. ICP aligns
//! the scan with the map whatever the prior said, so the registration measures how wrong the
//! prior is. A correct gyroscope disagrees with ICP by its noise and bias over one frame (a
//! few thousandths of a radian) plus ICP's rotation error (about a tenth of a degree); a
//! gyroscope in deg/s, with a flipped axis, dead, corrupt or another recording's disagrees by a
//! large part of the frame's rotation. On such a frame the check rejects the IMU: the next
//! frames are predicted and deskewed as without the prior (the constant-velocity model) while
//! the gyroscope's rotation, still measured, disagrees, and the first rejection warns once with
//! the likely cause. The prior comes back after enough frames that turn and agree.
//!
//! The driver runs it only with the prior on: a run without an IMU never reaches this module.

use crate::outcome::FrameMeta;
use nalgebra::{UnitQuaternion, Vector3};

/// Disagreement (rad) a correct gyroscope stays under on a frame that does not turn: white
/// noise of 2.6e-4 rad/s/sqrt(Hz) integrates to 1e-4 rad over a 0.1 s sweep, a 0.01 rad/s
/// turn-on bias (before the prior learns it) to 1e-3 rad, and ICP's rotation error per frame
/// is a few thousandths; 0.02 rad (1.1 degrees) is several times their sum.
pub const FLOOR_RAD: f64 = 0.02;
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
/// raw samples' rates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured {
    /// The gyroscope's rotation vector over the frame (rad, LiDAR axes, less the bias).
    pub gyro: Vector3<f64>,
    /// ICP's registered rotation vector over the frame (rad).
    pub icp: Vector3<f64>,
    /// The frame's interval (s).
    pub dt: f64,
    /// Length of the mean of the samples' rates as given (rad/s).
    pub mean_rate: f64,
    /// The largest sample rate as given (rad/s).
    pub peak_rate: f64,
}

/// The likely reason a gyroscope disagrees with ICP.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cause {
    /// Rates about 57.3 times ICP's: degrees per second.
    Degrees,
    /// A sample beyond any gyroscope's range.
    Spike,
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
            Self::Spike => format!(
                "a sample beyond {FULL_SCALE} rad/s, more than any gyroscope measures: a corrupt \
                 sample"
            ),
            Self::Dead => "it measures no rotation while ICP turns: a dead gyroscope".into(),
            Self::FlippedAxis(a) => format!(
                "its {} axis (LiDAR axes) turns opposite to ICP's: a flipped axis in the data or \
                 in the extrinsic",
                AXIS[a]
            ),
            Self::Rotated180(a) => format!(
                "two of its axes turn opposite to ICP's: an extrinsic off by 180 degrees about {}",
                AXIS[a]
            ),
            Self::Unknown => "it turns otherwise than ICP: another recording's IMU, a wrong \
                              extrinsic or a clock offset"
                .into(),
        }
    }
}

/// The angle (rad) between the gyroscope's rotation and ICP's over a frame.
pub fn disagreement(gyro: &Vector3<f64>, icp: &Vector3<f64>) -> f64 {
    let g = UnitQuaternion::from_scaled_axis(*gyro);
    let r = UnitQuaternion::from_scaled_axis(*icp);
    g.angle_to(&r)
}

/// The largest disagreement (rad) a correct gyroscope gives on a frame ICP turned by `icp`.
pub fn tolerance(icp: &Vector3<f64>) -> f64 {
    FLOOR_RAD + SCALE * icp.norm()
}

/// Whether the gyroscope's rotation agrees with ICP's.
pub fn agrees(gyro: &Vector3<f64>, icp: &Vector3<f64>) -> bool {
    disagreement(gyro, icp) <= tolerance(icp)
}

/// The likely cause of a disagreement.
pub fn cause(m: &Measured) -> Cause {
    let icp_rate = m.icp.norm() / m.dt;
    let ratio = m.mean_rate / icp_rate;
    if icp_rate > 0.0 && (40.0..80.0).contains(&ratio) {
        return Cause::Degrees;
    }
    if m.peak_rate > FULL_SCALE {
        return Cause::Spike;
    }
    if m.mean_rate * m.dt < 0.2 * m.icp.norm() {
        return Cause::Dead;
    }
    let flipped = |axes: &[usize]| {
        let mut g = m.gyro;
        for &a in axes {
            g[a] = -g[a];
        }
        agrees(&g, &m.icp)
    };
    if let Some(a) = (0..3).find(|&a| flipped(&[a])) {
        return Cause::FlippedAxis(a);
    }
    if let Some(a) = (0..3).find(|&a| flipped(&[(a + 1) % 3, (a + 2) % 3])) {
        return Cause::Rotated180(a);
    }
    Cause::Unknown
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
    /// The first rejection (frame, source, disagreement and tolerance), until the next
    /// measured frame names its cause.
    first: Option<(usize, String, f64, f64)>,
    warning: Option<String>,
}

impl ImuCheck {
    /// Whether the next frame is to be predicted without the prior.
    pub fn rejecting(&self) -> bool {
        self.rejecting
    }

    /// The warning of the first rejection, once.
    pub fn warning(&mut self) -> Option<String> {
        self.warning.take()
    }

    /// Judges a registered frame whose gyroscope rotation was measured (whether or not it
    /// predicted the frame): returns the disagreement (rad) and whether it agrees, and moves
    /// the state for the next frame. The first such frame is not judged (it agrees): it is
    /// registered against the first scan alone, which no motion deskewed, and a turning
    /// sensor's first scan is smeared by its turn: ICP's rotation then is off by a large
    /// part of the sweep's own (0.087 rad of 0.1 with a correct gyroscope on a generated
    /// drone flight).
    pub fn judge(&mut self, meta: &FrameMeta, m: &Measured) -> (f64, bool) {
        let off = disagreement(&m.gyro, &m.icp);
        if !core::mem::replace(&mut self.started, true) {
            return (off, true);
        }
        let ok = off <= tolerance(&m.icp) && off.is_finite();
        // The frame that disagreed was registered with the wrong rotation, which ICP follows
        // part of the way: the cause is read from the next measured frame, registered
        // without it.
        if let Some((index, source, first_off, first_tol)) = self.first.take() {
            self.warning = Some(format!(
                "frame {index} ({source}): the gyroscope's rotation over the frame is \
                 {first_off:.3} rad away from the one ICP registered (a correct gyroscope stays \
                 within {first_tol:.3} rad): {}; the next frames are predicted and deskewed \
                 without the gyroscope prior while it disagrees (frames.csv imu_prior = \
                 rejected, summary.json imu_rejected_frames)",
                cause(m).describe()
            ));
        }
        if !ok {
            self.agreeing = 0;
            if !self.rejecting {
                self.rejecting = true;
                self.episodes += 1;
                if self.episodes == 1 {
                    self.first = Some((meta.index, meta.source.clone(), off, tolerance(&m.icp)));
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
