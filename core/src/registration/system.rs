//! The normal equations ICP sums, one partial system per chunk: the packed layout of `J^T J`
//! and `J^T r`, and how a point-to-point correspondence adds to it.

use crate::scalar::Real;
use nalgebra::Vector3;

/// Scalars in one partial linear system: 21 (upper triangle of `J^T J`) + 6 (`J^T r`) +
/// correspondence count + sum of squared residuals.
pub const SYSTEM_LEN: usize = 29;

/// Index of `(r, c)`, `r <= c`, in the packed upper triangle of a 6x6 matrix.
pub(super) const fn upper(r: usize, c: usize) -> usize {
    r * 6 - r * (r + 1) / 2 + c
}

/// Adds one weighted correspondence `w J^T J`, `w J^T r` for `J = [I, -[s]x]` to `acc`.
#[inline]
pub(super) fn accumulate<T: Real>(acc: &mut [T; SYSTEM_LEN], s: &Vector3<T>, r: &Vector3<T>, w: T) {
    let (x, y, z) = (s.x, s.y, s.z);
    // Translation block: w I.
    acc[upper(0, 0)] += w;
    acc[upper(1, 1)] += w;
    acc[upper(2, 2)] += w;
    // Cross block: -w [s]x.
    acc[upper(0, 4)] += w * z;
    acc[upper(0, 5)] -= w * y;
    acc[upper(1, 3)] -= w * z;
    acc[upper(1, 5)] += w * x;
    acc[upper(2, 3)] += w * y;
    acc[upper(2, 4)] -= w * x;
    // Rotation block: w [s]x^T [s]x = w (|s|^2 I - s s^T).
    acc[upper(3, 3)] += w * (y * y + z * z);
    acc[upper(3, 4)] -= w * x * y;
    acc[upper(3, 5)] -= w * x * z;
    acc[upper(4, 4)] += w * (x * x + z * z);
    acc[upper(4, 5)] -= w * y * z;
    acc[upper(5, 5)] += w * (x * x + y * y);
    // J^T r = [r; s x r].
    let c = s.cross(r);
    acc[21] += w * r.x;
    acc[22] += w * r.y;
    acc[23] += w * r.z;
    acc[24] += w * c.x;
    acc[25] += w * c.y;
    acc[26] += w * c.z;
    acc[27] += T::one();
    acc[28] += r.norm_squared();
}
