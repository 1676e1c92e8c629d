//! HeLiPR (`kiss_icp/datasets/helipr.py`): four LiDARs on one car, each its own sequence.
//!
//! ```text
//! SEQ/LiDAR/<sensor>/<ns>.bin              packed records (below), x y z float32 first
//! SEQ/LiDAR_GT/global_<sensor>_gt.txt      ns x y z qx qy qz qw, LiDAR frame; row i for scan i
//! ```
//!
//! `<sensor>` is `--sequence`: `Ouster`, `Velodyne`, `Avia` (Livox) or `Aeva`. Records are
//! packed with no padding, little-endian:
//!
//! | sensor | record | bytes | time field |
//! |---|---|---|---|
//! | Ouster | x y z intensity f32, t u32, reflectivity ring ambient u16 | 26 | t (ns) at 16 |
//! | Velodyne | x y z intensity f32, ring u16, time f32 | 22 | time (s) at 18 |
//! | Avia | x y z f32, reflectivity tag line u8, offset time u32 | 19 | offset (ns) at 15 |
//! | Aeva | x y z reflectivity velocity f32, time offset i32, line u8, intensity f32 | 29 | offset (ns) at 20 |
//!
//! Aeva scans named up to 1691936557946849179 ns have no intensity (25 bytes). As the loader:
//! records are taken while `offset < length - record`, so a file of whole records loses its
//! last one; per-point times are the time field scaled to [0, 1]; poses are not re-based.

use super::rotation::{quaternion_matrix, rigid};
use super::scans::{list, read_head, stem_number, Order};
use super::table::{self, Sep};
use super::{Layout, Scan, ScanPoints, Truth};
use crate::dataset::Format;
use anyhow::{bail, Result};
use std::path::Path;

/// The four sensors, as their folders are named.
pub const SENSORS: [&str; 4] = ["Ouster", "Velodyne", "Avia", "Aeva"];

/// Aeva scans named up to this (ns) were recorded without the intensity field.
pub const AEVA_NO_INTENSITY_UNTIL: u64 = 1_691_936_557_946_849_179;

/// Whether `root` looks like a HeLiPR sequence.
pub fn detect(root: &Path) -> bool {
    root.join("LiDAR").is_dir() && root.join("LiDAR_GT").is_dir()
}

/// How one sensor's records are laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Record {
    /// Bytes a record.
    pub size: usize,
    /// Where the time field starts.
    pub time_at: usize,
    /// The time field's type.
    pub time: TimeField,
}

/// Types of the time field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeField {
    /// Unsigned 32-bit.
    U32,
    /// Signed 32-bit.
    I32,
    /// float32.
    F32,
}

/// The record of `sensor`'s scan named `ns`.
pub fn record(sensor: &str, ns: u64) -> Option<Record> {
    let (size, time_at, time) = match sensor {
        "Ouster" => (26, 16, TimeField::U32),
        "Velodyne" => (22, 18, TimeField::F32),
        "Avia" => (19, 15, TimeField::U32),
        "Aeva" if ns <= AEVA_NO_INTENSITY_UNTIL => (25, 20, TimeField::I32),
        "Aeva" => (29, 20, TimeField::I32),
        _ => return None,
    };
    Some(Record {
        size,
        time_at,
        time,
    })
}

/// The sensor `--sequence` names (any case), else the only one `root/LiDAR` has.
fn sensor(root: &Path, sequence: Option<&str>) -> Result<&'static str> {
    let present: Vec<&'static str> = SENSORS
        .into_iter()
        .filter(|s| root.join("LiDAR").join(s).is_dir())
        .collect();
    match sequence {
        Some(asked) => match SENSORS.iter().find(|s| s.eq_ignore_ascii_case(asked)) {
            Some(s) => Ok(s),
            None => bail!(
                "--sequence {asked}: HeLiPR's sensors are {} (this sequence has {})",
                SENSORS.join(", "),
                present.join(", ")
            ),
        },
        None => match present.as_slice() {
            [one] => Ok(one),
            [] => bail!(
                "{}: none of the sensor folders {} found",
                root.join("LiDAR").display(),
                SENSORS.join(", ")
            ),
            several => bail!(
                "{}: several sensors ({}); choose one with --sequence",
                root.join("LiDAR").display(),
                several.join(", ")
            ),
        },
    }
}

/// Opens the HeLiPR sequence at `root` for the sensor `sequence` names.
pub fn layout(root: &Path, sequence: Option<&str>) -> Result<Layout> {
    let sensor = sensor(root, sequence)?;
    let files = list(&root.join("LiDAR").join(sensor), "bin", Order::Bytes)?;
    if files.is_empty() {
        bail!(
            "{}: no .bin scans",
            root.join("LiDAR").join(sensor).display()
        );
    }
    let gt_path = root.join(format!("LiDAR_GT/global_{sensor}_gt.txt"));
    let rows = table::read(&gt_path, Sep::Space, 0, 8, "HeLiPR's ground truth")?;
    let mut matrices = Vec::with_capacity(rows.len());
    for row in &rows {
        let c = &row.cells;
        if c[1..8].iter().any(|v| !v.is_finite()) {
            bail!("{}:{}: the pose is not finite", gt_path.display(), row.line);
        }
        matrices.push(rigid(
            &quaternion_matrix(c[7], c[4], c[5], c[6]),
            [c[1], c[2], c[3]],
        ));
    }
    let mut scans = Vec::with_capacity(files.len());
    for path in files {
        let ns = stem_number(&path)?;
        scans.push(Scan {
            path,
            time: Some(ns as f64 * 1e-9),
        });
    }
    Ok(Layout {
        format: Format::Helipr,
        scans,
        read: Box::new(move |path, max| read_scan(sensor, path, max)),
        truth: Truth {
            path: gt_path,
            matrices,
        },
        warnings: Vec::new(),
    })
}

/// The records the loader takes from a file of `len` bytes: those starting before
/// `len - size`.
pub fn records_taken(len: u64, size: usize) -> u64 {
    let size = size as u64;
    match len.checked_sub(size) {
        Some(limit) => limit.div_ceil(size),
        None => 0,
    }
}

/// Points and per-point times of `bytes` (whole records of `rec`).
pub fn decode(bytes: &[u8], rec: Record) -> (Vec<[f64; 3]>, Vec<f64>) {
    let f = |r: &[u8], o: usize| f32::from_le_bytes([r[o], r[o + 1], r[o + 2], r[o + 3]]);
    let mut points = Vec::with_capacity(bytes.len() / rec.size);
    let mut times = Vec::with_capacity(bytes.len() / rec.size);
    for r in bytes.chunks_exact(rec.size) {
        points.push([f(r, 0), f(r, 4), f(r, 8)].map(f64::from));
        let o = rec.time_at;
        let word = [r[o], r[o + 1], r[o + 2], r[o + 3]];
        times.push(match rec.time {
            TimeField::U32 => f64::from(u32::from_le_bytes(word)),
            TimeField::I32 => f64::from(i32::from_le_bytes(word)),
            TimeField::F32 => f64::from(f32::from_le_bytes(word)),
        });
    }
    (points, times)
}

/// One scan of `sensor`, as the loader reads it.
pub fn read_scan(sensor: &str, path: &Path, max_points: usize) -> Result<ScanPoints> {
    let ns = stem_number(path)?;
    let Some(rec) = record(sensor, ns) else {
        bail!("{sensor} is not a HeLiPR sensor");
    };
    let len = std::fs::metadata(path)?.len();
    let taken = records_taken(len, rec.size);
    if taken == 0 {
        bail!(
            "{len} bytes: no {sensor} record ({} bytes) before the last",
            rec.size
        );
    }
    let declared = usize::try_from(taken).unwrap_or(usize::MAX);
    let keep = declared.min(max_points);
    // Time scaling needs the whole scan's extremes, so all its records are read.
    let (bytes, _) = read_head(path, taken * rec.size as u64)?;
    let (mut points, times) = decode(&bytes, rec);
    let mut warnings = Vec::new();
    let lo = times.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = times.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut stamps = if hi > lo {
        Some(
            times
                .iter()
                .map(|t| (t - lo) / (hi - lo))
                .collect::<Vec<f64>>(),
        )
    } else {
        warnings.push(format!(
            "{}: every point has the same time: read without per-point times (no deskew)",
            path.display()
        ));
        None
    };
    if len % rec.size as u64 != 0 {
        warnings.push(format!(
            "{}: length {len} is not a whole number of {}-byte {sensor} records: the {} \
             whole ones are read",
            path.display(),
            rec.size,
            taken
        ));
    }
    points.truncate(keep);
    if let Some(s) = stamps.as_mut() {
        s.truncate(keep);
    }
    Ok(ScanPoints {
        points,
        stamps,
        declared,
        warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_of_whole_records_loses_its_last_as_the_loader_does() {
        assert_eq!(records_taken(26 * 3, 26), 2);
        assert_eq!(records_taken(26 * 3 + 5, 26), 3);
        assert_eq!(records_taken(26, 26), 0);
        assert_eq!(records_taken(10, 26), 0);
    }

    #[test]
    fn aeva_loses_its_intensity_before_the_cutoff() {
        assert_eq!(record("Aeva", AEVA_NO_INTENSITY_UNTIL).unwrap().size, 25);
        assert_eq!(
            record("Aeva", AEVA_NO_INTENSITY_UNTIL + 1).unwrap().size,
            29
        );
        assert_eq!(record("Ouster", 0).unwrap().size, 26);
        assert_eq!(record("Livox", 0), None);
    }
}
