//! A revisit's trajectory: the same route driven the other way, beside it, with a speed,
//! body motion and swings of its own.

use super::{Reverse, Speed, Trajectory, Wave};
use crate::rng::{Purpose, Stream};

impl Trajectory {
    /// This trajectory's route driven backwards from its arc length `start` (m), `lateral`
    /// metres left of it (in the route's own direction), at a speed in `speed` (m/s, entered
    /// moving), with body motion drawn from `seed`'s [`Purpose::Revisit`] stream.
    pub fn revisit(&self, seed: u64, start: f64, lateral: f64, speed: (f64, f64)) -> Self {
        let motion = self.motion;
        let mut rng = Stream::new(seed, Purpose::Revisit);
        let speed = Speed::new(&mut rng, speed.0, speed.1, 0.0);
        let [wr, wp, wz] = motion.wobble;
        let mut waves = |amp: [f64; 2]| {
            [
                Wave::random(&mut rng, amp[0], (3.0, 8.0)),
                Wave::random(&mut rng, amp[1], (0.6, 1.0)),
            ]
        };
        let (roll, pitch, bounce) = (waves(wr), waves(wp), waves(wz));
        let swing = self.swing.map(|_| {
            motion
                .swing
                .map(|axis| axis.map(|(amp, lo, hi)| Wave::random(&mut rng, amp, (lo, hi))))
        });
        Self {
            route: self.route.clone(),
            speed,
            motion,
            roll,
            pitch,
            bounce,
            swing,
            lead_in: 0.0,
            reverse: Some(Reverse { start, lateral }),
        }
    }
}
