//! How two outputs are compared: poses by translation distance and rotation angle
//! ([`kiss_odom_io::pose::pose_difference`]), point lists
//! position by position, point sets by their exact bits, and maps (whose points each side
//! computes with its own rounding) by nearest matching.

use kiss_odom_core::stages::{LocalMap, BLOCK};
use kiss_odom_core::{Config, Exact};
use kiss_odom_io::pose::pose_difference;
use nalgebra::Isometry3;
use std::collections::{HashMap, HashSet};

/// Largest distance between points at the same position of two lists of equal length.
pub fn max_point_difference(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            let d = [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        })
        .fold(0.0, f64::max)
}

/// The exact bits of a point, for set comparisons.
pub fn bits(p: &[f64; 3]) -> [u64; 3] {
    p.map(f64::to_bits)
}

/// Points in one set but not the other (exact bits).
pub fn set_difference(a: &[[f64; 3]], b: &[[f64; 3]]) -> usize {
    let sa: HashSet<[u64; 3]> = a.iter().map(bits).collect();
    let sb: HashSet<[u64; 3]> = b.iter().map(bits).collect();
    sa.symmetric_difference(&sb).count()
}

/// Positions at which two lists hold different points (the longer list's extra positions
/// count as different).
pub fn order_difference(a: &[[f64; 3]], b: &[[f64; 3]]) -> usize {
    let common = a.iter().zip(b).filter(|(p, q)| bits(p) != bits(q)).count();
    common + a.len().abs_diff(b.len())
}

/// Matches every point of `b` to a distinct point of `a` within `radius` (each side computed
/// the same points with its own rounding) and returns the largest matched distance, or `None`
/// when the counts differ or some point has no partner within `radius`.
pub fn matched_distance(a: &[[f64; 3]], b: &[[f64; 3]], radius: f64) -> Option<f64> {
    if a.len() != b.len() {
        return None;
    }
    let cell = |p: &[f64; 3]| p.map(|c| (c / radius).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (i, p) in a.iter().enumerate() {
        grid.entry(cell(p)).or_default().push(i);
    }
    let mut used = vec![false; a.len()];
    let mut worst = 0.0f64;
    for q in b {
        let c = cell(q);
        let mut best: Option<(usize, f64)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                        continue;
                    };
                    for &i in list {
                        if used[i] {
                            continue;
                        }
                        let d = max_point_difference(&[a[i]], &[*q]);
                        if d <= radius && best.is_none_or(|(_, bd)| d < bd) {
                            best = Some((i, d));
                        }
                    }
                }
            }
        }
        let (i, d) = best?;
        used[i] = true;
        worst = worst.max(d);
    }
    Some(worst)
}

/// Per-frame disagreement of two trajectories of equal length.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Agreement {
    /// Position difference per frame (m).
    pub translation_m: Vec<f64>,
    /// Rotation difference per frame (rad).
    pub rotation_rad: Vec<f64>,
    /// Difference of the frame-to-frame motion per frame (m): how differently the two
    /// estimated each step, independent of what came before.
    pub step_translation_m: Vec<f64>,
}

impl Agreement {
    /// Compares `a` and `b` frame by frame.
    pub fn of(a: &[Isometry3<f64>], b: &[Isometry3<f64>]) -> Self {
        let mut out = Self::default();
        for (k, (p, q)) in a.iter().zip(b).enumerate() {
            let (t, r) = pose_difference(p, q);
            out.translation_m.push(t);
            out.rotation_rad.push(r);
            let step = if k == 0 {
                0.0
            } else {
                let sa = a[k - 1].inverse() * p;
                let sb = b[k - 1].inverse() * q;
                pose_difference(&sa, &sb).0
            };
            out.step_translation_m.push(step);
        }
        out
    }

    /// Frames from the start while both differences stay within `(m, rad)`.
    pub fn agreeing_prefix(&self, m: f64, rad: f64) -> usize {
        self.translation_m
            .iter()
            .zip(&self.rotation_rad)
            .take_while(|(t, r)| **t <= m && **r <= rad)
            .count()
    }
}

/// (max, mean, last) of a series (zeros when empty).
pub fn summary(v: &[f64]) -> (f64, f64, f64) {
    if v.is_empty() {
        return (0.0, 0.0, 0.0);
    }
    let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    (max, mean, v[v.len() - 1])
}

/// Least-squares slope of `v` against its index.
pub fn slope(v: &[f64]) -> f64 {
    let n = v.len() as f64;
    if v.len() < 2 {
        return 0.0;
    }
    let mx = (n - 1.0) / 2.0;
    let my = v.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (i, y) in v.iter().enumerate() {
        let dx = i as f64 - mx;
        sxy += dx * (y - my);
        sxx += dx * dx;
    }
    sxy / sxx
}

/// A map on the heap (the core never allocates; the cross-check may).
pub type HeapMap = LocalMap<f64, Exact, Vec<u64>>;

/// An empty map with the voxel size, range and points per voxel of `cfg` and room for `points`
/// points in any arrangement: one voxel per point at worst, each then taking a whole block of
/// [`BLOCK`] point slots.
pub fn heap_map(cfg: &Config<f64>, points: usize) -> Result<HeapMap, kiss_odom_core::ConfigError> {
    let n = points.max(1);
    let slots = n * BLOCK;
    let words = vec![0u64; HeapMap::words(n, slots)];
    LocalMap::new(
        cfg.voxel_size,
        cfg.max_range,
        cfg.max_points_per_voxel,
        n,
        slots,
        words,
    )
}

/// Every point of a map, voxel by voxel.
pub fn map_points(map: &HeapMap) -> Vec<[f64; 3]> {
    let mut out = Vec::with_capacity(map.points());
    map.view().for_each_point(|_, p| out.push([p.x, p.y, p.z]));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_heap_map_holds_its_points_one_voxel_each() {
        let cfg = Config::<f64>::new(100.0);
        let points: Vec<[f64; 3]> = (0..50).map(|i| [3.0 * i as f64, 1.0, 0.5]).collect();
        let mut map = heap_map(&cfg, points.len()).unwrap();
        map.add_points(points.iter().map(|p| kiss_odom_core::Point::from(*p)));
        assert_eq!((map.voxels(), map.points()), (50, 50));
    }

    #[test]
    fn matching_finds_rounded_copies_and_refuses_missing_ones() {
        let a = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0]];
        let b = [[1.0, 1.0, 1.0 + 1e-12], [1e-12, 0.0, 0.0], [1.0, 1.0, 1.0]];
        let d = matched_distance(&a, &b, 1e-6).unwrap();
        assert!((d - 1e-12).abs() < 1e-15);
        assert_eq!(matched_distance(&a, &[[0.0; 3]; 3], 1e-6), None);
        assert_eq!(matched_distance(&a, &a[..2], 1e-6), None);
    }

    #[test]
    fn sets_and_orders_compare_exact_bits() {
        let a = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]];
        let b = [[4.0, 5.0, 6.0], [1.0, 2.0, 3.0]];
        assert_eq!(set_difference(&a, &b), 0);
        assert_eq!(order_difference(&a, &b), 2);
        assert_eq!(order_difference(&a, &a[..1]), 1);
    }

    #[test]
    fn slope_of_a_line_is_its_gradient() {
        let v: Vec<f64> = (0..50).map(|i| 3.0 + 0.25 * i as f64).collect();
        assert!((slope(&v) - 0.25).abs() < 1e-12);
    }
}
