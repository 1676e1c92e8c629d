//! Warnings for the gyroscope prior (`[imu] enabled`): a frame that cannot use it is predicted
//! and deskewed with the constant-velocity model instead, a pose the user did not ask for.
//! Each reason warns once per run, on the first frame it happens; `frames.csv`'s `imu_prior`
//! says which frames.

use crate::outcome::Outcome;
use kiss_odom_core::Prior;

/// The reasons already warned about in this run.
#[derive(Clone, Copy, Debug, Default)]
pub struct PriorWarnings {
    said: [bool; 3],
}

impl PriorWarnings {
    /// The warning `outcome` raises for the first time in this run, if any.
    pub fn check(&mut self, outcome: &Outcome) -> Option<String> {
        let (i, why) = match outcome.imu?.prior {
            Prior::NoSamples => (0, "no IMU sample came with it"),
            Prior::Gap => (
                1,
                "its IMU samples leave a gap longer than imu.max_gap (an IMU that stopped, or \
                 a clock offset: imu.time_offset)",
            ),
            Prior::BadSamples => (2, "its IMU samples are out of time order or not finite"),
            Prior::Used(_) | Prior::First => return None,
        };
        if core::mem::replace(&mut self.said[i], true) {
            return None;
        }
        Some(format!(
            "frame {} ({}): {why}: predicted and deskewed without the gyroscope prior, as the \
             reference does; later frames for the same reason are not warned about \
             (frames.csv imu_prior)",
            outcome.meta.index, outcome.meta.source
        ))
    }
}
