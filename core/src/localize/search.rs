//! The bounded search that recovers a lost pose: a fixed grid of starts around the pose
//! dead-reckoned from the last good one, a few per frame, each registered to the prior map;
//! once the grid is done, the best registration is taken if it is good and unambiguous.
//!
//! The grid is 7 x 7 positions 2 m apart (out to 6 m in `x` and `y`) times 7 headings 10
//! degrees apart (out to 30 degrees): 343 starts, so a start lies within 1.4 m and 5 degrees
//! of any pose inside the grid, which is the basin a registration with a 3 m gate converges
//! from. A result is kept as a correction of the map frame (`registered dead_reckoned^-1`), so
//! it stays valid as the dead-reckoned pose moves on over the search's frames.

use crate::geometry::Pose;
use crate::scalar::Real;
use nalgebra::{Translation3, UnitQuaternion, Vector3};

/// Positions per axis and headings of the grid.
const SIDE: usize = 7;
/// Starts in the grid.
pub const STARTS: usize = SIDE * SIDE * SIDE;
/// Spacing of the positions (m).
pub const STEP_M: f64 = 2.0;
/// Spacing of the headings (degrees).
pub const STEP_DEG: f64 = 10.0;
/// Two results farther apart than this (m) are different answers.
const DISTINCT_M: f64 = 1.0;

/// Start `k` of the grid around `at`.
pub(super) fn start<T: Real>(k: usize, at: &Pose<T>) -> Pose<T> {
    let half = (SIDE / 2) as f64;
    let (a, b, c) = (k % SIDE, (k / SIDE) % SIDE, k / (SIDE * SIDE));
    let dx = (a as f64 - half) * STEP_M;
    let dy = (b as f64 - half) * STEP_M;
    let yaw = ((c as f64 - half) * STEP_DEG).to_radians();
    let t = at.translation.vector + Vector3::new(T::of(dx), T::of(dy), T::zero());
    let r = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), T::of(yaw)) * at.rotation;
    Pose::from_parts(Translation3::from(t), r)
}

/// The search in progress: the next start and the best two distinct results so far.
#[derive(Clone, Copy, Debug)]
pub(super) struct Search<T: Real> {
    pub(super) next: usize,
    best: Option<(Pose<T>, T)>,
    runner_up: T,
}

impl<T: Real> Search<T> {
    pub(super) fn new() -> Self {
        Self {
            next: 0,
            best: None,
            runner_up: T::zero(),
        }
    }

    pub(super) fn done(&self) -> bool {
        self.next >= STARTS
    }

    /// Notes a registration's correction and inlier share.
    pub(super) fn note(&mut self, correction: Pose<T>, share: T) {
        match self.best {
            Some((best, s)) if share <= s => {
                if apart(&best, &correction) {
                    self.runner_up = self.runner_up.max(share);
                }
            }
            Some((best, s)) => {
                if apart(&best, &correction) {
                    self.runner_up = self.runner_up.max(s);
                }
                self.best = Some((correction, share));
            }
            None => self.best = Some((correction, share)),
        }
    }

    /// The best correction if its share reaches `good` and no distinct one comes within
    /// `margin` of it.
    pub(super) fn verdict(&self, good: T, margin: T) -> Option<Pose<T>> {
        let (c, s) = self.best?;
        (s >= good && s - self.runner_up >= margin).then_some(c)
    }
}

fn apart<T: Real>(a: &Pose<T>, b: &Pose<T>) -> bool {
    (a.translation.vector - b.translation.vector).norm() > T::of(DISTINCT_M)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_covers_six_metres_and_thirty_degrees_around_the_pose_in_order() {
        let at = Pose::<f64>::new(Vector3::new(10.0, -5.0, 1.0), Vector3::new(0.0, 0.0, 0.5));
        let centre = start(STARTS / 2, &at);
        assert!((centre.translation.vector - at.translation.vector).norm() < 1e-12);
        assert!(centre.rotation.angle_to(&at.rotation) < 1e-12);
        let corner = start(0, &at);
        let d = corner.translation.vector - at.translation.vector;
        assert_eq!((d.x, d.y, d.z), (-6.0, -6.0, 0.0));
        assert!((corner.rotation.angle_to(&at.rotation) - 30f64.to_radians()).abs() < 1e-12);
        let mut far = 0.0f64;
        for k in 0..STARTS {
            let s = start(k, &at);
            far = far.max((s.translation.vector - at.translation.vector).norm());
        }
        assert!((far - 72f64.sqrt()).abs() < 1e-9);
    }

    #[test]
    fn an_answer_needs_a_good_share_and_no_distinct_rival_close_to_it() {
        let p = |x: f64| Pose::<f64>::new(Vector3::new(x, 0.0, 0.0), Vector3::zeros());
        let mut s = Search::new();
        s.note(p(0.0), 0.7);
        s.note(p(0.5), 0.75);
        assert!(
            s.verdict(0.5, 0.1).is_some(),
            "a near twin is the same answer"
        );
        s.note(p(4.0), 0.7);
        assert!(
            s.verdict(0.5, 0.1).is_none(),
            "a rival 4 m off at 0.70 against 0.75"
        );
        assert_eq!(s.verdict(0.5, 0.05).map(|c| c.translation.x), Some(0.5));
        assert!(s.verdict(0.8, 0.0).is_none(), "below the good share");
    }
}
