//! Deterministic test data without an allocator: a xorshift generator and a structured scene.

/// xorshift64 uniform numbers in [0, 1).
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// An asymmetric walled yard: a floor, four walls and three boxes, sampled on a 0.5 m grid
/// (every voxel of 1 m holds a few points, none closer than the map resolution). Returns the
/// number of points written.
pub fn yard(out: &mut [[f64; 3]]) -> usize {
    let mut n = 0;
    let mut put = |p: [f64; 3]| {
        if n < out.len() {
            out[n] = p;
            n += 1;
        }
    };
    let step = 0.5;
    let grid = |a: f64, b: f64| ((b - a) / step) as i32;
    for i in 0..=grid(-12.0, 12.0) {
        for j in 0..=grid(-12.0, 12.0) {
            put([
                -12.0 + i as f64 * step + 0.1,
                -12.0 + j as f64 * step + 0.2,
                0.05,
            ]);
        }
    }
    // Walls stop short of the corners, where two walls would come closer than the map
    // resolution.
    for i in 0..grid(-12.0, 12.0) {
        for k in 1..8 {
            let t = -12.0 + i as f64 * step + 0.15;
            let z = k as f64 * step + 0.05;
            put([12.3, t, z]);
            put([-12.3, t, z]);
            put([t, 12.3, z]);
            put([t, -12.3, z]);
        }
    }
    // Boxes at irregular places break the yard's symmetry.
    for (cx, cy, sx, sy, h) in [
        (3.0, 4.0, 2.0, 1.0, 2.5),
        (-6.0, -2.0, 1.0, 3.0, 1.5),
        (5.5, -7.0, 1.5, 1.5, 3.0),
    ] {
        for i in 0..=grid(0.0, sx) {
            for k in 1..=grid(0.0, h) {
                let (x, z) = (cx + i as f64 * step, k as f64 * step);
                put([x, cy, z]);
                put([x, cy + sy, z]);
            }
        }
        // The end columns were written by the loop above; skip them to avoid duplicates.
        for j in 1..grid(0.0, sy) {
            for k in 1..=grid(0.0, h) {
                let (y, z) = (cy + j as f64 * step, k as f64 * step);
                put([cx, y, z]);
                put([cx + sx, y, z]);
            }
        }
    }
    n
}
