//! Trajectory files: KITTI (`r11 r12 r13 tx r21 r22 r23 ty r31 r32 r33 tz` per line) and TUM
//! (`timestamp tx ty tz qx qy qz qw` per line).
//!
//! Ground truth comes in through these readers and estimates go out through the writers, so both
//! directions are exact for `f64`: values are written in the shortest form that parses back to
//! the same bits. Rotations read from text are only orthonormal to the printed precision (KITTI
//! ground truth has seven digits); they are projected onto SO(3) when an [`Isometry3`] is built.

use anyhow::{bail, Context, Result};
use nalgebra::{
    Isometry3, Matrix3, Matrix4, Quaternion, Rotation3, Translation3, UnitQuaternion, Vector3,
};
use std::fmt::Write as _;
use std::path::Path;

/// One KITTI line: the top 3x4 block of a homogeneous transform, row-major.
pub type Rows = [f64; 12];

/// A pose with its time, as in a TUM file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimedPose {
    /// Seconds (any offset).
    pub time: f64,
    /// Sensor pose in the world frame.
    pub pose: Isometry3<f64>,
}

/// How far (max abs entry) a rotation block read from text may be from its projection onto
/// SO(3) before it is rejected as not a rotation. Seven printed digits give about 1e-7.
const MAX_ROTATION_DEFECT: f64 = 1e-2;

/// The 4x4 homogeneous matrix of `rows`, exactly as written.
pub fn matrix_from_rows(rows: &Rows) -> Matrix4<f64> {
    let mut m = Matrix4::identity();
    for r in 0..3 {
        for c in 0..4 {
            m[(r, c)] = rows[4 * r + c];
        }
    }
    m
}

/// The top 3x4 block of `m`, row-major.
pub fn rows_from_matrix(m: &Matrix4<f64>) -> Rows {
    let mut rows = [0.0; 12];
    for r in 0..3 {
        for c in 0..4 {
            rows[4 * r + c] = m[(r, c)];
        }
    }
    rows
}

/// The rigid transform closest to `m`: the rotation block is projected onto SO(3) with
/// [`Rotation3::from_matrix`] (nearest rotation in the Frobenius sense), the translation is kept
/// as is. Fails when the block is not within `MAX_ROTATION_DEFECT` of a rotation (a
/// reflection, a scale, a non-finite entry).
pub fn isometry_from_matrix(m: &Matrix4<f64>) -> Result<Isometry3<f64>> {
    if m.iter().any(|v| !v.is_finite()) {
        bail!("pose has a non-finite entry");
    }
    let block: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    // A rotation's entries lie in [-1, 1]; anything far outside cannot pass the defect check,
    // and the projection's iteration need not converge on it (found by fuzzing: 1e300 entries
    // made `from_matrix` spin), so refuse it first and bound the iterations anyway.
    if block.amax() > 1.0 + MAX_ROTATION_DEFECT {
        bail!(
            "rotation block is not a rotation (an entry of magnitude {:.3e})",
            block.amax()
        );
    }
    let rotation = Rotation3::from_matrix_eps(&block, f64::EPSILON, 1000, Rotation3::identity());
    let defect = (rotation.matrix() - block).amax();
    if defect > MAX_ROTATION_DEFECT {
        bail!("rotation block is not a rotation (off by {defect:.3e})");
    }
    let translation = Translation3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]);
    Ok(Isometry3::from_parts(
        translation,
        crate::pose::quaternion_of(rotation.matrix()),
    ))
}

/// [`isometry_from_matrix`] of a KITTI line.
pub fn isometry_from_rows(rows: &Rows) -> Result<Isometry3<f64>> {
    isometry_from_matrix(&matrix_from_rows(rows))
}

/// The KITTI line of `pose`.
pub fn rows_from_isometry(pose: &Isometry3<f64>) -> Rows {
    rows_from_matrix(&pose.to_homogeneous())
}

/// Parses KITTI text; `name` is used in errors (`name:line: reason`). Blank lines and lines
/// starting with `#` are ignored.
pub fn parse_kitti_rows(text: &str, name: &str) -> Result<Vec<Rows>> {
    Ok(numbered_kitti_rows(text, name)?
        .into_iter()
        .map(|(_, rows)| rows)
        .collect())
}

/// Reads a KITTI pose file as written (no re-orthonormalisation).
pub fn read_kitti_matrices(path: &Path) -> Result<Vec<Matrix4<f64>>> {
    let rows = parse_kitti_rows(&read_text(path)?, &path.display().to_string())?;
    Ok(rows.iter().map(matrix_from_rows).collect())
}

/// Reads a KITTI pose file into rigid transforms (see [`isometry_from_matrix`]).
pub fn read_kitti(path: &Path) -> Result<Vec<Isometry3<f64>>> {
    let name = path.display().to_string();
    numbered_kitti_rows(&read_text(path)?, &name)?
        .iter()
        .map(|(number, rows)| isometry_from_rows(rows).with_context(|| format!("{name}:{number}")))
        .collect()
}

fn numbered_kitti_rows(text: &str, name: &str) -> Result<Vec<(usize, Rows)>> {
    data_lines(text, name)
        .map(|(number, values)| {
            let values = values?;
            let rows: Rows = values.as_slice().try_into().map_err(|_| {
                anyhow::anyhow!(
                    "{name}:{number}: expected 12 numbers, found {}",
                    values.len()
                )
            })?;
            Ok((number, rows))
        })
        .collect()
}

/// A pose from `X,Y,Z,ROLL,PITCH,YAW` (metres, degrees; `R = Rz(yaw) Ry(pitch) Rx(roll)`).
pub fn parse_xyz_rpy(text: &str) -> Result<Isometry3<f64>> {
    let v: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| anyhow::anyhow!("{text:?}: expected six numbers X,Y,Z,ROLL,PITCH,YAW"))?;
    if v.len() != 6 || v.iter().any(|x| !x.is_finite()) {
        bail!("{text:?}: expected six finite numbers X,Y,Z,ROLL,PITCH,YAW (m, degrees)");
    }
    let r = nalgebra::UnitQuaternion::from_euler_angles(
        v[3].to_radians(),
        v[4].to_radians(),
        v[5].to_radians(),
    );
    Ok(Isometry3::from_parts(
        nalgebra::Translation3::new(v[0], v[1], v[2]),
        r,
    ))
}

/// KITTI text of `poses`, one line each.
pub fn format_kitti(poses: &[Isometry3<f64>]) -> String {
    let rows: Vec<Rows> = poses.iter().map(rows_from_isometry).collect();
    format_kitti_rows(&rows)
}

/// KITTI text of `rows` as given, one line each: every number in the shortest scientific form
/// that parses back to the same `f64` (`{:e}`).
pub fn format_kitti_rows(rows: &[Rows]) -> String {
    let mut out = String::new();
    for r in rows {
        let line: Vec<String> = r.iter().map(|v| format!("{v:e}")).collect();
        let _ = writeln!(out, "{}", line.join(" "));
    }
    out
}

/// Writes `poses` as a KITTI file. Numbers are written in the shortest scientific form that
/// parses back to the same `f64`.
pub fn write_kitti(path: &Path, poses: &[Isometry3<f64>]) -> Result<()> {
    std::fs::write(path, format_kitti(poses)).with_context(|| format!("{}", path.display()))
}

/// Parses TUM text; `name` is used in errors. The quaternion is normalised.
pub fn parse_tum(text: &str, name: &str) -> Result<Vec<TimedPose>> {
    let mut out = Vec::new();
    for (number, values) in data_lines(text, name) {
        let values = values?;
        let [time, tx, ty, tz, qx, qy, qz, qw]: [f64; 8] =
            values.as_slice().try_into().map_err(|_| {
                anyhow::anyhow!(
                    "{name}:{number}: expected 8 numbers, found {}",
                    values.len()
                )
            })?;
        let q = Quaternion::new(qw, qx, qy, qz);
        let largest = q.coords.amax();
        if largest == 0.0 {
            bail!("{name}:{number}: quaternion has zero norm");
        }
        // A squared norm that overflows (or underflows) would normalise the quaternion to
        // zeros, a pose that is no rotation (cargo-fuzz found it): scale to the largest
        // component first, only then, so every other line keeps its bits.
        let q = if q.norm_squared().is_normal() {
            q
        } else {
            q / largest
        };
        let Some(rotation) = UnitQuaternion::try_new(q, 1e-6) else {
            bail!("{name}:{number}: quaternion has zero norm");
        };
        let pose = Isometry3::from_parts(Vector3::new(tx, ty, tz).into(), rotation);
        out.push(TimedPose { time, pose });
    }
    Ok(out)
}

/// Reads a TUM trajectory file.
pub fn read_tum(path: &Path) -> Result<Vec<TimedPose>> {
    parse_tum(&read_text(path)?, &path.display().to_string())
}

/// TUM text of `poses`, one line each.
pub fn format_tum(poses: &[TimedPose]) -> String {
    let mut out = String::new();
    for p in poses {
        let t = p.pose.translation.vector;
        let q = p.pose.rotation.coords; // i, j, k, w
        let _ = writeln!(
            out,
            "{} {:e} {:e} {:e} {:e} {:e} {:e} {:e}",
            p.time, t.x, t.y, t.z, q[0], q[1], q[2], q[3]
        );
    }
    out
}

/// Writes `poses` as a TUM file (shortest round-trip numbers).
pub fn write_tum(path: &Path, poses: &[TimedPose]) -> Result<()> {
    std::fs::write(path, format_tum(poses)).with_context(|| format!("{}", path.display()))
}

fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))
}

/// The numbers on each data line with its 1-based line number; a token that is not a finite
/// number is an error naming the line.
fn data_lines<'a>(
    text: &'a str,
    name: &'a str,
) -> impl Iterator<Item = (usize, Result<Vec<f64>>)> + 'a {
    text.lines()
        .enumerate()
        .map(|(i, line)| (i + 1, line.trim()))
        .filter(|(_, line)| !line.is_empty() && !line.starts_with('#'))
        .map(move |(number, line)| {
            let values = line
                .split_whitespace()
                .map(|token| match token.parse::<f64>() {
                    Ok(v) if v.is_finite() => Ok(v),
                    _ => Err(anyhow::anyhow!(
                        "{name}:{number}: {token:?} is not a finite number"
                    )),
                })
                .collect();
            (number, values)
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_poses() -> Vec<Isometry3<f64>> {
        (0..5)
            .map(|i| {
                let f = i as f64;
                Isometry3::new(
                    Vector3::new(1.0 + f * 0.1, -2.5 * f, 1e-9 * f),
                    Vector3::new(0.01 * f, -0.3 * f, 0.7 + f),
                )
            })
            .collect()
    }

    #[test]
    fn kitti_text_round_trips_every_bit() {
        let poses = sample_poses();
        let text = format_kitti(&poses);
        let rows = parse_kitti_rows(&text, "mem").unwrap();
        for (pose, row) in poses.iter().zip(&rows) {
            assert_eq!(*row, rows_from_isometry(pose));
        }
    }

    #[test]
    fn tum_text_round_trips_every_bit() {
        let poses: Vec<TimedPose> = sample_poses()
            .into_iter()
            .enumerate()
            .map(|(i, pose)| TimedPose {
                time: 1317384506.4 + i as f64 * 0.1,
                pose,
            })
            .collect();
        let back = parse_tum(&format_tum(&poses), "mem").unwrap();
        for (a, b) in poses.iter().zip(&back) {
            assert_eq!(a.time, b.time);
            assert_eq!(a.pose.translation, b.pose.translation);
            // Normalising an already unit quaternion may move the last bit.
            assert!(a.pose.rotation.angle_to(&b.pose.rotation) < 1e-15);
        }
    }

    #[test]
    fn a_quaternion_too_large_or_small_to_square_is_still_a_rotation() {
        // cargo-fuzz's input: qw = 3.8e211, whose square overflows.
        let big = parse_tum("1 1 1. 83e-10 38e-10 1. 83e-10 38e210", "mem").unwrap();
        let q = big[0].pose.rotation;
        println!(
            "huge qw: rotation {:?}, angle {:e} rad",
            q.coords,
            q.angle()
        );
        assert!((q.coords.norm() - 1.0).abs() < 1e-15 && q.angle() < 1e-200);
        // Components whose squares underflow: the rotation they point to, about y by 90 deg.
        let tiny = parse_tum("0 0 0 0 0 1e-170 0 1e-170", "mem").unwrap();
        let want =
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), core::f64::consts::FRAC_PI_2);
        let off = tiny[0].pose.rotation.angle_to(&want);
        println!("tiny components: {off:e} rad from 90 deg about y (tol 1e-15)");
        assert!(off < 1e-15);
    }

    #[test]
    fn seven_digit_rotation_is_projected_onto_so3() {
        // A KITTI ground-truth line: orthonormal only to the printed precision.
        let text = "0.9990498 -0.00164978 0.04355194 0.05154656 0.001760423 0.9999953 \
                    -0.002502237 -0.02424883 -0.0435476 0.002576529 0.999048 1.000725";
        let rows = parse_kitti_rows(text, "mem").unwrap()[0];
        let pose = isometry_from_rows(&rows).unwrap();
        let r = pose.rotation.to_rotation_matrix().into_inner();
        assert!((r.transpose() * r - Matrix3::identity()).amax() < 1e-14);
        assert!((r.determinant() - 1.0).abs() < 1e-14);
        // Close to what was written, translation untouched.
        let written = matrix_from_rows(&rows);
        assert!((r - written.fixed_view::<3, 3>(0, 0)).amax() < 1e-6);
        assert_eq!(
            pose.translation.vector,
            Vector3::new(0.05154656, -0.02424883, 1.000725)
        );
    }

    #[test]
    fn parse_errors_name_file_and_line() {
        let text = "1 0 0 0 0 1 0 0 0 0 1 0\n\n1 0 0 0 0 1 0 0 0 0 1\n";
        let e = parse_kitti_rows(text, "gt.txt").unwrap_err().to_string();
        assert!(e.starts_with("gt.txt:3:"), "{e}");
        let e = parse_kitti_rows("1 0 0 x 0 1 0 0 0 0 1 0", "gt.txt")
            .unwrap_err()
            .to_string();
        assert!(e.contains("gt.txt:1") && e.contains("\"x\""), "{e}");
        let e = parse_tum("# t x y z qx qy qz qw\n0 0 0 0 0 0 0 0\n", "traj.tum")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("traj.tum:2:"), "{e}");
    }

    #[test]
    fn reflections_and_nan_are_not_poses() {
        let mirror = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0];
        assert!(isometry_from_rows(&mirror).is_err());
        let mut nan = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        nan[3] = f64::NAN;
        assert!(isometry_from_rows(&nan).is_err());
        assert!(parse_kitti_rows("1 0 0 inf 0 1 0 0 0 0 1 0", "f").is_err());
    }

    #[test]
    fn a_pose_is_six_finite_numbers_in_metres_and_degrees() {
        let p = parse_xyz_rpy("1, -2.5, 0.25, 0, 0, 90").unwrap();
        assert_eq!(p.translation.vector.as_slice(), &[1.0, -2.5, 0.25]);
        let x = p.rotation * nalgebra::Vector3::x();
        assert!(
            (x - nalgebra::Vector3::y()).norm() < 1e-12,
            "yaw turns x to y"
        );
        let q = parse_xyz_rpy("0,0,0,90,0,0").unwrap().rotation * nalgebra::Vector3::y();
        assert!(
            (q - nalgebra::Vector3::z()).norm() < 1e-12,
            "roll turns y to z"
        );
        for bad in [
            "1,2,3,4,5",
            "1,2,3,4,5,6,7",
            "1,2,x,4,5,6",
            "1,2,3,4,5,inf",
            "",
        ] {
            assert!(parse_xyz_rpy(bad).is_err(), "{bad}");
        }
    }
}
