//! What every dataset layout shares: listing its scan files, reading one on demand
//! ([`LayoutSource`]), and a [`Layout`] made into a [`Dataset`] whose ground truth has been
//! checked against the scans.

use super::{Layout, Scan, ScanPoints};
use crate::dataset::{Dataset, DatasetInfo, Frame, FrameSource, Item};
use crate::folders::file_cloud::truncation_warning;
use crate::folders::listing::natural_cmp;
use crate::poses;
use anyhow::{bail, Context, Result};
use nalgebra::Isometry3;
use std::io::Read;
use std::path::{Path, PathBuf};

/// How a loader orders the files it lists.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// Python's `sorted` of the names: byte by byte.
    Bytes,
    /// `natsort.natsorted`: runs of digits as numbers.
    Natural,
}

/// The files in `dir` whose name ends in `.ext` (none hidden, as Python's `glob` skips them),
/// in `order`.
pub fn list(dir: &Path, ext: &str, order: Order) -> Result<Vec<PathBuf>> {
    if !dir.is_dir() {
        bail!("{}: no such folder", dir.display());
    }
    let suffix = format!(".{ext}");
    let mut names: Vec<String> = Vec::new();
    for entry in std::fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))? {
        let entry = entry.with_context(|| format!("listing {}", dir.display()))?;
        let Ok(name) = entry.file_name().into_string() else {
            continue;
        };
        if name.ends_with(&suffix) && !name.starts_with('.') && entry.path().is_file() {
            names.push(name);
        }
    }
    match order {
        Order::Bytes => names.sort(),
        Order::Natural => names.sort_by(|a, b| natural_cmp(a, b)),
    }
    Ok(names.into_iter().map(|n| dir.join(n)).collect())
}

/// The whole number a scan's name starts with (`1234.bin`, `1234.pcd.bin`), as the loaders'
/// `int(name.split(".")[0])`.
pub fn stem_number(path: &Path) -> Result<u64> {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
    let stem = name.split('.').next().unwrap_or("");
    stem.parse::<u64>().with_context(|| {
        format!(
            "{}: the name is not a time (a whole number before the first dot)",
            path.display()
        )
    })
}

/// The first `max_bytes` bytes of `path` and the file's length.
pub fn read_head(path: &Path, max_bytes: u64) -> Result<(Vec<u8>, u64)> {
    let file = std::fs::File::open(path)?;
    let len = file.metadata()?.len();
    let mut bytes = Vec::with_capacity(len.min(max_bytes).min(1 << 28) as usize);
    file.take(max_bytes).read_to_end(&mut bytes)?;
    if (bytes.len() as u64) < len.min(max_bytes) {
        bail!("file shrank while it was read");
    }
    Ok((bytes, len))
}

/// Little-endian `f32`s of fixed-size records: `fields` floats from the start of each of
/// `record` bytes, widened to `f64` (the loaders read float32 and cast).
pub fn f32_records(bytes: &[u8], record: usize, fields: usize) -> Vec<[f64; 3]> {
    bytes
        .chunks_exact(record)
        .map(|r| {
            let at = |i: usize| {
                let o = 4 * i;
                f64::from(f32::from_le_bytes([r[o], r[o + 1], r[o + 2], r[o + 3]]))
            };
            debug_assert!(fields >= 3);
            [at(0), at(1), at(2)]
        })
        .collect()
}

/// A `.bin` scan of little-endian `f32` records of `floats` values each, x, y, z first, as
/// `np.fromfile(..., float32).reshape(-1, floats)[:, :3]` reads it: a length that is not a
/// whole number of records is refused, an empty file is no scan.
pub fn read_f32_bin(path: &Path, floats: usize, max_points: usize) -> Result<ScanPoints> {
    let record = 4 * floats;
    let len = std::fs::metadata(path)?.len();
    if len == 0 {
        bail!("empty file");
    }
    if len % record as u64 != 0 {
        bail!("length {len} is not a multiple of {record} bytes ({floats} float32 a point)");
    }
    let declared = usize::try_from(len / record as u64).unwrap_or(usize::MAX);
    let keep = declared.min(max_points);
    let (bytes, _) = read_head(path, (keep * record) as u64)?;
    Ok(ScanPoints {
        points: f32_records(&bytes, record, floats),
        stamps: None,
        declared,
        warnings: Vec::new(),
    })
}

/// The per-point times MulRan's and Newer College's loaders give a whole 64 x 1024 Ouster
/// scan (column-major: point `i` is in column `i / 64` of 1024), `floor(i / 64) / 1024`;
/// `None` for a scan of another size, which the loaders read without times.
pub fn ouster_grid_stamps(declared: usize, kept: usize) -> Option<Vec<f64>> {
    const H: usize = 64;
    const W: usize = 1024;
    (declared == H * W).then(|| {
        (0..kept)
            .map(|i| (i as f64 / H as f64).floor() / W as f64)
            .collect()
    })
}

/// The warning for a scan the Ouster grid times do not fit.
pub fn grid_warning(path: &Path, declared: usize) -> String {
    format!(
        "{}: {declared} points, not the 65536 (64 x 1024) of a whole Ouster scan: read without \
         per-point times (no deskew), as kiss-icp's loader does",
        path.display()
    )
}

/// The scans of a layout, read one at a time in order.
pub struct LayoutSource {
    scans: Vec<Scan>,
    read: super::ReadScan,
    max_points: usize,
    next: usize,
}

impl FrameSource for LayoutSource {
    fn len_hint(&self) -> Option<usize> {
        Some(self.scans.len())
    }

    fn next_item(&mut self) -> Result<Option<Item>> {
        let index = self.next;
        let Some(scan) = self.scans.get(index) else {
            return Ok(None);
        };
        self.next += 1;
        let name = scan.path.display().to_string();
        let read = match (self.read)(&scan.path, self.max_points) {
            Ok(read) => read,
            Err(e) => {
                return Ok(Some(Item::Skipped {
                    index,
                    name,
                    time: scan.time,
                    reason: crate::folders::generic::reason(&scan.path, &e),
                }))
            }
        };
        let mut warnings = read.warnings;
        if read.declared > read.points.len() {
            let w = truncation_warning(read.points.len(), read.declared);
            warnings.push(format!("{name}: {w}"));
        }
        Ok(Some(Item::Frame(Frame {
            index,
            name,
            points: read.points,
            stamps: read.stamps,
            time: scan.time,
            warnings,
            ..Frame::default()
        })))
    }

    fn seek(&mut self, index: usize) -> bool {
        self.next = index.min(self.scans.len());
        true
    }
}

/// The warning for ground truth with `rows` poses for `scans` scans, if they differ.
pub fn count_warning(truth: &Path, rows: usize, scans: &[Scan]) -> Option<String> {
    let n = scans.len();
    if rows < n {
        let first = &scans[rows].path;
        Some(format!(
            "{} has {rows} poses for {n} scans: the {} scan(s) from {} on have no ground truth \
             (metrics use the frames that have it; kiss-icp's loader would stop here)",
            truth.display(),
            n - rows,
            first.display()
        ))
    } else {
        (rows > n).then(|| {
            format!(
                "{} has {rows} poses for {n} scans: its last {} match no scan (scans lost at \
                 the end?)",
                truth.display(),
                rows - n
            )
        })
    }
}

/// `layout` as a dataset: its ground truth as rigid transforms (projected onto SO(3)), its
/// scans read at most `max_points` points each.
pub fn dataset(layout: Layout, max_points: usize) -> Result<Dataset> {
    let Layout {
        format,
        scans,
        read,
        truth,
        mut warnings,
    } = layout;
    let ground_truth = truth
        .matrices
        .iter()
        .enumerate()
        .map(|(i, m)| {
            poses::isometry_from_matrix(m)
                .with_context(|| format!("{}: pose of frame {i}", truth.path.display()))
        })
        .collect::<Result<Vec<Isometry3<f64>>>>()?;
    warnings.extend(count_warning(&truth.path, ground_truth.len(), &scans));
    let frame_times: Option<Vec<f64>> = scans.iter().map(|s| s.time).collect();
    let info = DatasetInfo {
        ground_truth: Some(ground_truth),
        ground_truth_path: Some(truth.path),
        frame_times,
        format: Some(format),
        kitti_correction: format == crate::dataset::Format::KittiRaw,
        warnings,
    };
    let frames = LayoutSource {
        scans,
        read,
        max_points,
        next: 0,
    };
    Ok(Dataset {
        frames: Box::new(frames),
        info,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_times_are_column_major_and_only_for_whole_scans() {
        let t = ouster_grid_stamps(65536, 65536).unwrap();
        assert_eq!(t[0], 0.0);
        assert_eq!(t[63], 0.0);
        assert_eq!(t[64], 1.0 / 1024.0);
        assert_eq!(t[65535], 1023.0 / 1024.0);
        assert_eq!(ouster_grid_stamps(65536, 10).unwrap().len(), 10);
        assert!(ouster_grid_stamps(65535, 65535).is_none());
    }

    #[test]
    fn names_are_times_before_the_first_dot() {
        assert_eq!(stem_number(Path::new("a/1234.pcd.bin")).unwrap(), 1234);
        let e = format!("{:#}", stem_number(Path::new("a/x1.bin")).unwrap_err());
        assert!(e.contains("a/x1.bin") && e.contains("not a time"), "{e}");
    }

    #[test]
    fn counts_that_disagree_are_named() {
        let scans: Vec<Scan> = (0..3)
            .map(|i| Scan {
                path: PathBuf::from(format!("s/{i}.bin")),
                time: None,
            })
            .collect();
        let w = count_warning(Path::new("gt.csv"), 2, &scans).unwrap();
        assert!(
            w.contains("2 poses for 3 scans") && w.contains("s/2.bin"),
            "{w}"
        );
        let w = count_warning(Path::new("gt.csv"), 5, &scans).unwrap();
        assert!(w.contains("last 2 match no scan"), "{w}");
        assert_eq!(count_warning(Path::new("gt.csv"), 3, &scans), None);
    }
}
