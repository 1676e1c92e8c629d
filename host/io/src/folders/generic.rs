//! The generic folder layout: one file per scan, plus optional side files.
//!
//! ```text
//! PATH/velodyne/*.bin|*.ply|*.pcd   frames, identified by the number or time in their name
//!                                   (or directly in PATH; see `listing`)
//! PATH/timestamps/<stem>.bin        per-point times, f64 little-endian, one per point
//! PATH/poses.txt                    ground truth, KITTI 3x4, LiDAR frame, end of each sweep
//! PATH/times.txt                    frame times, one number per line
//! PATH/imu.csv                      IMU samples (`crate::imu`), on the frames' clock
//! ```
//!
//! This is what `kiss-odom simulate` writes and what most recordings can be converted to. Row
//! `k` of `poses.txt` and `times.txt` belongs to frame `k` (the number in the name, or the
//! place in time order for time-named frames); a side file with fewer or more rows than that
//! needs is reported. Frames are read one at a time when asked for ([`FileSource`], shared with
//! the KITTI layout); a missing or bad frame becomes an [`Item::Skipped`], a bad timestamps
//! file a [`Frame::warnings`] entry. Each frame takes the IMU samples up to its end (its
//! latest point's time, the clock the IMU shares; else its `times.txt` row) that no earlier
//! frame took; the last frame takes the rest ([`WithImu`]).

use super::file_cloud::{truncation_warning, Cloud};
use super::listing::{self, Listing, Naming, Slot};
use super::{bin, pcd, ply};
use crate::dataset::{
    Dataset, DatasetInfo, Format, Frame, FrameSource, ImuInput, Item, OpenOptions,
};
use crate::imu::{self, attach::WithImu};
use crate::poses;
use anyhow::{bail, Context, Result};
use std::io::Read;
use std::path::{Path, PathBuf};

/// Reads at most `max_points` points of one frame file of `format` (`Bin`, `Ply` or `Pcd`).
pub fn read_cloud(path: &Path, format: Format, max_points: usize) -> Result<Cloud> {
    match format {
        Format::Bin => bin::read_at_most(path, max_points),
        Format::Ply => ply::read_at_most(path, max_points),
        Format::Pcd => pcd::read_at_most(path, max_points),
        other => bail!("{other:?} is not a per-file frame format"),
    }
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

/// The frame format of the generic layout at `root`: the only one its frames have; several is
/// an error naming the counts, none is `None`.
pub fn detect_format(root: &Path) -> Result<Option<Format>> {
    let dir = frames_dir(root);
    match listing::count_formats(&dir)?.as_slice() {
        [] => Ok(None),
        [(format, _)] => Ok(Some(*format)),
        // The listing refuses several formats with the counts and the way out.
        _ => listing::list(&dir, None).map(|l| Some(l.format)),
    }
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
    crate::write::write(path, &bytes)
}

/// `path: reason` on one line, for [`Item::Skipped`] and warnings.
pub(crate) fn reason(path: &Path, err: &anyhow::Error) -> String {
    let text = format!("{}: {err:#}", path.display());
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Per-file frames of a folder (generic or KITTI), read on demand in frame order.
pub struct FileSource {
    slots: Vec<Slot>,
    format: Format,
    stamps_dir: Option<PathBuf>,
    /// Frame times by identity (`times.txt`), for frames whose name is not a time.
    times: Option<Vec<f64>>,
    max_points: usize,
    /// Applied to every scan read (the KITTI correction).
    correct: Option<fn(&mut [[f64; 3]])>,
    next: usize,
}

impl FileSource {
    /// The frames of `listing`; per-point times from `stamps_dir/<stem>.bin` if given, frame
    /// times from `times` (by identity) if given, at most `max_points` points a frame.
    pub fn new(
        listing: Listing,
        stamps_dir: Option<PathBuf>,
        times: Option<Vec<f64>>,
        max_points: usize,
    ) -> Self {
        Self {
            slots: listing.slots,
            format: listing.format,
            stamps_dir,
            times,
            max_points,
            correct: None,
            next: 0,
        }
    }

    /// Applies `correct` to every scan read.
    pub fn with_correction(mut self, correct: fn(&mut [[f64; 3]])) -> Self {
        self.correct = Some(correct);
        self
    }

    /// Replaces the file's own times by the side file's. A side file that cannot be used is a
    /// warning; the frame keeps the times of its own file (none for `.bin`). Only as many
    /// times as points were read are read.
    fn attach_timestamps(&self, path: &Path, declared: usize, frame: &mut Frame) {
        let Some(dir) = &self.stamps_dir else { return };
        let Some(stem) = path.file_stem() else { return };
        let mut side = dir.join(stem);
        side.as_mut_os_string().push(".bin");
        let stamps = read_side_stamps(&side, declared, frame.points.len());
        match stamps {
            Ok(stamps) => frame.stamps = Some(stamps),
            Err(e) => frame.warnings.push(reason(&side, &e)),
        }
    }
}

/// The first `keep` times of a `timestamps/<stem>.bin` file that must hold `declared`.
fn read_side_stamps(side: &Path, declared: usize, keep: usize) -> Result<Vec<f64>> {
    let file = std::fs::File::open(side)?;
    let len = file.metadata()?.len();
    if len % 8 != 0 {
        bail!("length {len} is not a multiple of 8 bytes");
    }
    if len / 8 != declared as u64 {
        bail!(
            "{} timestamps for {declared} points; timestamps ignored",
            len / 8
        );
    }
    let mut bytes = Vec::with_capacity(keep * 8);
    file.take(keep as u64 * 8).read_to_end(&mut bytes)?;
    parse_timestamps(&bytes)
}

impl FrameSource for FileSource {
    fn len_hint(&self) -> Option<usize> {
        Some(self.slots.len())
    }

    fn next_item(&mut self) -> Result<Option<Item>> {
        let Some(slot) = self.slots.get(self.next) else {
            return Ok(None);
        };
        self.next += 1;
        let (index, path) = (slot.index, &slot.path);
        let time = slot
            .time
            .or_else(|| self.times.as_ref().and_then(|t| t.get(index).copied()));
        let name = path.display().to_string();
        let read = match &slot.problem {
            Some(problem) => Err(anyhow::anyhow!("{problem}")),
            None => read_cloud(path, self.format, self.max_points),
        };
        let cloud = match read {
            Ok(cloud) => cloud,
            Err(e) => {
                let reason = reason(path, &e);
                return Ok(Some(Item::Skipped {
                    index,
                    name,
                    time,
                    reason,
                }));
            }
        };
        let mut frame = Frame {
            index,
            name,
            points: cloud.points,
            stamps: cloud.stamps,
            time,
            warnings: Vec::new(),
            intensity: None,
            sweep: None,
            end: None,
            imu: Vec::new(),
        };
        if cloud.declared > frame.points.len() {
            let w = truncation_warning(frame.points.len(), cloud.declared);
            frame.warnings.push(format!("{}: {w}", frame.name));
        }
        if let Some(correct) = self.correct {
            correct(&mut frame.points);
        }
        self.attach_timestamps(path, cloud.declared, &mut frame);
        Ok(Some(Item::Frame(frame)))
    }

    fn seek(&mut self, index: usize) -> bool {
        let end = self.slots.last().map_or(0, |s| s.index + 1);
        if index > end {
            return false;
        }
        self.next = self.slots.partition_point(|s| s.index < index);
        true
    }
}

/// A file with one row per frame (`poses.txt`, `times.txt`), checked against the frames of
/// `listing`: the warning when it has too few rows (naming the frames left without, which lack
/// `what`) or rows that match no frame.
pub(crate) fn check_rows(
    file: &Path,
    rows: usize,
    listing: &Listing,
    what: &str,
) -> Option<String> {
    let last = listing.slots.last()?;
    let shown = file.display();
    let without = listing.slots.iter().filter(|s| s.index >= rows).count();
    if without > 0 {
        let first = listing.slots.iter().find(|s| s.index >= rows)?;
        return Some(format!(
            "{shown} has {rows} rows but the frames go up to {} (frame {}): {without} frame(s) \
             from {} on have no {what}",
            last.path.display(),
            last.index,
            first.path.display(),
        ));
    }
    (rows > last.index + 1).then(|| {
        format!(
            "{shown} has {rows} rows but the last frame is {} (frame {}): its last {} rows \
             match no frame file (frames lost at the end?)",
            last.path.display(),
            last.index,
            rows - last.index - 1
        )
    })
}

/// What a row of `poses.txt` and `times.txt` lacks for a frame without it.
pub(crate) const NO_GROUND_TRUTH: &str = "ground truth (metrics use the frames that have it)";
/// See [`NO_GROUND_TRUTH`].
pub(crate) const NO_TIME: &str =
    "time (poses_tum.txt then gives every frame its number instead of seconds)";

/// Frame times from `times.txt` at `path` for the frames of `listing`, with what is worth
/// reporting; time-named frames keep the times of their names.
pub(crate) fn frame_times(
    path: &Path,
    listing: &Listing,
    warnings: &mut Vec<String>,
) -> Result<Option<Vec<f64>>> {
    if !path.is_file() {
        return Ok(None);
    }
    if listing.naming == Naming::Timed {
        warnings.push(format!(
            "{}: not used, the frame names give the times",
            path.display()
        ));
        return Ok(None);
    }
    let times = read_times(path)?;
    warnings.extend(check_rows(path, times.len(), listing, NO_TIME));
    Ok(Some(times))
}

/// Says how rows of side files pair with frames numbered in steps (thinned sequences).
pub(crate) fn step_note(listing: &Listing, side_files: bool) -> Option<String> {
    match listing.naming {
        Naming::Numbered { step } if step > 1 && side_files => Some(format!(
            "{}: frame numbers go in steps of {step}; frame N is paired with row N of poses.txt \
             and times.txt",
            listing.dir.display()
        )),
        _ => None,
    }
}

/// Opens the generic layout at `root`; `format` is `Bin`, `Ply`, `Pcd`, or `None` to pick by
/// the extension of the frames found.
pub fn open(root: &Path, format: Option<Format>, opts: &OpenOptions) -> Result<Dataset> {
    if !root.is_dir() {
        bail!("{}: not a folder", root.display());
    }
    let listing = listing::list(&frames_dir(root), format)?;
    let mut warnings = listing.warnings.clone();
    let stamps_dir = Some(root.join("timestamps")).filter(|d| d.is_dir());
    let frame_times = frame_times(&root.join("times.txt"), &listing, &mut warnings)?;
    let gt_path = root.join("poses.txt");
    let (ground_truth, ground_truth_path) = if gt_path.is_file() {
        let gt = poses::read_kitti(&gt_path)?;
        warnings.extend(check_rows(&gt_path, gt.len(), &listing, NO_GROUND_TRUTH));
        (Some(gt), Some(gt_path))
    } else {
        (None, None)
    };
    warnings.extend(step_note(
        &listing,
        ground_truth.is_some() || frame_times.is_some(),
    ));
    // `--imu FILE` replaces the folder's own, so that is not read.
    let imu_path = root.join(imu::CSV_NAME);
    let own_imu = imu_path.is_file() && !matches!(opts.imu, ImuInput::File(_));
    let imu_samples = match own_imu.then(|| imu::read_csv(&imu_path)) {
        Some(Ok(samples)) => samples,
        Some(Err(e)) => {
            warnings.push(format!("{e:#}; no IMU samples used"));
            Vec::new()
        }
        None => Vec::new(),
    };

    let info = DatasetInfo {
        ground_truth,
        ground_truth_path,
        frame_times: frame_times.clone(),
        format: Some(listing.format),
        kitti_correction: false,
        warnings,
    };
    let mut frames: Box<dyn FrameSource> = Box::new(FileSource::new(
        listing,
        stamps_dir,
        frame_times.clone(),
        opts.scan_points,
    ));
    if !imu_samples.is_empty() {
        frames = Box::new(WithImu::new(frames, imu_samples).with_times(frame_times));
    }
    Ok(Dataset { frames, info })
}

#[cfg(test)]
mod tests {
    use super::*;

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
