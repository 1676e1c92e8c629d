//! Seeded randomness for the simulator, counter-based so that output does not depend on threads.
//!
//! Every draw is a pure function of `(seed, purpose, indices)`: a ray's noise is keyed by its
//! frame, column and beam, never by how many draws another thread made first. That is what makes
//! the dataset byte-identical whatever the rayon thread count. The mixer is SplitMix64's
//! finaliser; transcendental functions come from `libm` so that bytes also match across
//! platforms (the system `libm` differs in the last bit between C libraries). We keep this
//! instead of `rand`, whose distributions do not promise value stability across versions.

/// SplitMix64's finaliser: a bijective 64-bit mixer with full avalanche.
#[inline]
pub const fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// A 64-bit key from a list of integers (order matters).
#[inline]
pub fn key(parts: &[u64]) -> u64 {
    parts
        .iter()
        .fold(GOLDEN, |h, &p| mix(h ^ p).wrapping_add(GOLDEN))
}

/// What a stream of draws is for, so that streams of one seed never overlap.
#[derive(Clone, Copy, Debug)]
#[repr(u64)]
pub enum Purpose {
    /// The route's curvature pieces.
    Route = 1,
    /// The speed and attitude profiles.
    Motion = 2,
    /// Scene objects along the route.
    Scene = 3,
    /// Per-ray range noise, dropout and intensity.
    Ray = 4,
    /// A hand's or a multirotor's swings about its path.
    Swing = 5,
    /// IMU noise and biases.
    Imu = 6,
    /// A revisit's path: its speed, attitude and ray noise.
    Revisit = 7,
    /// What a revisit changes in the scene.
    Changes = 8,
}

/// A SplitMix64 sequence: fast, seedable from any key, good enough for scene generation.
#[derive(Clone, Debug)]
pub struct Stream {
    state: u64,
}

impl Stream {
    /// The stream for `purpose` under `seed`.
    pub fn new(seed: u64, purpose: Purpose) -> Self {
        Self::from_key(key(&[seed, purpose as u64]))
    }

    /// The stream starting at `key` (for per-ray streams keyed by indices).
    #[inline]
    pub fn from_key(key: u64) -> Self {
        Self { state: key }
    }

    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN);
        mix(self.state)
    }

    /// Uniform in `[0, 1)` with 53 random bits.
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[lo, hi)`.
    #[inline]
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    /// True with probability `p`.
    #[inline]
    pub fn chance(&mut self, p: f64) -> bool {
        self.uniform() < p
    }

    /// +1 or -1 with equal probability.
    #[inline]
    pub fn sign(&mut self) -> f64 {
        if self.next_u64() >> 63 == 0 {
            1.0
        } else {
            -1.0
        }
    }

    /// A standard normal draw (Box-Muller, one of the pair).
    #[inline]
    pub fn normal(&mut self) -> f64 {
        self.normal_pair()[0]
    }

    /// Two independent standard normal draws (Box-Muller) for one logarithm.
    #[inline]
    pub fn normal_pair(&mut self) -> [f64; 2] {
        // 1 - u is in (0, 1], so the logarithm is finite.
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        let r = libm::sqrt(-2.0 * libm::log(u1));
        let (s, c) = libm::sincos(core::f64::consts::TAU * u2);
        [r * c, r * s]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_draws_have_unit_variance_and_zero_mean() {
        let mut s = Stream::new(7, Purpose::Ray);
        let n = 200_000;
        let (mut sum, mut sq, mut cross) = ([0.0; 2], [0.0; 2], 0.0);
        for _ in 0..n {
            let x = s.normal_pair();
            for i in 0..2 {
                sum[i] += x[i];
                sq[i] += x[i] * x[i];
            }
            cross += x[0] * x[1];
        }
        for i in 0..2 {
            let mean = sum[i] / n as f64;
            let var = sq[i] / n as f64 - mean * mean;
            println!("draw {i}: mean {mean:.4} (tol 0.01), variance {var:.4} (tol 0.02)");
            assert!(mean.abs() < 0.01);
            assert!((var - 1.0).abs() < 0.02);
        }
        let corr = cross / n as f64;
        println!("correlation of the pair {corr:.4} (tol 0.01)");
        assert!(corr.abs() < 0.01);
    }

    #[test]
    fn uniform_draws_stay_in_the_half_open_unit_interval() {
        let mut s = Stream::from_key(0);
        let mut lo = f64::MAX;
        let mut hi = f64::MIN;
        for _ in 0..100_000 {
            let u = s.uniform();
            assert!((0.0..1.0).contains(&u));
            lo = lo.min(u);
            hi = hi.max(u);
        }
        assert!(lo < 1e-3 && hi > 1.0 - 1e-3);
    }

    #[test]
    fn keys_depend_on_every_part_and_their_order() {
        assert_ne!(key(&[1, 2, 3]), key(&[1, 2, 4]));
        assert_ne!(key(&[1, 2, 3]), key(&[3, 2, 1]));
        assert_eq!(key(&[1, 2, 3]), key(&[1, 2, 3]));
    }
}
