//! The public datasets' own layouts, read as kiss-icp 1.3.0's dataloaders read them
//! (`kiss_icp/datasets/<name>.py`), so that a run's error against ground truth is the figure
//! the paper's tables report.
//!
//! Each dataset has a module that lists its scans, says how one scan file becomes points (and
//! per-point times, where the loader gives them) and reads its ground truth into the frame and
//! with the first-pose convention the loader uses; [`scans`] turns that [`Layout`] into a
//! [`Dataset`] that reads one scan at a time. Frame `i` is the loader's item `i` and ground
//! truth row `i` is its pose. Where a loader casts (float32 points widened to float64, poses
//! stored as float32) the reader does the same, so points agree bit for bit.
//!
//! | format | folder | scans | ground truth |
//! |---|---|---|---|
//! | `mulran` | `SEQ/` | `Ouster/<ns>.bin` | `global_pose.csv`, nearest in time |
//! | `nclt` | `DATE/` | `velodyne_sync/<us>.bin` | `../ground_truth/groundtruth_DATE.csv`, nearest |
//! | `ncd` | `SEQ/` | `raw_format/ouster_scan/cloud_<s>_<ns>.pcd` | `ground_truth/registered_poses.csv` |
//! | `helipr` | `SEQ/` | `LiDAR/<sensor>/<ns>.bin` | `LiDAR_GT/global_<sensor>_gt.txt` |
//! | `boreas` | `SEQ/` | `lidar/<us>.bin` | `applanix/lidar_poses.csv` |
//! | `nuscenes` | `DATAROOT/` | `v1.0-*/sample_data.json` | `ego_pose.json`, `calibrated_sensor.json` |
//! | `apollo` | `SEQ/` | `pcds/<n>.pcd` | `poses/gt_poses.txt` |
//! | `kitti-raw` | `RAW/` | `DATE/DRIVE/velodyne_points/data/*.bin` | `DATE/DRIVE/oxts/data/*.txt` |
//!
//! HeLiPR, nuScenes and KITTI raw hold several sequences under one folder; which one is
//! [`OpenOptions::sequence`] (`--sequence`), as kiss-icp's `--sequence`.

pub mod apollo;
pub mod boreas;
pub mod helipr;
pub mod kitti_raw;
pub mod mulran;
pub mod ncd;
pub mod nclt;
pub mod nuscenes;
pub mod rotation;
pub mod scans;
pub mod table;

use crate::dataset::{Dataset, Format, OpenOptions};
use anyhow::{bail, Result};
use nalgebra::Matrix4;
use std::path::{Path, PathBuf};

/// The dataset layouts this module reads, in the order `auto` tries them.
pub const FORMATS: [Format; 8] = [
    Format::Mulran,
    Format::Nclt,
    Format::Ncd,
    Format::Helipr,
    Format::Boreas,
    Format::Nuscenes,
    Format::Apollo,
    Format::KittiRaw,
];

/// One scan file and what its name (or the dataset's tables) says about it.
#[derive(Clone, Debug, PartialEq)]
pub struct Scan {
    /// The file.
    pub path: PathBuf,
    /// Acquisition time in seconds, if the dataset tells it.
    pub time: Option<f64>,
}

/// Points (and per-point times) of one scan as the dataset's loader returns them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ScanPoints {
    /// Points in metres, after the loader's casts.
    pub points: Vec<[f64; 3]>,
    /// Per-point times as the loader returns them, if it returns any.
    pub stamps: Option<Vec<f64>>,
    /// Points the file holds (more than `points.len()` when cut at the scan capacity).
    pub declared: usize,
    /// Problems that did not stop the scan from being used.
    pub warnings: Vec<String>,
}

/// Reads one scan file, at most `max_points` points.
pub type ReadScan = Box<dyn Fn(&Path, usize) -> Result<ScanPoints>>;

/// Ground truth as the loader holds it: one 4x4 matrix per frame, in the LiDAR frame and
/// with the loader's first-pose convention, including its casts (not re-orthonormalised).
#[derive(Clone, Debug, PartialEq)]
pub struct Truth {
    /// The file it came from.
    pub path: PathBuf,
    /// Row `i` for frame `i`.
    pub matrices: Vec<Matrix4<f64>>,
}

/// A dataset's layout, opened: its scans in the loader's order, how to read one, its ground
/// truth and what was found on the way.
pub struct Layout {
    /// Which dataset.
    pub format: Format,
    /// The scans, frame `i` at `scans[i]`.
    pub scans: Vec<Scan>,
    /// How one scan is read.
    pub read: ReadScan,
    /// The ground truth.
    pub truth: Truth,
    /// Findings about the dataset as a whole, one line each, naming the file.
    pub warnings: Vec<String>,
}

/// Whether `format` is one of the dataset layouts of this module.
pub fn is_layout(format: Format) -> bool {
    FORMATS.contains(&format)
}

/// The folders `format` is recognised by, for messages.
fn signature(format: Format) -> &'static str {
    match format {
        Format::Mulran => "Ouster/",
        Format::Nclt => "velodyne_sync/",
        Format::Ncd => "raw_format/ouster_scan/",
        Format::Helipr => "LiDAR/ and LiDAR_GT/",
        Format::Boreas => "lidar/ and applanix/",
        Format::Nuscenes => "v1.0-*/scene.json",
        Format::Apollo => "pcds/ and poses/",
        Format::KittiRaw => "YYYY_MM_DD/calib_imu_to_velo.txt",
        _ => "",
    }
}

/// Whether the folder `root` has the structure of `format`.
fn matches(format: Format, root: &Path) -> bool {
    match format {
        Format::Mulran => mulran::detect(root),
        Format::Nclt => nclt::detect(root),
        Format::Ncd => ncd::detect(root),
        Format::Helipr => helipr::detect(root),
        Format::Boreas => boreas::detect(root),
        Format::Nuscenes => nuscenes::detect(root),
        Format::Apollo => apollo::detect(root),
        Format::KittiRaw => kitti_raw::detect(root),
        _ => false,
    }
}

/// The dataset layout the folder `root` has, for `--format auto`: `None` when it has none,
/// an error naming both when it has the structure of two.
pub fn detect(root: &Path) -> Result<Option<Format>> {
    let found: Vec<Format> = FORMATS.into_iter().filter(|f| matches(*f, root)).collect();
    match found.as_slice() {
        [] => Ok(None),
        [one] => Ok(Some(*one)),
        [a, b, ..] => bail!(
            "{}: has the structure of two datasets, {} ({}) and {} ({}); name one with --format",
            root.display(),
            name(*a),
            signature(*a),
            name(*b),
            signature(*b)
        ),
    }
}

/// The `--format` value of `format`.
pub fn name(format: Format) -> &'static str {
    match format {
        Format::Mulran => "mulran",
        Format::Nclt => "nclt",
        Format::Ncd => "ncd",
        Format::Helipr => "helipr",
        Format::Boreas => "boreas",
        Format::Nuscenes => "nuscenes",
        Format::Apollo => "apollo",
        Format::KittiRaw => "kitti-raw",
        _ => "?",
    }
}

/// Opens `root` as the dataset layout `format` without reading any scan.
pub fn layout(root: &Path, format: Format, opts: &OpenOptions) -> Result<Layout> {
    if !root.is_dir() {
        bail!("{}: not a folder", root.display());
    }
    match format {
        Format::Mulran => mulran::layout(root),
        Format::Nclt => nclt::layout(root),
        Format::Ncd => ncd::layout(root),
        Format::Helipr => helipr::layout(root, opts.sequence.as_deref()),
        Format::Boreas => boreas::layout(root),
        Format::Nuscenes => nuscenes::layout(root, opts.sequence.as_deref()),
        Format::Apollo => apollo::layout(root),
        Format::KittiRaw => kitti_raw::layout(root, opts.sequence.as_deref()),
        other => bail!("{other:?} is not a dataset layout"),
    }
}

/// Opens `root` as the dataset layout `format`.
pub fn open(root: &Path, format: Format, opts: &OpenOptions) -> Result<Dataset> {
    scans::dataset(layout(root, format, opts)?, opts.scan_points)
}
