//! Data for the benchmarks: real KITTI scans (kitti-mini) or a generated sequence, read with
//! the host's own readers, and the odometry run (through the host's driver) that records
//! poses and clouds per frame.

#![allow(dead_code)]

use kiss_odom_core::Pose;
use kiss_odom_drive::Settings;
use kiss_odom_drive::{Driver, FrameMeta};
use kiss_odom_io::{self as io, Format, Item, OpenOptions};
use std::path::{Path, PathBuf};

/// Where kitti-mini is: `KISS_ODOM_KITTI_MINI`, else `../shared/data/kitti-mini` beside the
/// repository.
pub fn kitti_mini() -> PathBuf {
    std::env::var_os("KISS_ODOM_KITTI_MINI")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/kitti-mini")
        })
}

/// One scan in memory.
pub struct Scan {
    /// Points (KITTI scans corrected as the reference does).
    pub points: Vec<[f64; 3]>,
    /// Per-point times, if any.
    pub stamps: Option<Vec<f64>>,
}

/// Up to `max` frames of `path`; `None` (with a message) if the data is missing.
pub fn load(path: &Path, max: usize) -> Option<Vec<Scan>> {
    let mut ds = match io::open(path, Format::Auto, &OpenOptions::default()) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("skipping: {e:#}");
            return None;
        }
    };
    let mut out = Vec::new();
    while out.len() < max {
        match ds.frames.next_item() {
            Ok(Some(Item::Frame(f))) => out.push(Scan {
                points: f.points,
                stamps: f.stamps,
            }),
            Ok(Some(Item::Skipped { .. })) => {}
            Ok(None) => break,
            Err(e) => {
                eprintln!("skipping: {e:#}");
                return None;
            }
        }
    }
    Some(out)
}

/// What the odometry did with each frame.
pub struct Recorded {
    /// Merge cloud (sensor frame, deskewed) of each frame.
    pub merge: Vec<Vec<[f64; 3]>>,
    /// Registered pose of each frame.
    pub poses: Vec<Pose<f64>>,
    /// The prediction each frame started from.
    pub guesses: Vec<Pose<f64>>,
    /// sigma used for each frame.
    pub sigmas: Vec<f64>,
}

/// Runs the full-scale f64 odometry with the default configuration over `scans`.
pub fn record(scans: &[Scan]) -> Recorded {
    let mut settings = Settings::default();
    settings.runtime.threads = 1;
    let mut driver = Driver::new(&settings).unwrap();
    let mut rec = Recorded {
        merge: Vec::new(),
        poses: Vec::new(),
        guesses: Vec::new(),
        sigmas: Vec::new(),
    };
    for s in scans {
        // Eq. (1): the latest pose moved by the latest motion.
        let last = rec.poses.last().copied().unwrap_or_else(Pose::identity);
        let guess = last * driver.last_delta();
        let o = driver
            .register_points(FrameMeta::default(), &s.points, s.stamps.as_deref())
            .unwrap();
        rec.merge.push(driver.merge_cloud());
        rec.poses.push(o.pose);
        rec.guesses.push(guess);
        rec.sigmas.push(o.sigma);
    }
    rec
}
