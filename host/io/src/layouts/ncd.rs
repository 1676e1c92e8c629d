//! The Newer College dataset (`kiss_icp/datasets/ncd.py`): a handheld Ouster OS1-64.
//!
//! ```text
//! SEQ/raw_format/ouster_scan/cloud_<s>_<ns>.pcd   x y z (float32) and the sensor's fields
//! SEQ/ground_truth/registered_poses.csv           s, ns, x, y, z, qx, qy, qz, qw; row i for scan i
//! ```
//!
//! As the loader: scans in time order of their names, x y z widened to float64, the Ouster
//! grid's per-point times for a whole 65536-point scan (the file's own time field is not
//! used); pose row `i` belongs to scan `i`, is moved to the LiDAR frame with the loader's
//! fixed `T_CL` (stored as float32) and re-based to the first.

use super::rotation::{quaternion_matrix, rebase, rigid};
use super::scans::{grid_warning, ouster_grid_stamps};
use super::table::{self, Sep};
use super::{Layout, Scan, ScanPoints, Truth};
use crate::dataset::Format;
use anyhow::{bail, Context, Result};
use nalgebra::Matrix4;
use std::path::Path;

/// Whether `root` looks like a Newer College sequence.
pub fn detect(root: &Path) -> bool {
    root.join("raw_format/ouster_scan").is_dir()
}

/// The loader's `T_CL`: quaternion (w 0.383, z 0.924), translation (-0.084, -0.025, 0.050),
/// every entry stored as float32.
pub fn t_cl() -> Matrix4<f64> {
    let r = quaternion_matrix(0.383, 0.0, 0.0, 0.924);
    let m = rigid(&r, [-0.084, -0.025, 0.050]);
    super::rotation::to_f32(&m)
}

/// `(s, ns)` of a `cloud_<s>_<ns>.pcd` name.
pub fn name_time(name: &str) -> Option<(u64, u64)> {
    let rest = name.strip_prefix("cloud_")?;
    let end = rest
        .find(|c: char| !c.is_ascii_digit() && c != '_')
        .unwrap_or(rest.len());
    let (s, ns) = rest[..end].split_once('_')?;
    Some((s.parse().ok()?, ns.split('_').next()?.parse().ok()?))
}

/// Opens the Newer College sequence at `root`.
pub fn layout(root: &Path) -> Result<Layout> {
    let dir = root.join("raw_format/ouster_scan");
    let mut named = Vec::new();
    let mut ignored = 0usize;
    for entry in std::fs::read_dir(&dir).with_context(|| format!("listing {}", dir.display()))? {
        let entry = entry?;
        let name = entry.file_name().to_string_lossy().into_owned();
        match name_time(&name) {
            Some((s, ns)) if name.ends_with(".pcd") => {
                named.push((s * 1_000_000_000 + ns, s, ns, entry.path()))
            }
            _ => ignored += 1,
        }
    }
    named.sort_by(|a, b| a.0.cmp(&b.0).then_with(|| a.3.cmp(&b.3)));
    let mut warnings = Vec::new();
    if ignored > 0 {
        warnings.push(format!(
            "{}: {ignored} file(s) not named cloud_<s>_<ns>.pcd are ignored",
            dir.display()
        ));
    }
    let gt_path = root.join("ground_truth/registered_poses.csv");
    let rows = table::read(&gt_path, Sep::Comma, 0, 9, "Newer College's ground truth")?;
    let mut poses = Vec::with_capacity(rows.len());
    for row in &rows {
        let c = &row.cells;
        if c[2..9].iter().any(|v| !v.is_finite()) {
            bail!("{}:{}: the pose is not finite", gt_path.display(), row.line);
        }
        let r = quaternion_matrix(c[8], c[5], c[6], c[7]);
        poses.push(rigid(&r, [c[2], c[3], c[4]]) * t_cl());
    }
    let matrices = rebase(&poses, "the first pose of registered_poses.csv")?;
    let scans = named
        .into_iter()
        .map(|(_, s, ns, path)| Scan {
            path,
            time: Some(s as f64 + ns as f64 * 1e-9),
        })
        .collect();
    Ok(Layout {
        format: Format::Ncd,
        scans,
        read: Box::new(read_scan),
        truth: Truth {
            path: gt_path,
            matrices,
        },
        warnings,
    })
}

/// One `.pcd` scan: x y z widened to float64; grid times if whole.
pub fn read_scan(path: &Path, max_points: usize) -> Result<ScanPoints> {
    let cloud = crate::folders::pcd::read_at_most(path, max_points)?;
    let stamps = ouster_grid_stamps(cloud.declared, cloud.points.len());
    let mut warnings = Vec::new();
    if stamps.is_none() {
        warnings.push(grid_warning(path, cloud.declared));
    }
    Ok(ScanPoints {
        points: cloud.points,
        stamps,
        declared: cloud.declared,
        warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_give_seconds_and_nanoseconds() {
        assert_eq!(
            name_time("cloud_1583836591_182590976.pcd"),
            Some((1583836591, 182590976))
        );
        assert_eq!(name_time("scan_1_2.pcd"), None);
        assert_eq!(name_time("cloud_12.pcd"), None);
    }

    #[test]
    fn t_cl_is_a_turn_about_z_rounded_to_f32() {
        let m = t_cl();
        assert_eq!(m[(0, 3)], -0.084f32 as f64);
        assert!((m[(0, 0)] - (-0.70687f64)).abs() < 1e-3, "{m}");
        assert_eq!(m[(2, 2)], 1.0);
    }
}
