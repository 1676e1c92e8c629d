//! The cycle stop: a registration with plane terms that goes round in a loop stops.
//!
//! With plane terms, the system Gauss-Newton solves changes in steps as the iterate moves: a
//! source point that crosses into another voxel reads another neighbourhood's normal, or none,
//! and the planar share `a` moves with it. Where the optimum sits on such a step, the iterate can
//! settle into a loop: on kitti-mini 02 frame 4, `dx` alternates between two opposite twists of
//! norm 1.4e-4 from iteration 11 to the cap of 500, and the iterate between two poses 0.14 mm
//! apart. `|dx| < gamma` is never met, though the iterate no longer goes anywhere. Loops of 2, 3,
//! 4 and 6 iterations, some of them a centimetre across, take up most of the time of the preset
//! on the drives where the scene is least planar or most degenerate (BENCHMARKS.md, "The accurate
//! preset").
//!
//! The stop is `gamma`'s test over more than one step: the registration also stops when the
//! iterate comes back within `gamma` (the norm of the twist between them) of one of the last
//! [`LEN`] iterates before the one it came from. The pose is then the current iterate, one of
//! the loop's, as the cap would have left it.

use crate::geometry::Pose;
use crate::lie::se3_log;
use crate::scalar::Real;

/// Iterates kept: loops of up to this many iterations are found.
pub const LEN: usize = 8;

/// The last [`LEN`] iterates of a registration, oldest overwritten first.
pub(super) struct Recent<T: Real> {
    poses: [Pose<T>; LEN],
    /// Iterates pushed so far.
    count: usize,
}

impl<T: Real> Recent<T> {
    /// Starting from the iterate `start`.
    pub(super) fn new(start: Pose<T>) -> Self {
        Self {
            poses: [start; LEN],
            count: 1,
        }
    }

    /// Whether `pose` is within `gamma` of a kept iterate other than the last one (the last one
    /// is `|dx| < gamma`'s own test).
    pub(super) fn returns_to(&self, pose: &Pose<T>, gamma: T) -> bool {
        (2..=LEN.min(self.count)).any(|back| {
            let before = &self.poses[(self.count - back) % LEN];
            se3_log(&(before.inverse() * pose)).norm() < gamma
        })
    }

    /// Keeps `pose` as the newest iterate.
    pub(super) fn push(&mut self, pose: Pose<T>) {
        self.poses[self.count % LEN] = pose;
        self.count += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lie::se3_exp;
    use nalgebra::Vector6;

    fn step(x: f64) -> Pose<f64> {
        se3_exp(&Vector6::new(x, 0.0, 0.0, 0.0, 0.0, x / 2.0))
    }

    #[test]
    fn a_loop_of_two_to_len_iterates_is_found_and_a_descent_is_not() {
        let gamma = 1e-4;
        for len in 2..=LEN {
            // Round a loop of `len` poses 1 mm apart, twice: found exactly when the iterate
            // comes back to where it was `len` iterates before.
            let at = |k: usize| step(1e-3 * (k % len) as f64);
            let mut recent = Recent::new(at(0));
            for k in 1..2 * len {
                assert_eq!(
                    recent.returns_to(&at(k), gamma),
                    k >= len,
                    "loop {len}, iterate {k}"
                );
                recent.push(at(k));
            }
        }
        // A descent whose steps halve never comes back while they are above gamma (2^-6 cm).
        let mut recent = Recent::new(step(0.0));
        let mut x = 0.0;
        for k in 0..7 {
            x += 1e-2 / f64::from(1 << k);
            assert!(!recent.returns_to(&step(x), gamma), "descent, step {k}");
            recent.push(step(x));
        }
        // The bound is strict, as `|dx| < gamma` is.
        let mut recent = Recent::new(step(0.0));
        recent.push(step(1e-3));
        let d = se3_log(&step(2e-3)).norm();
        assert!(!recent.returns_to(&step(2e-3), d));
        assert!(recent.returns_to(&step(2e-3), d * (1.0 + 1e-9)));
        // The last iterate alone does not count: that is the step's own test.
        let mut recent = Recent::new(step(0.0));
        recent.push(step(1e-3));
        assert!(!recent.returns_to(&step(1e-3), gamma));
        // Nor does one older than LEN iterates.
        let mut recent = Recent::new(step(0.0));
        for k in 1..=LEN {
            recent.push(step(1e-3 * k as f64));
        }
        assert!(!recent.returns_to(&step(0.0), gamma));
        assert!(recent.returns_to(&step(1e-3), gamma));
    }
}
