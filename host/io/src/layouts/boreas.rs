//! Boreas (`kiss_icp/datasets/boreas.py`): a Velodyne Alpha Prime on a car, Applanix
//! ground truth.
//!
//! ```text
//! SEQ/lidar/<us>.bin               float32 x y z intensity laser time, 24 bytes a point
//! SEQ/applanix/lidar_poses.csv     a header, then t, easting, northing, altitude, 3 velocities,
//!                                  roll, pitch, heading, 3 angular rates; row i for scan i
//! ```
//!
//! As the loader: scans in natural order; per-point times from each point's azimuth, in
//! float32 (`0.5 (-atan2(y, x) / pi + 1)`); poses `[C, r]` with `C = R_roll R_pitch R_yaw`
//! (each the transposed elementary rotation), re-based to the first and stored as float32.

use super::rotation::{inverse, to_f32};
use super::scans::{list, read_f32_bin, stem_number, Order};
use super::table::{self, Sep};
use super::{Layout, Scan, ScanPoints, Truth};
use crate::dataset::Format;
use anyhow::{bail, Result};
use nalgebra::{Matrix3, Matrix4};
use std::path::Path;

/// Whether `root` looks like a Boreas sequence.
pub fn detect(root: &Path) -> bool {
    root.join("lidar").is_dir() && root.join("applanix").is_dir()
}

/// The loader's `get_transformation_matrix(x, y, z, yaw, pitch, roll)`.
pub fn pose(x: f64, y: f64, z: f64, yaw: f64, pitch: f64, roll: f64) -> Matrix4<f64> {
    let (sy, cy) = (yaw.sin(), yaw.cos());
    let (sp, cp) = (pitch.sin(), pitch.cos());
    let (sr, cr) = (roll.sin(), roll.cos());
    let r_yaw = Matrix3::new(cy, sy, 0.0, -sy, cy, 0.0, 0.0, 0.0, 1.0);
    let r_pitch = Matrix3::new(cp, 0.0, -sp, 0.0, 1.0, 0.0, sp, 0.0, cp);
    let r_roll = Matrix3::new(1.0, 0.0, 0.0, 0.0, cr, sr, 0.0, -sr, cr);
    super::rotation::rigid(&(r_roll * r_pitch * r_yaw), [x, y, z])
}

/// Per-point times from the azimuth, in float32 as the loader computes them.
pub fn azimuth_stamps(points: &[[f64; 3]]) -> Vec<f64> {
    points
        .iter()
        .map(|p| {
            let (x, y) = (p[0] as f32, p[1] as f32);
            let yaw = -y.atan2(x);
            f64::from(0.5f32 * (yaw / core::f32::consts::PI + 1.0f32))
        })
        .collect()
}

/// Opens the Boreas sequence at `root`.
pub fn layout(root: &Path) -> Result<Layout> {
    let files = list(&root.join("lidar"), "bin", Order::Natural)?;
    let gt_path = root.join("applanix/lidar_poses.csv");
    let rows = table::read(&gt_path, Sep::Comma, 1, 13, "Boreas's ground truth")?;
    let mut poses = Vec::with_capacity(rows.len());
    for row in &rows {
        let c = &row.cells;
        if c[1..10].iter().any(|v| !v.is_finite()) {
            bail!("{}:{}: the pose is not finite", gt_path.display(), row.line);
        }
        poses.push(pose(c[1], c[2], c[3], c[9], c[8], c[7]));
    }
    let first = inverse(&poses[0], "the first pose of lidar_poses.csv")?;
    let matrices = poses.iter().map(|p| to_f32(&(first * p))).collect();
    let scans = files
        .into_iter()
        .map(|path| Scan {
            time: stem_number(&path).ok().map(|us| us as f64 * 1e-6),
            path,
        })
        .collect();
    Ok(Layout {
        format: Format::Boreas,
        scans,
        read: Box::new(read_scan),
        truth: Truth {
            path: gt_path,
            matrices,
        },
        warnings: Vec::new(),
    })
}

/// One `lidar/<us>.bin` scan: x y z of six float32, azimuth times.
pub fn read_scan(path: &Path, max_points: usize) -> Result<ScanPoints> {
    let mut scan = read_f32_bin(path, 6, max_points)?;
    scan.stamps = Some(azimuth_stamps(&scan.points));
    Ok(scan)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn azimuth_times_run_from_half_to_one_and_zero_to_half() {
        let t = azimuth_stamps(&[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]]);
        assert_eq!(t, vec![0.5, 0.25, 0.75]);
    }

    #[test]
    fn pose_rotation_is_the_transposed_yaw_pitch_roll() {
        let m = pose(1.0, 2.0, 3.0, 0.3, 0.0, 0.0);
        assert!((m[(0, 1)] - 0.3f64.sin()).abs() < 1e-15);
        assert_eq!(m[(1, 3)], 2.0);
    }
}
