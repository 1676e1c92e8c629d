//! A second drive through the first run's scene, for localization in a prior map: the map is
//! built from the first run, the revisit is scored against it.
//!
//! The scene is the first run's (same profile, seed, frames and sensor give the same route and
//! the same objects), changed as [`crate::city::changes`] describes. The sensor drives the same
//! route the other way, [`lateral_offset`] to the side (the other lane), from where the first
//! run's last sweep ended back towards where its first began, at 60-95 % of the first run's
//! mean speed, so that it stays on the stretch the first run swept. Its ground truth is in the
//! first run's frame (the sensor at the end of the first run's first sweep), so its first pose
//! is not the identity; [`crate::writer::INITIAL_POSE`] states that pose on its own.

use crate::profile::Profile;
use crate::trajectory::PoseM;
use anyhow::{bail, Result};
use serde::Serialize;

/// Share of the scene's objects changed when none is asked for (`--changes`).
pub const DEFAULT_CHANGES: f64 = 0.1;

/// The revisit's speed band as fractions of the first run's mean speed: never more than the
/// first run covered.
pub const SPEED_SHARE: (f64, f64) = (0.6, 0.95);

/// A second drive through the first run's scene.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Revisit {
    /// Share of the scene's objects (parked cars first, then structures) moved, turned or
    /// removed, in `0..=1`; at least [`crate::city::changes::CAR_SHARE`] of the parked cars
    /// change and a new wall stands beside the route whatever the share.
    pub changes: f64,
}

impl Default for Revisit {
    fn default() -> Self {
        Self {
            changes: DEFAULT_CHANGES,
        }
    }
}

impl Revisit {
    /// Checks the share; the message names the option.
    pub fn validate(&self) -> Result<()> {
        if !(0.0..=1.0).contains(&self.changes) {
            bail!("changes must be a fraction in 0..=1");
        }
        Ok(())
    }
}

/// How far (m) left of the route the revisit drives: the other lane, or less where the scene
/// keeps less clearance (racks 1.4 m from a warehouse route, tunnel structure 2.5 m).
pub fn lateral_offset(profile: Profile) -> f64 {
    match profile {
        Profile::Warehouse => 0.5,
        Profile::Corridor | Profile::Tunnel => 1.0,
        _ => 1.75,
    }
}

/// Roll, pitch and yaw (rad) of a rotation `Rz(yaw) Ry(pitch) Rx(roll)`.
pub fn roll_pitch_yaw(pose: &PoseM) -> [f64; 3] {
    let r = pose.rotation.matrix();
    let yaw = libm::atan2(r[(1, 0)], r[(0, 0)]);
    let pitch = libm::atan2(-r[(2, 0)], libm::hypot(r[(0, 0)], r[(1, 0)]));
    let roll = libm::atan2(r[(2, 1)], r[(2, 2)]);
    [roll, pitch, yaw]
}

#[cfg(test)]
mod tests;
