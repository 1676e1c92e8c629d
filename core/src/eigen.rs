//! Symmetric 3x3 eigen-decomposition by cyclic Jacobi rotations, for the voxel shapes robust
//! mode's planes read and the one-plane test of a registration cloud (`one_plane`): fixed
//! sweep order, only `+ - * /` and the correctly rounded square root, so every target
//! gives the same bits.

use crate::scalar::Real;
use nalgebra::{Matrix3, Vector3};

/// Eigenvalues and eigenvectors (columns) of the symmetric `a` by cyclic Jacobi rotations.
pub(crate) fn jacobi_eigen<T: Real>(mut a: Matrix3<T>) -> (Vector3<T>, Matrix3<T>) {
    let mut v = Matrix3::identity();
    let scale = a.iter().fold(T::zero(), |m, x| m.max(x.abs()));
    let tiny = T::EPS * T::EPS * scale * scale;
    for _ in 0..32 {
        let mut off = T::zero();
        for p in 0..3 {
            for q in p + 1..3 {
                off += a[(p, q)] * a[(p, q)];
            }
        }
        if off <= tiny {
            break;
        }
        for p in 0..3 {
            for q in p + 1..3 {
                rotate(&mut a, &mut v, p, q);
            }
        }
    }
    (a.diagonal(), v)
}

/// One Jacobi rotation zeroing `a[(p, q)]`, accumulated into `v`.
fn rotate<T: Real>(a: &mut Matrix3<T>, v: &mut Matrix3<T>, p: usize, q: usize) {
    let apq = a[(p, q)];
    if apq == T::zero() {
        return;
    }
    let theta = (a[(q, q)] - a[(p, p)]) / (T::of(2.0) * apq);
    let root = (theta * theta + T::one()).sqrt_l();
    let t = if theta >= T::zero() {
        T::one() / (theta + root)
    } else {
        -T::one() / (-theta + root)
    };
    if !t.is_finite() {
        return;
    }
    let c = T::one() / (t * t + T::one()).sqrt_l();
    let s = t * c;
    for k in 0..3 {
        let (akp, akq) = (a[(k, p)], a[(k, q)]);
        a[(k, p)] = c * akp - s * akq;
        a[(k, q)] = s * akp + c * akq;
    }
    for k in 0..3 {
        let (apk, aqk) = (a[(p, k)], a[(q, k)]);
        a[(p, k)] = c * apk - s * aqk;
        a[(q, k)] = s * apk + c * aqk;
    }
    for k in 0..3 {
        let (vkp, vkq) = (v[(k, p)], v[(k, q)]);
        v[(k, p)] = c * vkp - s * vkq;
        v[(k, q)] = s * vkp + c * vkq;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobi_eigen_decomposes_symmetric_matrices() {
        let mut rng = crate::testutil::Rng(7);
        let mut worst = 0.0f64;
        // Miri interprets every index operation: a dozen matrices there, the full set natively.
        let matrices = if cfg!(miri) { 12 } else { 200 };
        for _ in 0..matrices {
            let b = Matrix3::from_fn(|_, _| rng.next() - 0.5);
            let a = b * b.transpose();
            let (values, vectors) = jacobi_eigen(a);
            let back = vectors * Matrix3::from_diagonal(&values) * vectors.transpose();
            worst = worst.max((back - a).amax());
            worst = worst.max((vectors.transpose() * vectors - Matrix3::identity()).amax());
        }
        std::println!("jacobi: worst reconstruction error {worst:e} (tol 1e-12)");
        assert!(worst < 1e-12);
    }
}
