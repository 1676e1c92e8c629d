//! Apollo-SouthBay (`kiss_icp/datasets/apollo.py`): a Velodyne HDL-64E on a car.
//!
//! ```text
//! SEQ/pcds/<n>.pcd          x y z (and the sensor's fields), read through Open3D by the loader
//! SEQ/poses/gt_poses.txt    n t x y z qx qy qz qw, LiDAR frame; row i for scan i
//! ```
//!
//! As the loader: scans in natural order, x y z as float64 (Open3D widens float32 fields),
//! no per-point times; poses re-based to the first. A frame's time is its pose row's `t`.

use super::rotation::{quaternion_matrix, rebase, rigid};
use super::scans::{list, Order};
use super::table::{self, Sep};
use super::{Layout, Scan, ScanPoints, Truth};
use crate::dataset::Format;
use anyhow::{bail, Result};
use std::path::Path;

/// Whether `root` looks like an Apollo-SouthBay sequence.
pub fn detect(root: &Path) -> bool {
    root.join("pcds").is_dir() && root.join("poses").is_dir()
}

/// Opens the Apollo-SouthBay sequence at `root`.
pub fn layout(root: &Path) -> Result<Layout> {
    let files = list(&root.join("pcds"), "pcd", Order::Natural)?;
    let gt_path = root.join("poses/gt_poses.txt");
    let rows = table::read(&gt_path, Sep::Space, 0, 9, "Apollo's ground truth")?;
    let mut poses = Vec::with_capacity(rows.len());
    for row in &rows {
        let c = &row.cells;
        if c[2..9].iter().any(|v| !v.is_finite()) {
            bail!("{}:{}: the pose is not finite", gt_path.display(), row.line);
        }
        poses.push(rigid(
            &quaternion_matrix(c[8], c[5], c[6], c[7]),
            [c[2], c[3], c[4]],
        ));
    }
    let matrices = rebase(&poses, "the first pose of gt_poses.txt")?;
    let scans = files
        .into_iter()
        .enumerate()
        .map(|(i, path)| Scan {
            path,
            time: rows.get(i).map(|r| r.cells[1]),
        })
        .collect();
    Ok(Layout {
        format: Format::Apollo,
        scans,
        read: Box::new(read_scan),
        truth: Truth {
            path: gt_path,
            matrices,
        },
        warnings: Vec::new(),
    })
}

/// One `.pcd` scan's x y z; the file's own time field is not used (the loader has none).
pub fn read_scan(path: &Path, max_points: usize) -> Result<ScanPoints> {
    let cloud = crate::folders::pcd::read_at_most(path, max_points)?;
    Ok(ScanPoints {
        points: cloud.points,
        stamps: None,
        declared: cloud.declared,
        warnings: Vec::new(),
    })
}
