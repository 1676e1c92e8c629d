//! MulRan (`kiss_icp/datasets/mulran.py`): an Ouster OS1-64 on a car.
//!
//! ```text
//! SEQ/Ouster/<ns>.bin     float32 x y z intensity, 64 x 1024 points column-major
//! SEQ/global_pose.csv     ns, then the 3x4 base pose row-major (12 numbers), more rows than scans
//! ```
//!
//! Each scan takes the pose row nearest its name's time; poses are re-based to the first
//! scan's and moved from the base to the LiDAR frame with the loader's fixed calibration
//! (`calib_base2ouster.txt`). A whole 65536-point scan gets the grid's per-point times.

use super::rotation::{inverse, rebase};
use super::scans::{grid_warning, list, ouster_grid_stamps, read_f32_bin, stem_number, Order};
use super::table::{self, Sep};
use super::{Layout, Scan, Truth};
use crate::dataset::Format;
use anyhow::Result;
use nalgebra::Matrix4;
use std::path::Path;

/// The loader's LiDAR-to-base transform (translation 1.7042, -0.021, 1.8047 m; rotation
/// 0.0001, 0.0003, 179.6654 degrees about x, y, z), as it writes it.
#[rustfmt::skip]
pub const T_LIDAR_TO_BASE: [f64; 16] = [
    -9.9998295e-01, -5.8398386e-03, -5.2257060e-06, 1.7042000e00,
    5.8398386e-03, -9.9998295e-01, 1.7758769e-06, -2.1000000e-02,
    -5.2359878e-06, 1.7453292e-06, 1.0000000e00, 1.8047000e00,
    0.0, 0.0, 0.0, 1.0,
];

/// A scan whose nearest pose row is farther than this (ns) is reported: rows are missing.
const FAR_NS: f64 = 1e8;

/// Whether `root` looks like a MulRan sequence.
pub fn detect(root: &Path) -> bool {
    root.join("Ouster").is_dir()
}

/// Opens the MulRan sequence at `root`.
pub fn layout(root: &Path) -> Result<Layout> {
    let files = list(&root.join("Ouster"), "bin", Order::Bytes)?;
    let stamps_ns = files
        .iter()
        .map(|p| stem_number(p))
        .collect::<Result<Vec<u64>>>()?;
    let gt_path = root.join("global_pose.csv");
    let rows = table::read(&gt_path, Sep::Comma, 0, 13, "MulRan's ground truth")?;
    let times: Vec<f64> = rows.iter().map(|r| r.cells[0]).collect();
    let mut warnings = Vec::new();
    let mut picked = Vec::with_capacity(files.len());
    let mut far: Vec<(f64, &Path)> = Vec::new();
    for (path, &ns) in files.iter().zip(&stamps_ns) {
        let Some((i, distance)) = table::nearest(&times, ns as f64) else {
            continue;
        };
        if distance > FAR_NS {
            far.push((distance, path));
        }
        let row = &rows[i].cells;
        let mut m = Matrix4::identity();
        for k in 0..12 {
            m[(k / 4, k % 4)] = row[1 + k];
        }
        picked.push(m);
    }
    if let Some((worst, path)) = far
        .iter()
        .copied()
        .reduce(|a, b| if b.0 > a.0 { b } else { a })
    {
        warnings.push(format!(
            "{}: {} scan(s) are more than {} s from the nearest pose row (farthest {:.3} s, \
             {}): rows are missing there; those scans take the nearest pose anyway, as \
             kiss-icp's loader does",
            gt_path.display(),
            far.len(),
            FAR_NS * 1e-9,
            worst * 1e-9,
            path.display()
        ));
    }
    let base = rebase(&picked, "the first scan's pose in global_pose.csv")?;
    let lb = Matrix4::from_row_slice(&T_LIDAR_TO_BASE);
    let bl = inverse(&lb, "the LiDAR calibration")?;
    let matrices = base.iter().map(|p| lb * p * bl).collect();
    let scans = files
        .into_iter()
        .zip(stamps_ns)
        .map(|(path, ns)| Scan {
            path,
            time: Some(ns as f64 * 1e-9),
        })
        .collect();
    Ok(Layout {
        format: Format::Mulran,
        scans,
        read: Box::new(read_scan),
        truth: Truth {
            path: gt_path,
            matrices,
        },
        warnings,
    })
}

/// One `Ouster/<ns>.bin` scan: float32 x y z intensity, widened; grid times if whole.
pub fn read_scan(path: &Path, max_points: usize) -> Result<super::ScanPoints> {
    let mut scan = read_f32_bin(path, 4, max_points)?;
    scan.stamps = ouster_grid_stamps(scan.declared, scan.points.len());
    if scan.stamps.is_none() {
        scan.warnings.push(grid_warning(path, scan.declared));
    }
    Ok(scan)
}
