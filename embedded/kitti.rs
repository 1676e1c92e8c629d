//! The frames the bare-metal program embeds, derived from kitti-mini by one fixed rule.
//!
//! Shared (through `#[path]`) by `embedded/build.rs`, which writes them into the binary, and by
//! `tests/tests/embedded.rs`, which runs the same frames through the host build of the core, so
//! both sides see the same points by construction. The rule, per scan:
//! 1. read `x, y, z, reflectance` float32 records and widen `x, y, z` to f64 (as the reference's
//!    KITTI loader does);
//! 2. apply the reference's KITTI scan correction (`kiss_icp::CorrectKITTIScan`): rotate `p` by
//!    0.205 deg about `normalize(p x (0, 0, 1))`, in f64, through Eigen's angle-axis matrix;
//! 3. crop: keep points with `|p| < max_range` (f64), the range the odometry is configured with;
//! 4. decimate: keep every `keep_every`-th of the cropped points (index 0, k, 2k, ...), so the
//!    frames fit the target's flash;
//! 5. round to the build's scalar (`f32` or `f64`) with `as`.
//!
//! KITTI is CC BY-NC-SA 3.0 (Geiger, Lenz, Urtasun, CVPR 2012): anything derived from these
//! frames that the project ships must carry that notice (see `embedded/README.md`).
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// The vertical angle offset of `_correct_kitti_scan`, in radians.
pub const KITTI_VERTICAL_OFFSET: f64 = 0.205 * std::f64::consts::PI / 180.0;

/// Which frames to take and how to reduce them.
#[derive(Clone, Debug)]
pub struct Selection {
    /// kitti-mini root (holds `sequences/`).
    pub root: PathBuf,
    /// Sequence name, e.g. `"05"`.
    pub sequence: String,
    /// First frame index.
    pub first: usize,
    /// Number of consecutive frames.
    pub frames: usize,
    /// Crop radius (the configuration's `max_range`).
    pub max_range: f64,
    /// Keep every k-th cropped point.
    pub keep_every: usize,
}

/// One prepared frame.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Points in the scan file.
    pub raw_points: usize,
    /// Points left after the range crop.
    pub cropped_points: usize,
    /// The kept points, corrected, in f64.
    pub points: Vec<[f64; 3]>,
}

/// Default location of kitti-mini relative to the repository root: `../shared/data/kitti-mini`.
pub fn default_root(repo_root: &Path) -> PathBuf {
    repo_root.join("../shared/data/kitti-mini")
}

/// Path of one scan.
pub fn scan_path(sel: &Selection, index: usize) -> PathBuf {
    sel.root
        .join("sequences")
        .join(&sel.sequence)
        .join("velodyne")
        .join(format!("{index:06}.bin"))
}

/// Rotates `p` as `CorrectKITTIScan` does: `AngleAxisd(offset, (p x z).normalized()) * p`.
/// Eigen multiplies by `toRotationMatrix()`, and normalizing a zero vector leaves it zero (the
/// matrix is then `cos(offset) I`); both are mirrored here term by term.
pub fn correct_kitti(p: [f64; 3]) -> [f64; 3] {
    // p x (0, 0, 1) = (p.y, -p.x, 0)
    let a = [p[1], -p[0], 0.0];
    let n2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    let axis = if n2 > 0.0 {
        let n = n2.sqrt();
        [a[0] / n, a[1] / n, a[2] / n]
    } else {
        a
    };
    let (s, c) = (KITTI_VERTICAL_OFFSET.sin(), KITTI_VERTICAL_OFFSET.cos());
    let sin_axis = [s * axis[0], s * axis[1], s * axis[2]];
    let cos1_axis = [
        (1.0 - c) * axis[0],
        (1.0 - c) * axis[1],
        (1.0 - c) * axis[2],
    ];
    let mut m = [[0.0f64; 3]; 3];
    let t = cos1_axis[0] * axis[1];
    m[0][1] = t - sin_axis[2];
    m[1][0] = t + sin_axis[2];
    let t = cos1_axis[0] * axis[2];
    m[0][2] = t + sin_axis[1];
    m[2][0] = t - sin_axis[1];
    let t = cos1_axis[1] * axis[2];
    m[1][2] = t - sin_axis[0];
    m[2][1] = t + sin_axis[0];
    for i in 0..3 {
        m[i][i] = cos1_axis[i] * axis[i] + c;
    }
    let mut out = [0.0; 3];
    for i in 0..3 {
        out[i] = m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2];
    }
    out
}

/// Reads one KITTI scan (`x, y, z, reflectance` as little-endian f32) as f64 points.
pub fn read_scan(path: &Path) -> std::io::Result<Vec<[f64; 3]>> {
    let bytes = std::fs::read(path)?;
    if bytes.len() % 16 != 0 {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "{}: {} bytes, not a multiple of 16",
                path.display(),
                bytes.len()
            ),
        ));
    }
    let f = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64;
    Ok(bytes
        .chunks_exact(16)
        .map(|r| [f(&r[0..4]), f(&r[4..8]), f(&r[8..12])])
        .collect())
}

/// Applies the rule in the module docs to one scan.
pub fn prepare(raw: &[[f64; 3]], max_range: f64, keep_every: usize) -> Frame {
    let cropped: Vec<[f64; 3]> = raw
        .iter()
        .map(|&p| correct_kitti(p))
        .filter(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() < max_range)
        .collect();
    Frame {
        raw_points: raw.len(),
        cropped_points: cropped.len(),
        points: cropped.into_iter().step_by(keep_every.max(1)).collect(),
    }
}

/// Loads and prepares the selected frames.
pub fn load(sel: &Selection) -> std::io::Result<Vec<Frame>> {
    (sel.first..sel.first + sel.frames)
        .map(|i| {
            Ok(prepare(
                &read_scan(&scan_path(sel, i))?,
                sel.max_range,
                sel.keep_every,
            ))
        })
        .collect()
}
