//! A moving sensor in a static street, for pipeline tests: each scan is the street's points
//! within range, seen from the sensor pose of that frame (no occlusion, no motion blur).
#![allow(dead_code)]

use kiss_odom_core::{Capacities, Config, Odometry, PointCodec, Pose, Real};
use nalgebra::{Translation3, UnitQuaternion, Vector3};

pub struct Rng(pub u64);

impl Rng {
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A street along x: ground, facades with recesses and gaps on both sides, and scattered
/// boxes, sampled about every 0.3 m with random jitter. (A perfectly periodic lattice would
/// let ICP lock onto a shift by one lattice step; real scans are never lattice-sampled.)
pub fn street(seed: u64) -> Vec<[f64; 3]> {
    let mut rng = Rng(seed | 1);
    let mut pts = Vec::new();
    let s = 0.3;
    for i in 0..400 {
        for j in 0..60 {
            let (jx, jy) = (rng.uniform() - 0.5, rng.uniform() - 0.5);
            pts.push([
                -20.0 + (i as f64 + jx) * s,
                -9.0 + (j as f64 + jy) * s,
                -1.8,
            ]);
        }
    }
    for side in [-9.5f64, 9.5] {
        for i in 0..400 {
            let x = -20.0 + i as f64 * s;
            // Facade segments with gaps and recesses give structure along x.
            let recess = if (i / 13) % 3 == 0 { 1.0 } else { 0.0 };
            if (i / 29) % 4 == 3 {
                continue;
            }
            for k in 0..25 {
                let y = side + side.signum() * recess;
                let (jx, jz) = (rng.uniform() - 0.5, rng.uniform() - 0.5);
                pts.push([x + jx * s, y, -1.5 + (k as f64 + jz) * s]);
            }
        }
    }
    // Poles: vertical structure every few metres pins the motion along the street.
    for _ in 0..150 {
        let (x, y) = (-20.0 + rng.uniform() * 120.0, -8.5 + rng.uniform() * 17.0);
        for k in 0..(8 + (rng.uniform() * 12.0) as usize) {
            pts.push([x, y, -1.8 + (k as f64 + rng.uniform() * 0.5) * s]);
        }
    }
    for _ in 0..80 {
        let (cx, cy) = (-15.0 + rng.uniform() * 110.0, -7.0 + rng.uniform() * 14.0);
        let (w, h) = (0.6 + rng.uniform() * 2.0, 0.5 + rng.uniform() * 2.0);
        let n = (w / s) as usize + 1;
        for a in 0..n {
            for k in 0..((h / s) as usize + 1) {
                let z = -1.8 + (k as f64 + rng.uniform() * 0.5) * s;
                let t = (a as f64 + rng.uniform() * 0.5) * s;
                pts.push([cx + t, cy, z]);
                pts.push([cx + t, cy + w, z]);
                pts.push([cx, cy + t, z]);
                pts.push([cx + w, cy + t, z]);
            }
        }
    }
    pts
}

/// Sensor pose at frame `i`: accelerating along x with a gentle weave, some pitch and yaw.
pub fn pose_at(i: usize) -> Pose<f64> {
    let t = i as f64 * 0.1;
    let x = 8.0 * t + 1.5 * t * t;
    let y = 0.8 * (0.7 * t).sin();
    let yaw = 0.08 * (0.7 * t).cos() - 0.08;
    Pose::from_parts(
        Translation3::new(x, y, 0.05 * t.sin()),
        UnitQuaternion::from_euler_angles(0.005 * t.cos(), 0.01 * t.sin(), yaw),
    )
}

/// The scan of frame `i` in the sensor frame, within `range` of the sensor.
pub fn scan(street: &[[f64; 3]], i: usize, range: f64) -> Vec<[f64; 3]> {
    let inv = pose_at(i).inverse();
    street
        .iter()
        .map(|p| inv * nalgebra::Point3::from(*p))
        .filter(|p| p.coords.norm() < range)
        .map(|p| [p.x, p.y, p.z])
        .collect()
}

/// A scan in scalar `T`.
pub fn narrow<T: Real>(pts: &[[f64; 3]]) -> Vec<[T; 3]> {
    pts.iter()
        .map(|p| [T::of(p[0]), T::of(p[1]), T::of(p[2])])
        .collect()
}

/// Capacities comfortably above what the street needs.
pub fn caps() -> Capacities {
    Capacities {
        scan_points: 100_000,
        merge_points: 65_536,
        source_points: 16_384,
        map_voxels: 16_384,
        map_points: 262_144,
        plane_terms: false,
    }
}

/// Runs `frames` scans through a fresh odometry and returns the poses relative to the first.
pub fn run<T: Real, P: PointCodec<T>>(
    config: Config<T>,
    caps: Capacities,
    scans: &[Vec<[T; 3]>],
) -> Vec<Pose<T>> {
    let mut arena = vec![0u64; caps.arena_words::<T, P>()];
    let mut odom = Odometry::<T, P, _>::new(config, caps, &mut arena[..]).unwrap();
    scans
        .iter()
        .map(|s| odom.register_frame(s, None).unwrap().pose)
        .collect()
}

/// Translation error of `est` (relative to frame 0) against the truth at frame `i`.
pub fn error_at(est: &Pose<f64>, i: usize) -> f64 {
    let truth = pose_at(0).inverse() * pose_at(i);
    (truth.translation.vector - est.translation.vector).norm()
}

/// Distance between two poses' translations.
pub fn gap(a: &Pose<f64>, b: &Pose<f64>) -> f64 {
    (a.translation.vector - b.translation.vector).norm()
}

pub fn v3(x: f64, y: f64, z: f64) -> Vector3<f64> {
    Vector3::new(x, y, z)
}
