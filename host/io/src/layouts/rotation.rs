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

/// How a float32 matrix product rounds each entry's sum: numpy's `@` on float32 arrays calls
/// the BLAS `sgemm` kernel OpenBLAS picks for the CPU, which accumulates `sum_k a_ik b_kj` in
/// order of `k` either with fused multiply-adds (the Haswell, Skylake-X and Zen kernels, and
/// ARM's) or rounding each product before adding it (the SSE kernels OpenBLAS falls back to on
/// CPUs it does not recognise).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum F32Products {
    /// `acc = fma(a_ik, b_kj, acc)`.
    Fused,
    /// `acc = acc + round(a_ik b_kj)`.
    Separate,
}

/// `inv(poses[0]) @ poses` on float32 poses (entries that are float32 values), as numpy
/// computes it: `np.linalg.inv` works in float64 and rounds its result to float32, then the
/// product is a float32 `sgemm` whose sums round as `products` says. `what` names the first
/// pose in the error.
pub fn rebase_f32(
    poses: &[Matrix4<f64>],
    products: F32Products,
    what: &str,
) -> Result<Vec<Matrix4<f64>>> {
    let Some(first) = poses.first() else {
        return Ok(Vec::new());
    };
    let inv = inverse(first, what)?.map(|v| v as f32);
    Ok(poses
        .iter()
        .map(|p| {
            let p = p.map(|v| v as f32);
            Matrix4::from_fn(|i, j| {
                let mut acc = inv[(i, 0)] * p[(0, j)];
                for k in 1..4 {
                    acc = match products {
                        F32Products::Fused => inv[(i, k)].mul_add(p[(k, j)], acc),
                        F32Products::Separate => acc + inv[(i, k)] * p[(k, j)],
                    };
                }
                f64::from(acc)
            })
        })
        .collect())
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

    /// `np.linalg.inv(first) @ np.stack([first, pose])` on float32 arrays, as numpy 2.4.6's
    /// OpenBLAS 0.3.31 computes it with its Haswell kernel (fused) and its Prescott kernel
    /// (`OPENBLAS_CORETYPE=Prescott`, separate): both poses, row-major.
    #[rustfmt::skip]
    const NUMPY_REBASED: [(F32Products, [[f64; 16]; 2]); 2] = [
        (F32Products::Fused, [
            [
                1.0, -1.1090826035342616e-08, 0.0, 0.0,
                -1.1090826035342616e-08, 1.0, 0.0, 0.0,
                0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
            ],
            [
                0.9800665974617004, -0.19866934418678284, 0.0, 3.0999755859375,
                0.19866932928562164, 0.9800665974617004, 0.0, 1.6999969482421875,
                0.0, 0.0, 1.0, 0.049999237060546875, 0.0, 0.0, 0.0, 1.0,
            ],
        ]),
        (F32Products::Separate, [
            [
                1.0, 0.0, 0.0, 0.0,
                0.0, 1.0, 0.0, -1.52587890625e-05,
                0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
            ],
            [
                0.9800665378570557, -0.19866934418678284, 0.0, 3.0999755859375,
                0.19866934418678284, 0.9800665378570557, 0.0, 1.6999969482421875,
                0.0, 0.0, 1.0, 0.049999237060546875, 0.0, 0.0, 0.0, 1.0,
            ],
        ]),
    ];

    #[test]
    fn float32_rebase_is_numpys_to_the_bit_for_either_kernel() {
        // 1.4 km from the origin, turned 0.6 rad; then 3.1 m on and 0.2 rad more.
        #[rustfmt::skip]
        let first = Matrix4::from_row_slice(&[
            0.8253356218338013, -0.5646424889564514, 0.0, 1234.5,
            0.5646424889564514, 0.8253356218338013, 0.0, 678.25,
            0.0, 0.0, 1.0, 35.0, 0.0, 0.0, 0.0, 1.0,
        ]);
        #[rustfmt::skip]
        let pose = Matrix4::from_row_slice(&[
            0.6967067122459412, -0.7173560857772827, 0.0, 1236.0986328125,
            0.7173560857772827, 0.6967067122459412, 0.0, 681.4034423828125,
            0.0, 0.0, 1.0, 35.04999923706055, 0.0, 0.0, 0.0, 1.0,
        ]);
        for (products, numpy) in NUMPY_REBASED {
            let ours = rebase_f32(&[first, pose], products, "first").unwrap();
            for (m, theirs) in ours.iter().zip(numpy) {
                let differing = m
                    .transpose()
                    .iter()
                    .zip(theirs)
                    .filter(|(a, b)| a.to_bits() != b.to_bits())
                    .count();
                assert_eq!(differing, 0, "{products:?}: {m}");
            }
        }
        // Re-based in float64 and rounded once, the same pose is neither kernel's.
        let f64_rebased = to_f32(&(inverse(&first, "first").unwrap() * pose));
        for (_, numpy) in NUMPY_REBASED {
            assert_ne!(f64_rebased.transpose().as_slice(), numpy[1]);
        }
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
