//! The KITTI odometry benchmark layout, read as the reference kiss-icp 1.3.0 reads it
//! (`kiss_icp/datasets/kitti.py`).
//!
//! ```text
//! .../sequences/XX/velodyne/NNNNNN.bin   scans (see `bin`)
//! .../sequences/XX/calib.txt             `Tr:` LiDAR to left camera, 12 numbers
//! .../sequences/XX/times.txt             frame times
//! .../poses/XX.txt  or  sequences/XX/poses.txt   ground truth, left camera frame
//! ```
//!
//! Two things make this more than the generic layout: every scan gets the reference's vertical
//! angle correction ([`correct_scan`]), and ground truth is moved from the camera to the LiDAR
//! frame ([`lidar_ground_truth`]) with `Tr` rounded to `f32` as the reference does.

use super::generic::{check_rows, frame_times, step_note, FileSource, NO_GROUND_TRUTH};
use super::listing;
use crate::dataset::{Dataset, DatasetInfo, Format, OpenOptions};
use crate::poses;
use anyhow::{bail, Context, Result};
use nalgebra::{Isometry3, Matrix4};
use std::path::{Path, PathBuf};

/// The reference's `VERTICAL_ANGLE_OFFSET`: KITTI scans are tilted down by about 0.2 degrees.
pub const VERTICAL_ANGLE_OFFSET: f64 = (0.205 * core::f64::consts::PI) / 180.0;

/// The reference's KITTI scan correction (`CorrectKITTIScan` in kiss-icp's C++): each point `p`
/// is rotated by [`VERTICAL_ANGLE_OFFSET`] about `normalize(p x z)`, which lifts it towards +z
/// while keeping its range and azimuth.
///
/// This is Eigen's `AngleAxisd(angle, axis.normalized()) * p` term by term (Eigen builds the
/// rotation matrix, then multiplies), including its degenerate case: a point on the z axis has
/// a zero axis, which Eigen leaves unnormalised, giving the matrix `cos(angle) * I`.
pub fn correct_scan(points: &mut [[f64; 3]]) {
    let (s, c) = VERTICAL_ANGLE_OFFSET.sin_cos();
    for p in points {
        let [x, y, z] = *p;
        // p x (0, 0, 1)
        let mut axis = [y, -x, 0.0];
        let n2 = axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2];
        if n2 > 0.0 {
            let n = n2.sqrt();
            axis = axis.map(|a| a / n);
        }
        let sin_axis = axis.map(|a| s * a);
        let cos1_axis = axis.map(|a| (1.0 - c) * a);
        let xy = cos1_axis[0] * axis[1];
        let xz = cos1_axis[0] * axis[2];
        let yz = cos1_axis[1] * axis[2];
        let r = [
            [
                cos1_axis[0] * axis[0] + c,
                xy - sin_axis[2],
                xz + sin_axis[1],
            ],
            [
                xy + sin_axis[2],
                cos1_axis[1] * axis[1] + c,
                yz - sin_axis[0],
            ],
            [
                xz - sin_axis[1],
                yz + sin_axis[0],
                cos1_axis[2] * axis[2] + c,
            ],
        ];
        *p = r.map(|row| row[0] * x + row[1] * y + row[2] * z);
    }
}

/// `Tr` (LiDAR to left camera) from a KITTI `calib.txt`, as a 4x4 matrix. Each number is parsed
/// as `f64` and rounded to `f32`, as the reference's `read_calib_file` does with
/// `np.array(values, dtype=np.float32)`; this moves ground truth by up to about 1e-8.
pub fn read_calib_tr(path: &Path) -> Result<Matrix4<f64>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    for (i, line) in text.lines().enumerate() {
        let mut tokens = line.split_whitespace();
        if !matches!(tokens.next(), Some("Tr:" | "Tr")) {
            continue;
        }
        let values: Vec<f64> = tokens
            .map(|t| t.parse::<f64>().map(|v| f64::from(v as f32)))
            .collect::<Result<_, _>>()
            .with_context(|| format!("{}:{}: Tr is not numbers", path.display(), i + 1))?;
        let Ok(rows) = poses::Rows::try_from(values.as_slice()) else {
            bail!(
                "{}:{}: Tr has {} numbers, expected 12",
                path.display(),
                i + 1,
                values.len()
            );
        };
        // Values beyond f32's range became infinite above (found by fuzzing).
        if values.iter().any(|v| !v.is_finite()) {
            bail!("{}:{}: Tr has a non-finite value", path.display(), i + 1);
        }
        return Ok(poses::matrix_from_rows(&rows));
    }
    bail!("{}: no Tr line", path.display())
}

/// Camera-frame poses moved to the LiDAR frame: `Tr^-1 * T_cam * Tr`, evaluated left to right
/// with a general 4x4 inverse of `Tr`, as the reference does (`Tr` is not exactly rigid).
pub fn lidar_ground_truth(cam: &[Matrix4<f64>], tr: &Matrix4<f64>) -> Result<Vec<Matrix4<f64>>> {
    let Some(tr_inv) = tr.try_inverse() else {
        bail!("Tr is not invertible");
    };
    Ok(cam.iter().map(|t| tr_inv * t * tr).collect())
}

/// Where the ground truth of the sequence at `seq` is: the benchmark's `../../poses/XX.txt`
/// (what the reference reads), else `poses.txt` beside the scans.
pub fn ground_truth_path(seq: &Path) -> Option<PathBuf> {
    let seq = std::fs::canonicalize(seq).ok()?;
    let benchmark = seq.file_name().and_then(|name| {
        let mut file = name.to_os_string();
        file.push(".txt");
        Some(seq.parent()?.parent()?.join("poses").join(file))
    });
    benchmark
        .into_iter()
        .chain([seq.join("poses.txt")])
        .find(|p| p.is_file())
}

/// The LiDAR-frame ground truth of the sequence at `seq` as full matrices (what the reference
/// holds), with the file it came from; `None` without a ground-truth file.
pub fn ground_truth_matrices(seq: &Path) -> Result<Option<(PathBuf, Vec<Matrix4<f64>>)>> {
    let Some(path) = ground_truth_path(seq) else {
        return Ok(None);
    };
    let tr = read_calib_tr(&seq.join("calib.txt"))?;
    let cam = poses::read_kitti_matrices(&path)?;
    let lidar = lidar_ground_truth(&cam, &tr).with_context(|| format!("{}", seq.display()))?;
    Ok(Some((path, lidar)))
}

/// Whether `seq` is a KITTI benchmark sequence folder for `--format auto`: a `calib.txt` with
/// `Tr` and no `timestamps/` folder (per-point times mark the generic layout). A KITTI-shaped
/// folder (`calib.txt` beside `velodyne/`) whose `calib.txt` has no usable `Tr` is refused: read as generic, its scans would miss the KITTI
/// correction and its camera-frame ground truth would be scored as LiDAR poses.
pub fn detect(seq: &Path) -> Result<bool> {
    let calib = seq.join("calib.txt");
    if seq.join("timestamps").is_dir() || !calib.is_file() {
        return Ok(false);
    }
    match read_calib_tr(&calib) {
        Ok(_) => Ok(true),
        Err(e) if seq.join("velodyne").is_dir() => bail!(
            "{e:#}: {} looks like a KITTI sequence (calib.txt beside velodyne/), but without Tr \
             (LiDAR to camera) its camera-frame ground truth cannot be scored as LiDAR poses; \
             add the Tr line, or run with --format kitti to read it as KITTI without ground \
             truth (if it is not KITTI data, name its frame format with --format)",
            seq.display()
        ),
        Err(_) => Ok(false),
    }
}

/// Opens the KITTI sequence folder `seq` (`.../sequences/XX`). Without a usable `Tr` in
/// `calib.txt` the ground truth is not used, with a warning.
pub fn open(seq: &Path, opts: &OpenOptions) -> Result<Dataset> {
    let velodyne = seq.join("velodyne");
    if !velodyne.is_dir() {
        bail!("{}: no velodyne/ folder", seq.display());
    }
    let listing = listing::list(&velodyne, Some(Format::Bin))?;
    let mut warnings = listing.warnings.clone();
    let times = frame_times(&seq.join("times.txt"), &listing, &mut warnings)?;
    let found = match ground_truth_matrices(seq) {
        Ok(found) => found,
        Err(e)
            if ground_truth_path(seq).is_some()
                && read_calib_tr(&seq.join("calib.txt")).is_err() =>
        {
            warnings.push(format!(
                "{e:#}: ground truth not used (it is in the camera frame, and Tr is needed to \
                 score it against LiDAR poses)"
            ));
            None
        }
        Err(e) => return Err(e),
    };
    let (ground_truth, ground_truth_path) = match found {
        Some((path, matrices)) => {
            let poses = matrices
                .iter()
                .enumerate()
                .map(|(i, m)| {
                    poses::isometry_from_matrix(m)
                        .with_context(|| format!("{}:{}", path.display(), i + 1))
                })
                .collect::<Result<Vec<Isometry3<f64>>>>()?;
            warnings.extend(check_rows(&path, poses.len(), &listing, NO_GROUND_TRUTH));
            (Some(poses), Some(path))
        }
        None => (None, None),
    };
    warnings.extend(step_note(
        &listing,
        ground_truth.is_some() || times.is_some(),
    ));
    let info = DatasetInfo {
        ground_truth,
        ground_truth_path,
        frame_times: times.clone(),
        format: Some(Format::Kitti),
        kitti_correction: true,
        warnings,
    };
    let frames =
        FileSource::new(listing, None, times, opts.scan_points).with_correction(correct_scan);
    Ok(Dataset {
        frames: Box::new(frames),
        info,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn correction_keeps_range_and_azimuth_and_lifts_by_the_offset() {
        let mut points = vec![[10.0, 0.0, 0.0], [-3.0, 4.0, -1.0], [0.1, -50.0, 2.0]];
        let before = points.clone();
        correct_scan(&mut points);
        for (p, q) in before.iter().zip(&points) {
            let (p, q) = (Vector3::from(*p), Vector3::from(*q));
            assert!((p.norm() - q.norm()).abs() < 1e-12 * p.norm());
            assert!((p.angle(&q) - VERTICAL_ANGLE_OFFSET).abs() < 1e-9);
            assert!((p.y.atan2(p.x) - q.y.atan2(q.x)).abs() < 1e-12);
            let elevation = |v: &Vector3<f64>| (v.z / v.xy().norm()).atan();
            assert!((elevation(&q) - elevation(&p) - VERTICAL_ANGLE_OFFSET).abs() < 1e-12);
        }
    }

    #[test]
    fn correction_on_the_z_axis_scales_by_cos_like_eigen() {
        let mut points = vec![[0.0, 0.0, 2.0]];
        correct_scan(&mut points);
        assert_eq!(points[0], [0.0, 0.0, 2.0 * VERTICAL_ANGLE_OFFSET.cos()]);
    }

    #[test]
    fn calib_tr_is_rounded_to_f32() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("calib.txt");
        std::fs::write(
            &path,
            "P0: 1 2 3 4 5 6 7 8 9 10 11 12\nTr: 0.1 0 0 0 0 1 0 0 0 0 1 -0.2921968648686\n",
        )
        .unwrap();
        let tr = read_calib_tr(&path).unwrap();
        assert_eq!(tr[(0, 0)], 0.1f32 as f64);
        assert_eq!(tr[(2, 3)], (-0.2921968648686f64) as f32 as f64);
        assert_eq!(tr[(3, 3)], 1.0);
        std::fs::write(&path, "Tr: 1 0 0\n").unwrap();
        assert!(read_calib_tr(&path)
            .unwrap_err()
            .to_string()
            .contains("calib.txt:1"));
    }

    #[test]
    fn ground_truth_identity_stays_identity() {
        let tr = Isometry3::new(Vector3::new(0.1, -0.2, 0.3), Vector3::new(0.5, 0.1, -1.2))
            .to_homogeneous();
        let cam = [Matrix4::identity()];
        let lidar = lidar_ground_truth(&cam, &tr).unwrap();
        assert!((lidar[0] - Matrix4::identity()).amax() < 1e-15);
    }
}
