//! The pose arithmetic the loaders use, written out so that our ground truth is theirs: a
//! quaternion's matrix as `pyquaternion` builds it, Euler angles as the loaders compose them,
//! rounding to float32 where the loader stores float32, and a general 4x4 inverse (the loaders
//! use `np.linalg.inv`, not a rigid inverse).

use anyhow::{bail, Result};
use nalgebra::{Matrix3, Matrix4};

/// The rotation matrix of the quaternion `w, x, y, z` as `pyquaternion.Quaternion` gives it:
/// normalised unless its squared norm is within 1e-14 of 1, then `(Q Q̄^T)[1:, 1:]`.
pub fn quaternion_matrix(w: f64, x: f64, y: f64, z: f64) -> Matrix3<f64> {
    let mut q = [w, x, y, z];
    let ss = q.iter().map(|v| v * v).fold(0.0, |a, b| a + b);
    if (1.0 - ss).abs() >= 1e-14 && ss > 0.0 {
        let n = ss.sqrt();
        q = q.map(|v| v / n);
    }
    let [a, b, c, d] = q;
    let qm = [[a, -b, -c, -d], [b, a, -d, c], [c, d, a, -b], [d, -c, b, a]];
    let qb = [[a, -b, -c, -d], [b, a, d, -c], [c, -d, a, b], [d, c, -b, a]];
    Matrix3::from_fn(|i, j| {
        let (r, s) = (&qm[i + 1], &qb[j + 1]);
        r[0] * s[0] + r[1] * s[1] + r[2] * s[2] + r[3] * s[3]
    })
}

/// `Rz(yaw) Ry(pitch) Rx(roll)`: intrinsic Z-Y-X Euler angles.
pub fn zyx(yaw: f64, pitch: f64, roll: f64) -> Matrix3<f64> {
    let (sy, cy) = yaw.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let (sr, cr) = roll.sin_cos();
    let rz = Matrix3::new(cy, -sy, 0.0, sy, cy, 0.0, 0.0, 0.0, 1.0);
    let ry = Matrix3::new(cp, 0.0, sp, 0.0, 1.0, 0.0, -sp, 0.0, cp);
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, cr, -sr, 0.0, sr, cr);
    rz * (ry * rx)
}

/// The 4x4 homogeneous matrix of rotation `r` and translation `t`.
pub fn rigid(r: &Matrix3<f64>, t: [f64; 3]) -> Matrix4<f64> {
    let mut m = Matrix4::identity();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(r);
    for (i, v) in t.into_iter().enumerate() {
        m[(i, 3)] = v;
    }
    m
}

/// Every entry rounded to float32, as an `np.float32` array stores it.
pub fn to_f32(m: &Matrix4<f64>) -> Matrix4<f64> {
    m.map(|v| f64::from(v as f32))
}

/// The general inverse of `m` (what `np.linalg.inv` computes); `what` names it in the error.
pub fn inverse(m: &Matrix4<f64>, what: &str) -> Result<Matrix4<f64>> {
    match m.try_inverse() {
        Some(inv) if inv.iter().all(|v| v.is_finite()) => Ok(inv),
        _ => bail!("{what} is not invertible"),
    }
}

/// Each pose of `poses` relative to the first, `inv(poses[0]) @ poses`, as the loaders
/// re-base their ground truth.
pub fn rebase(poses: &[Matrix4<f64>], what: &str) -> Result<Vec<Matrix4<f64>>> {
    let Some(first) = poses.first() else {
        return Ok(Vec::new());
    };
    let inv = inverse(first, what)?;
    Ok(poses.iter().map(|p| inv * p).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, UnitQuaternion, Vector3};

    #[test]
    fn quaternion_matrix_is_the_rotation_even_unnormalised() {
        let q = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 0.7);
        let m = quaternion_matrix(2.0 * q.w, 2.0 * q.i, 2.0 * q.j, 2.0 * q.k);
        assert!((m - q.to_rotation_matrix().matrix()).amax() < 1e-15);
    }

    #[test]
    fn zyx_is_nalgebra_euler() {
        let m = zyx(0.3, -0.2, 0.1);
        let r = Rotation3::from_euler_angles(0.1, -0.2, 0.3);
        assert!((m - r.matrix()).amax() < 1e-15);
    }

    #[test]
    fn rebase_makes_the_first_pose_identity() {
        let a = rigid(&zyx(0.3, 0.0, 0.0), [1.0, 2.0, 3.0]);
        let b = rigid(&zyx(0.5, 0.1, 0.0), [4.0, 2.0, 3.0]);
        let r = rebase(&[a, b], "pose").unwrap();
        assert!((r[0] - Matrix4::identity()).amax() < 1e-15);
        assert!((a * r[1] - b).amax() < 1e-14);
        assert!(inverse(&Matrix4::zeros(), "zero").is_err());
    }
}
