//! NCLT, the University of Michigan North Campus set (`kiss_icp/datasets/nclt.py`): a
//! Velodyne HDL-32E on a Segway.
//!
//! ```text
//! ROOT/DATE/velodyne_sync/<us>.bin               8 bytes a point: x y z int16, intensity, laser
//! ROOT/ground_truth/groundtruth_DATE.csv         us, x, y, z, roll, pitch, yaw (NED), ~100 Hz
//! ```
//!
//! As the loader: the coordinates are read as *signed* int16 (the dataset's own script reads
//! unsigned; a coordinate beyond +63.835 m wraps 327.68 m away, where the range crop drops
//! it), scaled in float32 (`0.005 x - 100`), y and z negated; only scans strictly inside the
//! ground truth's time span are kept; each takes the pose row nearest in time
//! (`scipy.interpolate.interp1d(kind="nearest")`), stored as float32 and turned to z-up
//! (`S T S`, `S = diag(1, -1, -1, 1)`), not re-based. No per-point times.

use super::rotation::{rigid, to_f32, zyx};
use super::scans::{list, read_head, stem_number, Order};
use super::table::{self, Sep};
use super::{Layout, Scan, ScanPoints, Truth};
use crate::dataset::Format;
use anyhow::{bail, Context, Result};
use nalgebra::Matrix4;
use std::path::{Path, PathBuf};

/// Bytes a point: x, y, z int16 little-endian, intensity and laser number u8.
pub const POINT_BYTES: usize = 8;

/// Whether `root` looks like an NCLT date folder.
pub fn detect(root: &Path) -> bool {
    root.join("velodyne_sync").is_dir()
}

/// The ground-truth file of the date folder `root`: `../ground_truth/groundtruth_DATE.csv`.
pub fn ground_truth_path(root: &Path) -> Result<PathBuf> {
    let real = std::fs::canonicalize(root).with_context(|| format!("{}", root.display()))?;
    let date = root
        .file_name()
        .or(real.file_name())
        .and_then(|n| n.to_str())
        .context("the folder has no name to find its ground truth by")?;
    let parent = real.parent().unwrap_or(&real);
    Ok(parent
        .join("ground_truth")
        .join(format!("groundtruth_{date}.csv")))
}

/// Index of the row `interp1d(kind="nearest")` picks for `t` among sorted `times`: the
/// midpoints `x[k+1] / 2 + x[k] / 2` bound the rows, a tie goes to the earlier row.
pub fn nearest_row(times: &[f64], t: f64) -> usize {
    let below = times
        .windows(2)
        .take_while(|w| w[1] / 2.0 + w[0] / 2.0 < t)
        .count();
    below.min(times.len().saturating_sub(1))
}

/// Opens the NCLT date folder `root`.
pub fn layout(root: &Path) -> Result<Layout> {
    let files = list(&root.join("velodyne_sync"), "bin", Order::Bytes)?;
    let gt_path = ground_truth_path(root)?;
    let mut rows = table::read(&gt_path, Sep::Comma, 0, 7, "NCLT's ground truth")?;
    // interp1d sorts its samples (stably) by time.
    rows.sort_by(|a, b| a.cells[0].total_cmp(&b.cells[0]));
    let times: Vec<f64> = rows.iter().map(|r| r.cells[0]).collect();
    let (first, last) = (times[0], times[times.len() - 1]);
    let mut scans = Vec::new();
    let mut matrices = Vec::new();
    let mut outside = 0usize;
    let flip = Matrix4::from_diagonal(&nalgebra::Vector4::new(1.0, -1.0, -1.0, 1.0));
    for path in files {
        let us = stem_number(&path)?;
        let t = us as f64;
        if !(t > first && t < last) {
            outside += 1;
            continue;
        }
        let row = &rows[nearest_row(&times, t)];
        let c = &row.cells;
        if c[1..7].iter().any(|v| !v.is_finite()) {
            bail!(
                "{}:{}: the pose nearest {} is not finite",
                gt_path.display(),
                row.line,
                path.display()
            );
        }
        let pose = to_f32(&rigid(&zyx(c[6], c[5], c[4]), [c[1], c[2], c[3]]));
        matrices.push(flip * pose * flip);
        scans.push(Scan {
            path,
            time: Some(t * 1e-6),
        });
    }
    let mut warnings = Vec::new();
    if outside > 0 {
        warnings.push(format!(
            "{}: {outside} scan(s) outside the ground truth's time span are left out, as \
             kiss-icp's loader does",
            root.join("velodyne_sync").display()
        ));
    }
    Ok(Layout {
        format: Format::Nclt,
        scans,
        read: Box::new(read_scan),
        truth: Truth {
            path: gt_path,
            matrices,
        },
        warnings,
    })
}

/// The points of one `velodyne_sync` file's bytes, as the loader decodes them.
pub fn decode(bytes: &[u8]) -> Vec<[f64; 3]> {
    let coordinate = |b: &[u8], o: usize| {
        let v = f32::from(i16::from_le_bytes([b[o], b[o + 1]]));
        v * 0.005f32 + -100.0f32
    };
    bytes
        .chunks_exact(POINT_BYTES)
        .map(|p| {
            let (x, y, z) = (coordinate(p, 0), coordinate(p, 2), coordinate(p, 4));
            [f64::from(x), f64::from(-y), f64::from(-z)]
        })
        .collect()
}

/// One `velodyne_sync/<us>.bin` scan; a length that is not a whole number of points is
/// refused (the loader fails on it).
pub fn read_scan(path: &Path, max_points: usize) -> Result<ScanPoints> {
    let len = std::fs::metadata(path)?.len();
    if len == 0 {
        bail!("empty file");
    }
    if len % POINT_BYTES as u64 != 0 {
        bail!(
            "length {len} is not a multiple of {POINT_BYTES} bytes (x y z int16, intensity, \
             laser): truncated or not an NCLT scan"
        );
    }
    let declared = usize::try_from(len / POINT_BYTES as u64).unwrap_or(usize::MAX);
    let keep = declared.min(max_points);
    let (bytes, _) = read_head(path, (keep * POINT_BYTES) as u64)?;
    Ok(ScanPoints {
        points: decode(&bytes),
        stamps: None,
        declared,
        warnings: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coordinates_are_signed_scaled_in_f32_and_flipped() {
        let mut b = Vec::new();
        for v in [20000i16, 20000, 20000] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&[7, 3]);
        let p = decode(&b);
        assert_eq!(p, vec![[0.0, -0.0, -0.0]]);
        let b = [0xff, 0xff, 0, 0, 0, 0, 0, 0]; // -1 as int16
        let x = decode(&b)[0][0];
        assert_eq!(x, f64::from(-0.005f32 - 100.0f32));
    }

    #[test]
    fn nearest_row_splits_at_midpoints_and_ties_go_to_the_earlier() {
        let t = [0.0, 10.0, 20.0];
        assert_eq!(nearest_row(&t, 4.0), 0);
        assert_eq!(nearest_row(&t, 5.0), 0);
        assert_eq!(nearest_row(&t, 5.5), 1);
        assert_eq!(nearest_row(&t, 19.0), 2);
    }
}
