//! The generic folder layout: one file per scan, plus optional side files.
//!
//! ```text
//! PATH/velodyne/*.bin|*.ply|*.pcd   frames, in natural name order (or directly in PATH)
//! PATH/timestamps/<stem>.bin        per-point times, f64 little-endian, one per point
//! PATH/poses.txt                    ground truth, KITTI 3x4, LiDAR frame, end of each sweep
//! PATH/times.txt                    frame times, one number per line
//! ```
//!
//! This is what `kiss-odom simulate` writes and what most recordings can be converted to. Frames
//! are read one at a time when asked for; a bad frame becomes an [`Item::Skipped`], a bad
//! timestamps file a [`Frame::warnings`] entry.

use super::{bin, pcd, ply, poses, Dataset, DatasetInfo, Format, Frame, FrameSource, Item};
use anyhow::{bail, Context, Result};
use std::cmp::Ordering;
use std::path::{Path, PathBuf};

/// Names of a per-point time field, in the order the reference looks them up
/// (`kiss_icp/datasets/generic.py`): the first one a file has is used.
pub const STAMP_FIELDS: [&str; 5] = ["t", "timestamp", "timestamps", "time", "stamps"];

/// Points of one file and their per-point times, if the file has them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Cloud {
    /// Points in metres, sensor frame.
    pub points: Vec<[f64; 3]>,
    /// One time per point, in the file's unit and offset.
    pub stamps: Option<Vec<f64>>,
}

/// Frame formats of the generic layout and their file extension.
const FRAME_FORMATS: [(Format, &str); 3] = [
    (Format::Bin, "bin"),
    (Format::Ply, "ply"),
    (Format::Pcd, "pcd"),
];

/// The file extension of the frames of `format`, if it is a per-file format.
pub fn frame_extension(format: Format) -> Option<&'static str> {
    FRAME_FORMATS
        .iter()
        .find(|(f, _)| *f == format)
        .map(|(_, ext)| *ext)
}

/// Reads one frame file of `format` (`Bin`, `Ply` or `Pcd`).
pub fn read_cloud(path: &Path, format: Format) -> Result<Cloud> {
    match format {
        Format::Bin => Ok(Cloud {
            points: bin::read(path)?,
            stamps: None,
        }),
        Format::Ply => ply::read(path),
        Format::Pcd => pcd::read(path),
        other => bail!("{other:?} is not a per-file frame format"),
    }
}

/// Orders names so that `scan2` comes before `scan10`: runs of digits compare as numbers,
/// everything else byte-wise. Zero-padded names keep their plain order.
pub fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (mut a, mut b) = (a.as_bytes(), b.as_bytes());
    loop {
        match (a.first(), b.first()) {
            (None, None) => return Ordering::Equal,
            (None, Some(_)) => return Ordering::Less,
            (Some(_), None) => return Ordering::Greater,
            (Some(x), Some(y)) if x.is_ascii_digit() && y.is_ascii_digit() => {
                let (da, ra) = split_digits(a);
                let (db, rb) = split_digits(b);
                let (ta, tb) = (trim_zeros(da), trim_zeros(db));
                let order = ta
                    .len()
                    .cmp(&tb.len())
                    .then_with(|| ta.cmp(tb))
                    .then_with(|| da.len().cmp(&db.len()));
                if order != Ordering::Equal {
                    return order;
                }
                (a, b) = (ra, rb);
            }
            (Some(x), Some(y)) => {
                if x != y {
                    return x.cmp(y);
                }
                (a, b) = (&a[1..], &b[1..]);
            }
        }
    }
}

fn split_digits(s: &[u8]) -> (&[u8], &[u8]) {
    let n = s.iter().take_while(|c| c.is_ascii_digit()).count();
    s.split_at(n)
}

fn trim_zeros(s: &[u8]) -> &[u8] {
    let n = s.iter().take_while(|c| **c == b'0').count();
    &s[n..]
}

/// Files in `dir` whose extension is `ext` (case-insensitive), in natural name order.
pub fn list_frames(dir: &Path, ext: &str) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).with_context(|| format!("{}", dir.display()))? {
        let path = entry.with_context(|| format!("{}", dir.display()))?.path();
        let matches = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case(ext));
        if matches && path.is_file() {
            files.push(path);
        }
    }
    files.sort_by(|a, b| natural_cmp(&file_name(a), &file_name(b)));
    Ok(files)
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Where the frames of the generic layout at `root` live: `root/velodyne` if it exists.
pub fn frames_dir(root: &Path) -> PathBuf {
    let velodyne = root.join("velodyne");
    if velodyne.is_dir() {
        velodyne
    } else {
        root.to_path_buf()
    }
}

/// The frame format of the generic layout at `root`, by the extension of the first frame file
/// in name order; `None` if there is no `.bin`, `.ply` or `.pcd` file.
pub fn detect_format(root: &Path) -> Result<Option<Format>> {
    let dir = frames_dir(root);
    let mut first: Option<(String, Format)> = None;
    for (format, ext) in FRAME_FORMATS {
        if let Some(path) = list_frames(&dir, ext)?.first() {
            let name = file_name(path);
            if first
                .as_ref()
                .is_none_or(|(n, _)| natural_cmp(&name, n) == Ordering::Less)
            {
                first = Some((name, format));
            }
        }
    }
    Ok(first.map(|(_, f)| f))
}

/// Reads a `times.txt`-style file: one number per line (blank lines ignored).
pub fn read_times(path: &Path) -> Result<Vec<f64>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    let mut times = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        match line.parse::<f64>() {
            Ok(t) if t.is_finite() => times.push(t),
            _ => bail!("{}:{}: {line:?} is not a time", path.display(), i + 1),
        }
    }
    Ok(times)
}

/// Per-point times from the bytes of a `timestamps/<stem>.bin` file (f64 little-endian).
pub fn parse_timestamps(bytes: &[u8]) -> Result<Vec<f64>> {
    if bytes.len() % 8 != 0 {
        bail!("length {} is not a multiple of 8 bytes", bytes.len());
    }
    Ok(bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]))
        .collect())
}

/// Writes per-point times as a `timestamps/<stem>.bin` file.
pub fn write_timestamps(path: &Path, stamps: &[f64]) -> Result<()> {
    let bytes: Vec<u8> = stamps.iter().flat_map(|t| t.to_le_bytes()).collect();
    std::fs::write(path, bytes).with_context(|| format!("{}", path.display()))
}

/// `path: reason` on one line, for [`Item::Skipped`] and warnings.
pub(crate) fn reason(path: &Path, err: &anyhow::Error) -> String {
    let text = format!("{}: {err:#}", path.display());
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Frames of the generic layout, read on demand.
pub struct GenericSource {
    files: Vec<PathBuf>,
    format: Format,
    stamps_dir: Option<PathBuf>,
    times: Option<Vec<f64>>,
    next: usize,
}

impl GenericSource {
    /// Frames `files` of `format` (`Bin`, `Ply` or `Pcd`); per-point times from
    /// `stamps_dir/<stem>.bin` if given, frame times from `times` if given.
    pub fn new(
        files: Vec<PathBuf>,
        format: Format,
        stamps_dir: Option<PathBuf>,
        times: Option<Vec<f64>>,
    ) -> Self {
        Self {
            files,
            format,
            stamps_dir,
            times,
            next: 0,
        }
    }

    /// Replaces the file's own times by the side file's. A side file that cannot be used is a
    /// warning; the frame keeps the times of its own file (none for `.bin`).
    fn attach_timestamps(&self, path: &Path, frame: &mut Frame) {
        let Some(dir) = &self.stamps_dir else { return };
        let Some(stem) = path.file_stem() else { return };
        let mut side = dir.join(stem);
        side.as_mut_os_string().push(".bin");
        let stamps = std::fs::read(&side)
            .map_err(anyhow::Error::from)
            .and_then(|bytes| parse_timestamps(&bytes))
            .and_then(|stamps| {
                if stamps.len() == frame.points.len() {
                    Ok(stamps)
                } else {
                    bail!(
                        "{} timestamps for {} points; timestamps ignored",
                        stamps.len(),
                        frame.points.len()
                    )
                }
            });
        match stamps {
            Ok(stamps) => frame.stamps = Some(stamps),
            Err(e) => frame.warnings.push(reason(&side, &e)),
        }
    }
}

impl FrameSource for GenericSource {
    fn len_hint(&self) -> Option<usize> {
        Some(self.files.len())
    }

    fn next_item(&mut self) -> Result<Option<Item>> {
        let index = self.next;
        let Some(path) = self.files.get(index) else {
            return Ok(None);
        };
        self.next += 1;
        let cloud = match read_cloud(path, self.format) {
            Ok(cloud) => cloud,
            Err(e) => {
                let reason = reason(path, &e);
                return Ok(Some(Item::Skipped { index, reason }));
            }
        };
        let mut frame = Frame {
            index,
            name: path.display().to_string(),
            points: cloud.points,
            stamps: cloud.stamps,
            time: self.times.as_ref().and_then(|t| t.get(index).copied()),
            warnings: Vec::new(),
        };
        self.attach_timestamps(path, &mut frame);
        Ok(Some(Item::Frame(frame)))
    }

    fn seek(&mut self, index: usize) -> bool {
        if index > self.files.len() {
            return false;
        }
        self.next = index;
        true
    }
}

/// Opens the generic layout at `root`; `format` is `Bin`, `Ply`, `Pcd`, or `None` to pick by
/// the extension of the frames found.
pub fn open(root: &Path, format: Option<Format>) -> Result<Dataset> {
    if !root.is_dir() {
        bail!("{}: not a folder", root.display());
    }
    let format = match format {
        Some(f) => f,
        None => match detect_format(root)? {
            Some(f) => f,
            None => bail!(
                "{}: no frames (*.bin, *.ply or *.pcd) found",
                frames_dir(root).display()
            ),
        },
    };
    let Some(ext) = frame_extension(format) else {
        bail!("{}: {format:?} is not a folder format", root.display());
    };
    let files = list_frames(&frames_dir(root), ext)?;
    if files.is_empty() {
        bail!("{}: no *.{ext} frames found", frames_dir(root).display());
    }

    let stamps_dir = Some(root.join("timestamps")).filter(|d| d.is_dir());
    let times_path = root.join("times.txt");
    let frame_times = if times_path.is_file() {
        Some(read_times(&times_path)?)
    } else {
        None
    };
    let gt_path = root.join("poses.txt");
    let (ground_truth, ground_truth_path) = if gt_path.is_file() {
        (Some(poses::read_kitti(&gt_path)?), Some(gt_path))
    } else {
        (None, None)
    };

    let info = DatasetInfo {
        ground_truth,
        ground_truth_path,
        frame_times: frame_times.clone(),
        format: Some(format),
        kitti_correction: false,
    };
    let frames = GenericSource::new(files, format, stamps_dir, frame_times);
    Ok(Dataset {
        frames: Box::new(frames),
        info,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural_order_compares_digit_runs_as_numbers() {
        let mut names = vec![
            "scan10.bin",
            "scan2.bin",
            "scan1.bin",
            "a.bin",
            "scan02.bin",
        ];
        names.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(
            names,
            [
                "a.bin",
                "scan1.bin",
                "scan2.bin",
                "scan02.bin",
                "scan10.bin"
            ]
        );
    }

    #[test]
    fn natural_order_keeps_zero_padded_order() {
        let names: Vec<String> = (0..1200).map(|i| format!("{i:06}.bin")).collect();
        let mut sorted = names.clone();
        sorted.reverse();
        sorted.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(sorted, names);
    }

    #[test]
    fn timestamps_file_is_f64_little_endian() {
        assert_eq!(
            parse_timestamps(&[0, 0, 0, 0, 0, 0, 0xf0, 0x3f]).unwrap(),
            vec![1.0]
        );
        assert!(parse_timestamps(&[0; 12]).is_err());
    }

    #[test]
    fn reasons_are_one_line_and_name_the_file() {
        let e = anyhow::anyhow!("bad\n\theader").context("outer");
        assert_eq!(
            reason(Path::new("dir/x.ply"), &e),
            "dir/x.ply: outer: bad header"
        );
    }
}
