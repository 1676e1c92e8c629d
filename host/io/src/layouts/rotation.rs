//! The pose arithmetic the loaders use, written out so that our ground truth is theirs: a
//! quaternion's matrix as `pyquaternion` builds it, Euler angles as the loaders compose them,
//! rounding to float32 where the loader stores float32, and a general 4x4 inverse (the loaders
//! use `np.linalg.inv`, not a rigid inverse). Where float32 makes the last bits visible
//! (nuScenes), also numpy's matrix products summed as its BLAS kernel sums them and its
//! inverse in LAPACK's order of operations.

use anyhow::{bail, Result};
use nalgebra::{Matrix3, Matrix4};

/// The rotation matrix of the quaternion `w, x, y, z` as `pyquaternion.Quaternion` gives it:
/// normalised unless its squared norm is within 1e-14 of 1, then `(Q Q̄^T)[1:, 1:]`, whose
/// sums are rounded product by product.
pub fn quaternion_matrix(w: f64, x: f64, y: f64, z: f64) -> Matrix3<f64> {
    quaternion_matrix_summed(w, x, y, z, Products::Separate)
}

/// [`quaternion_matrix`] with `Q Q̄^T` (`np.dot`, a BLAS `dgemm`) summed as `products` says.
pub fn quaternion_matrix_summed(
    w: f64,
    x: f64,
    y: f64,
    z: f64,
    products: Products,
) -> Matrix3<f64> {
    let mut q = [w, x, y, z];
    let ss = q.iter().map(|v| v * v).fold(0.0, |a, b| a + b);
    if (1.0 - ss).abs() >= 1e-14 && ss > 0.0 {
        let n = ss.sqrt();
        q = q.map(|v| v / n);
    }
    let [a, b, c, d] = q;
    let qm = [[a, -b, -c, -d], [b, a, -d, c], [c, d, a, -b], [d, -c, b, a]];
    let qb = [[a, -b, -c, -d], [b, a, d, -c], [c, -d, a, b], [d, c, -b, a]];
    Matrix3::from_fn(|i, j| products.sum(|k| (qm[i + 1][k], qb[j + 1][k])))
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

/// How a matrix product numpy computes rounds each entry's sum: numpy's `@` and `np.dot` call
/// the BLAS `gemm` kernel OpenBLAS picks for the CPU, which accumulates `sum_k a_ik b_kj` in
/// order of `k` (float32 and float64 alike) either with fused multiply-adds (the Haswell,
/// Skylake-X and Zen kernels: x86-64 CPUs since 2013) or rounding each product before adding
/// it (the SSE kernels OpenBLAS falls back to on CPUs it does not recognise). Other BLAS
/// libraries and other CPUs' kernels are not covered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Products {
    /// `acc = fma(a_ik, b_kj, acc)`.
    Fused,
    /// `acc = acc + round(a_ik b_kj)`.
    Separate,
}

impl Products {
    /// `sum_k a_k b_k` over `k = 0..4` of the pairs `term(k)`, in float64.
    fn sum(self, term: impl Fn(usize) -> (f64, f64)) -> f64 {
        let (a, b) = term(0);
        (1..4).fold(a * b, |acc, k| {
            let (a, b) = term(k);
            match self {
                Products::Fused => a.mul_add(b, acc),
                Products::Separate => acc + a * b,
            }
        })
    }

    /// The same in float32.
    fn sum_f32(self, term: impl Fn(usize) -> (f32, f32)) -> f32 {
        let (a, b) = term(0);
        (1..4).fold(a * b, |acc, k| {
            let (a, b) = term(k);
            match self {
                Products::Fused => a.mul_add(b, acc),
                Products::Separate => acc + a * b,
            }
        })
    }
}

/// `a @ b` of float64 4x4 matrices as numpy computes it, summed as `products` says.
pub fn product(a: &Matrix4<f64>, b: &Matrix4<f64>, products: Products) -> Matrix4<f64> {
    Matrix4::from_fn(|i, j| products.sum(|k| (a[(i, k)], b[(k, j)])))
}

/// `inv(poses[0]) @ poses` on float32 poses (entries that are float32 values), as numpy
/// computes it: `np.linalg.inv` works in float64 ([`lapack_inverse`]) and rounds its result
/// to float32, then the product is a float32 `sgemm` whose sums round as `products` says.
/// `what` names the first pose in the error.
pub fn rebase_f32(
    poses: &[Matrix4<f64>],
    products: Products,
    what: &str,
) -> Result<Vec<Matrix4<f64>>> {
    let Some(first) = poses.first() else {
        return Ok(Vec::new());
    };
    let Some(inv) = lapack_inverse(first) else {
        bail!("{what} is not invertible");
    };
    let inv = inv.map(|v| v as f32);
    Ok(poses
        .iter()
        .map(|p| {
            let p = p.map(|v| v as f32);
            Matrix4::from_fn(|i, j| f64::from(products.sum_f32(|k| (inv[(i, k)], p[(k, j)]))))
        })
        .collect())
}

/// The inverse of `m` in float64 as OpenBLAS's `dgesv` computes it for `np.linalg.inv`, in
/// its operations' order: LU with partial pivoting, each column of U by dot products with
/// the rows of L before it, L's multipliers scaled by the pivot's reciprocal; then the
/// identity solved through L and U column by column, U's diagonal applied as reciprocals.
/// Rounded to float32, an inverse's near-zero entries keep the last bits of this order (any
/// other float64 inverse differs there). `None` for a zero pivot.
pub fn lapack_inverse(m: &Matrix4<f64>) -> Option<Matrix4<f64>> {
    let mut a = *m;
    let mut pivots = [0usize; 4];
    for j in 0..4 {
        for i in 1..j {
            let dot = (0..i).fold(0.0, |s, k| s + a[(i, k)] * a[(k, j)]);
            a[(i, j)] -= dot;
        }
        for i in j..4 {
            let dot = (0..j).fold(0.0, |s, k| s + a[(i, k)] * a[(k, j)]);
            a[(i, j)] -= dot;
        }
        // The first of the largest magnitudes.
        let p = (j..4).fold(j, |p, i| {
            if a[(i, j)].abs() > a[(p, j)].abs() {
                i
            } else {
                p
            }
        });
        pivots[j] = p;
        if p != j {
            a.swap_rows(j, p);
        }
        if a[(j, j)] == 0.0 || !a[(j, j)].is_finite() {
            return None;
        }
        let r = 1.0 / a[(j, j)];
        for i in j + 1..4 {
            a[(i, j)] *= r;
        }
    }
    let mut x = Matrix4::<f64>::identity();
    for (j, &p) in pivots.iter().enumerate() {
        if p != j {
            x.swap_rows(j, p);
        }
    }
    for c in 0..4 {
        for i in 0..4 {
            for k in i + 1..4 {
                x[(k, c)] -= x[(i, c)] * a[(k, i)];
            }
        }
        for i in (0..4).rev() {
            x[(i, c)] *= 1.0 / a[(i, i)];
            for k in 0..i {
                x[(k, c)] -= x[(i, c)] * a[(k, i)];
            }
        }
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
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
    const NUMPY_REBASED: [(Products, [[f64; 16]; 2]); 2] = [
        (Products::Fused, [
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
        (Products::Separate, [
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
    fn lapack_inverse_rounded_to_float32_is_numpys_to_the_bit() {
        // A LiDAR pose 1.4 km out, tilted, as float32; and `np.linalg.inv` of it (numpy 2.4.6).
        #[rustfmt::skip]
        let m = Matrix4::from_row_slice(&[
            0.8270606994628906, -0.5620087385177612, -0.010806506499648094, 1234.5,
            0.5602836608886719, 0.8257668614387512, -0.06474002450704575, 678.25,
            0.04530811309814453, 0.0474892184138298, 0.9978436231613159, 35.0,
            0.0, 0.0, 0.0, 1.0,
        ]);
        #[rustfmt::skip]
        let numpy: [f64; 16] = [
            0.8270606994628906, 0.5602836608886719, 0.04530811682343483, -1402.6046142578125,
            -0.5620087385177612, 0.825766921043396, 0.0474892221391201, 132.061279296875,
            -0.01080650556832552, -0.06474002450704575, 0.9978436827659607, 22.326025009155273,
            0.0, 0.0, 0.0, 1.0,
        ];
        let inv = lapack_inverse(&m).unwrap();
        assert!((inv * m - Matrix4::identity()).amax() < 1e-12);
        let ours = to_f32(&inv).transpose();
        let differing = ours
            .iter()
            .zip(numpy)
            .filter(|(a, b)| a.to_bits() != b.to_bits())
            .count();
        assert_eq!(differing, 0, "{ours}");
        assert!(lapack_inverse(&Matrix4::zeros()).is_none());
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
