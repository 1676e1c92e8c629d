//! KITTI raw (`kiss_icp/datasets/kitti_raw.py`): the raw drives behind the odometry
//! benchmark's sequences, with the OXTS GPS/IMU as ground truth.
//!
//! ```text
//! RAW/DATE/calib_imu_to_velo.txt                         R (9) and T (3): IMU to Velodyne
//! RAW/DATE/DRIVE/velodyne_points/data/NNNNNNNNNN.bin     float32 x y z intensity
//! RAW/DATE/DRIVE/velodyne_points/timestamps.txt          one date and time a scan
//! RAW/DATE/DRIVE/oxts/data/NNNNNNNNNN.txt                lat lon alt roll pitch yaw ... (30)
//! ```
//!
//! `--sequence NN` is the odometry sequence; the loader's table names its drive and frame
//! range. As the loader: every scan gets the KITTI vertical-angle correction and per-point
//! times from the corrected points' azimuth (`0.5 (-atan2(y, x) / pi + 1)`); OXTS packets
//! become poses by pykitti's Mercator projection, are re-based to the first and moved to the
//! Velodyne frame, `T_velo_imu P T_velo_imu^-1`.

use super::rotation::{inverse, rebase, rigid, zyx};
use super::scans::{list, read_f32_bin, Order};
use super::{Layout, Scan, ScanPoints, Truth};
use crate::dataset::Format;
use crate::folders::kitti::correct_scan;
use anyhow::{bail, Context, Result};
use nalgebra::{Matrix3, Matrix4};
use std::path::{Path, PathBuf};

/// The loader's odometry sequences: drive and first and last frame.
pub const SEQUENCES: [(&str, &str, usize, usize); 10] = [
    ("00", "2011_10_03/2011_10_03_drive_0027_sync", 0, 4540),
    ("01", "2011_10_03/2011_10_03_drive_0042_sync", 0, 1100),
    ("02", "2011_10_03/2011_10_03_drive_0034_sync", 0, 4660),
    ("04", "2011_09_30/2011_09_30_drive_0016_sync", 0, 270),
    ("05", "2011_09_30/2011_09_30_drive_0018_sync", 0, 2760),
    ("06", "2011_09_30/2011_09_30_drive_0020_sync", 0, 1100),
    ("07", "2011_09_30/2011_09_30_drive_0027_sync", 0, 1100),
    ("08", "2011_09_30/2011_09_30_drive_0028_sync", 1100, 5170),
    ("09", "2011_09_30/2011_09_30_drive_0033_sync", 0, 1590),
    ("10", "2011_09_30/2011_09_30_drive_0034_sync", 0, 1200),
];

/// Earth radius pykitti's Mercator projection uses (m).
const EARTH_RADIUS: f64 = 6378137.0;

/// Whether `root` looks like the KITTI raw data root: a date folder with the IMU calibration.
pub fn detect(root: &Path) -> bool {
    SEQUENCES.iter().any(|(_, drive, _, _)| {
        let date = drive.split('/').next().unwrap_or("");
        root.join(date).join("calib_imu_to_velo.txt").is_file()
    })
}

/// The sequence `--sequence` names (`4` or `04`), else the only one whose drive is there.
fn sequence(
    root: &Path,
    asked: Option<&str>,
) -> Result<(&'static str, &'static str, usize, usize)> {
    let present: Vec<_> = SEQUENCES
        .iter()
        .filter(|(_, drive, _, _)| root.join(drive).is_dir())
        .copied()
        .collect();
    let list =
        |s: &[(&str, &str, usize, usize)]| s.iter().map(|q| q.0).collect::<Vec<_>>().join(", ");
    match asked {
        Some(asked) => {
            let want = format!("{asked:0>2}");
            SEQUENCES
                .iter()
                .find(|q| q.0 == want)
                .copied()
                .with_context(|| {
                    format!(
                        "--sequence {asked}: kiss-icp maps only the odometry sequences {} to raw \
                     drives",
                        list(&SEQUENCES)
                    )
                })
        }
        None => match present.as_slice() {
            [one] => Ok(*one),
            [] => bail!("{}: none of the mapped drives found", root.display()),
            _ => bail!(
                "{}: several drives ({}); choose one with --sequence",
                root.display(),
                list(&present)
            ),
        },
    }
}

/// The `key: numbers` lines of a KITTI calibration file (lines that are not numbers, such
/// as dates, are skipped as pykitti skips them).
pub fn read_calib(path: &Path) -> Result<Vec<(String, Vec<f64>)>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    Ok(text
        .lines()
        .filter_map(|line| {
            let (key, value) = line.split_once(':')?;
            let numbers: Result<Vec<f64>, _> = value.split_whitespace().map(str::parse).collect();
            Some((key.to_string(), numbers.ok()?))
        })
        .collect())
}

/// `T_velo_imu` from `calib_imu_to_velo.txt`.
pub fn t_velo_imu(path: &Path) -> Result<Matrix4<f64>> {
    let calib = read_calib(path)?;
    let get = |key: &str, n: usize| -> Result<&Vec<f64>> {
        match calib.iter().find(|(k, _)| k == key) {
            Some((_, v)) if v.len() == n => Ok(v),
            Some((_, v)) => bail!(
                "{}: {key} has {} numbers, expected {n}",
                path.display(),
                v.len()
            ),
            None => bail!("{}: no {key} line", path.display()),
        }
    };
    let r = Matrix3::from_row_slice(get("R", 9)?);
    let t = get("T", 3)?;
    Ok(rigid(&r, [t[0], t[1], t[2]]))
}

/// The IMU poses of OXTS packets (lat, lon, alt, roll, pitch, yaw first) by pykitti's
/// Mercator projection, the scale taken from the first packet's latitude.
pub fn oxts_poses(packets: &[[f64; 6]]) -> Vec<Matrix4<f64>> {
    let pi = std::f64::consts::PI;
    let Some(first) = packets.first() else {
        return Vec::new();
    };
    let scale = (first[0] * pi / 180.0).cos();
    packets
        .iter()
        .map(|&[lat, lon, alt, roll, pitch, yaw]| {
            let tx = scale * lon * pi * EARTH_RADIUS / 180.0;
            let ty = scale * EARTH_RADIUS * ((90.0 + lat) * pi / 360.0).tan().ln();
            rigid(&zyx(yaw, pitch, roll), [tx, ty, alt])
        })
        .collect()
}

/// Every packet of the OXTS files (one line each, usually one a file).
fn read_oxts(files: &[PathBuf]) -> Result<Vec<[f64; 6]>> {
    let mut packets = Vec::with_capacity(files.len());
    for file in files {
        let text = std::fs::read_to_string(file).with_context(|| format!("{}", file.display()))?;
        for (i, line) in text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty())
        {
            let values: Vec<f64> = line
                .split_whitespace()
                .map(str::parse)
                .collect::<Result<_, _>>()
                .with_context(|| format!("{}:{}: not numbers", file.display(), i + 1))?;
            if values.len() != 30 || values[..6].iter().any(|v| !v.is_finite()) {
                bail!(
                    "{}:{}: {} values, expected 30 (lat lon alt roll pitch yaw ...)",
                    file.display(),
                    i + 1,
                    values.len()
                );
            }
            packets.push([
                values[0], values[1], values[2], values[3], values[4], values[5],
            ]);
        }
    }
    Ok(packets)
}

/// Seconds since the Unix epoch of a `YYYY-MM-DD HH:MM:SS.fffffffff` line.
pub fn parse_time(line: &str) -> Option<f64> {
    let (date, time) = line.trim().split_once(' ')?;
    let mut d = date.split('-').map(|v| v.parse::<i64>().ok());
    let (y, m, day) = (d.next()??, d.next()??, d.next()??);
    let mut t = time.split(':');
    let (h, min) = (
        t.next()?.parse::<i64>().ok()?,
        t.next()?.parse::<i64>().ok()?,
    );
    let sec = t.next()?.parse::<f64>().ok()?;
    // Days from the civil date (proleptic Gregorian).
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let doy = (153 * (m + if m > 2 { -3 } else { 9 }) + 2) / 5 + day - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    let days = era * 146097 + doe - 719468;
    Some((days * 86400 + h * 3600 + min * 60) as f64 + sec)
}

/// Opens the KITTI raw drive of the odometry sequence `asked` under `root`.
pub fn layout(root: &Path, asked: Option<&str>) -> Result<Layout> {
    let (_, drive, first, last) = sequence(root, asked)?;
    let drive_dir = root.join(drive);
    let date = drive.split('/').next().unwrap_or("");
    let slice = |v: Vec<PathBuf>| -> Vec<PathBuf> {
        v.into_iter().skip(first).take(last + 1 - first).collect()
    };
    let files = slice(list(
        &drive_dir.join("velodyne_points/data"),
        "bin",
        Order::Bytes,
    )?);
    let oxts_files = slice(list(&drive_dir.join("oxts/data"), "txt", Order::Bytes)?);
    if oxts_files.is_empty() {
        bail!(
            "{}: no OXTS packets (the ground truth)",
            drive_dir.join("oxts/data").display()
        );
    }
    let calib = t_velo_imu(&root.join(date).join("calib_imu_to_velo.txt"))?;
    let imu = rebase(&oxts_poses(&read_oxts(&oxts_files)?), "the first OXTS pose")?;
    let calib_inv = inverse(&calib, "T_velo_imu")?;
    let matrices = imu.iter().map(|p| calib * p * calib_inv).collect();
    let stamps_path = drive_dir.join("velodyne_points/timestamps.txt");
    let times: Vec<Option<f64>> = std::fs::read_to_string(&stamps_path)
        .map(|t| t.lines().map(parse_time).skip(first).collect())
        .unwrap_or_default();
    let scans = files
        .into_iter()
        .enumerate()
        .map(|(i, path)| Scan {
            path,
            time: times.get(i).copied().flatten(),
        })
        .collect();
    Ok(Layout {
        format: Format::KittiRaw,
        scans,
        read: Box::new(read_scan),
        truth: Truth {
            path: drive_dir.join("oxts/data"),
            matrices,
        },
        warnings: Vec::new(),
    })
}

/// Per-point times from the azimuth of (corrected) points, in float64.
pub fn azimuth_stamps(points: &[[f64; 3]]) -> Vec<f64> {
    points
        .iter()
        .map(|p| 0.5 * (-p[1].atan2(p[0]) / std::f64::consts::PI + 1.0))
        .collect()
}

/// One scan: float32 x y z intensity, widened, corrected; azimuth times.
pub fn read_scan(path: &Path, max_points: usize) -> Result<ScanPoints> {
    let mut scan = read_f32_bin(path, 4, max_points)?;
    correct_scan(&mut scan.points);
    scan.stamps = Some(azimuth_stamps(&scan.points));
    Ok(scan)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_are_seconds_since_the_epoch() {
        assert_eq!(parse_time("1970-01-01 00:00:01.5"), Some(1.5));
        assert_eq!(
            parse_time("2011-10-03 12:55:34.000000000"),
            Some(1317646534.0)
        );
        assert_eq!(parse_time("garbage"), None);
    }

    #[test]
    fn the_first_packet_is_the_origin_of_its_projection() {
        let p = oxts_poses(&[
            [49.0, 8.4, 110.0, 0.0, 0.0, 0.3],
            [49.0, 8.4001, 110.0, 0.0, 0.0, 0.3],
        ]);
        let d = inverse(&p[0], "p").unwrap() * p[1];
        // 0.0001 degrees of longitude at 49 degrees north: about 7.3 m.
        let moved = (d[(0, 3)].powi(2) + d[(1, 3)].powi(2)).sqrt();
        assert!((moved - 7.3).abs() < 0.1, "{moved}");
    }
}
