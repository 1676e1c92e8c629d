//! Step 4 (Sec. III-E): robust point-to-point ICP, Gauss-Newton on SE(3).
//!
//! The source points `S = T_{t-1} T_pred P^` (Eq. (9)) are associated with their nearest map
//! points within `tau = 3 sigma` (Eq. (10)); each iteration solves the Geman-McClure weighted
//! normal equations for a twist `dx` (Eq. (11), weight `k^2 / (k + |r|^2)^2` with
//! `k = kernel_scale * sigma`, as the reference computes it), moves the points by `Exp(dx)`
//! (Eq. (12)) and stops once `|dx| < gamma` or at the iteration cap. The result is
//! `T_t = dT_icp T_{t-1} T_pred`.
//!
//! Determinism: the source is split into chunks of [`CHUNK`] points; each chunk's partial
//! system is summed in point order and the partials are added in chunk order, so the result is
//! bit-identical whichever [`Executor`] ran the chunks and on how many threads.

use crate::lie::se3_exp;
use crate::local_map::{MapView, PointCodec};
use crate::scalar::Real;
use crate::storage::{view, words_for};
use crate::{Point, Pose};
use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

/// Source points per chunk: the unit of parallel work and of the fixed reduction order (chunk
/// sums are added in chunk order whatever the thread count).
pub const CHUNK: usize = 64;
/// Scalars in one chunk's partial linear system: 21 (upper triangle of `J^T J`) + 6 (`J^T r`)
/// + correspondence count + sum of squared residuals.
pub const SYSTEM_LEN: usize = 29;
/// Scalars in one chunk: its points (`3 * CHUNK`), its partial system, its point count.
const CHUNK_LEN: usize = 3 * CHUNK + SYSTEM_LEN + 1;

/// One chunk of ICP work: up to [`CHUNK`] source points, moved in place from iteration to
/// iteration, and the partial normal equations they gave in the last iteration.
pub type Chunk<T> = [T; CHUNK_LEN];

/// Chunks for `points` source points.
pub const fn chunks_for(points: usize) -> usize {
    points.div_ceil(CHUNK)
}

/// `u64` words of ICP work space for `points` source points of scalar `T`.
pub const fn work_words<T>(points: usize) -> usize {
    words_for(chunks_for(points) * CHUNK_LEN * core::mem::size_of::<T>())
}

/// Runs ICP's per-chunk work, possibly in parallel. The core cuts the work into [`Chunk`]s and
/// hands them all over; an executor only decides who runs which chunk, so it cannot change
/// the chunking, drop points or reorder the reduction.
pub trait Executor {
    /// Calls `work` exactly once on every element of `chunks`, in any order, on any thread.
    fn for_each<C: Send>(&self, chunks: &mut [C], work: &(dyn Fn(&mut C) + Sync));
}

/// Runs chunks one after the other on the calling thread.
#[derive(Clone, Copy, Debug, Default)]
pub struct Sequential;

impl Executor for Sequential {
    fn for_each<C: Send>(&self, chunks: &mut [C], work: &(dyn Fn(&mut C) + Sync)) {
        for c in chunks {
            work(c);
        }
    }
}

/// ICP stopping rule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IcpParams<T> {
    /// `gamma`.
    pub convergence_criterion: T,
    /// Iteration cap.
    pub max_iterations: u32,
}

/// Outcome of one registration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Alignment<T: Real> {
    /// The registered pose `dT_icp * initial_guess`.
    pub pose: Pose<T>,
    /// Gauss-Newton iterations run.
    pub iterations: u32,
    /// Correspondences in the last iteration.
    pub correspondences: u32,
    /// Whether `|dx| < gamma` was reached (false when the cap stopped it).
    pub converged: bool,
    /// Whether a normal-equation system could not be solved (fewer than 3 usable
    /// correspondences); the correction of that iteration is zero.
    pub singular: bool,
    /// RMS point-to-point residual of the last iteration's correspondences (m).
    pub rms: T,
}

/// Index of `(r, c)`, `r <= c`, in the packed upper triangle of a 6x6 matrix.
const fn upper(r: usize, c: usize) -> usize {
    r * 6 - r * (r + 1) / 2 + c
}

/// Adds one weighted correspondence `w J^T J`, `w J^T r` for `J = [I, -[s]x]` to `acc`.
#[inline]
fn accumulate<T: Real>(acc: &mut [T; SYSTEM_LEN], s: &Vector3<T>, r: &Vector3<T>, w: T) {
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

/// Solves `H dx = -g` from summed chunk systems; `None` if `H` is not positive definite.
fn solve<T: Real>(sum: &[T; SYSTEM_LEN]) -> Option<Vector6<T>> {
    let mut h = Matrix6::zeros();
    for r in 0..6 {
        for c in r..6 {
            h[(r, c)] = sum[upper(r, c)];
            h[(c, r)] = sum[upper(r, c)];
        }
    }
    let g = Vector6::new(sum[21], sum[22], sum[23], sum[24], sum[25], sum[26]);
    let chol = h.cholesky()?;
    let dx = chol.solve(&(-g));
    dx.iter().all(|v| v.is_finite()).then_some(dx)
}

/// The chunk's points, its partial system and its point count.
#[inline]
fn parts<T: Real>(c: &mut Chunk<T>) -> Option<(&mut [T; 3 * CHUNK], &mut [T; SYSTEM_LEN], &mut T)> {
    let (points, rest) = c.split_first_chunk_mut::<{ 3 * CHUNK }>()?;
    let (system, rest) = rest.split_first_chunk_mut::<SYSTEM_LEN>()?;
    Some((points, system, rest.first_mut()?))
}

/// Copies `source` into the chunks of `work` (as many as fit); returns the chunks in use.
fn load<'w, T: Real>(source: &[[T; 3]], work: &'w mut [u64]) -> &'w mut [Chunk<T>] {
    let fit = (work.len() * 8) / (CHUNK_LEN * core::mem::size_of::<T>());
    let n = chunks_for(source.len()).min(fit);
    let Ok(chunks) = view::<Chunk<T>>(work, n) else {
        return &mut [];
    };
    for (c, pts) in chunks.iter_mut().zip(source.chunks(CHUNK)) {
        if let Some((points, _, count)) = parts(c) {
            for (dst, p) in points.chunks_exact_mut(3).zip(pts) {
                dst.copy_from_slice(p);
            }
            *count = T::of(pts.len() as f64);
        }
    }
    chunks
}

/// The points ICP moved, in source order (world frame, as the last iteration left them).
pub fn moved_points<T: Real>(work: &mut [u64], n: usize) -> impl Iterator<Item = Point<T>> + '_ {
    let chunks = view::<Chunk<T>>(work, chunks_for(n)).unwrap_or_default();
    chunks.iter_mut().flat_map(|c| {
        let (points, count) = match parts(c) {
            Some((p, _, count)) => (&p[..], count.wide() as usize),
            None => (&[][..], 0),
        };
        points
            .chunks_exact(3)
            .take(count)
            .map(|p| Point::new(p[0], p[1], p[2]))
    })
}

/// Registers `source` (sensor frame) to `map` starting from `initial_guess` (the reference's
/// `AlignPointsToMap`), moving a copy of the points in `work`, which needs
/// [`work_words`]`::<T>(source.len())` words (points beyond what fits are not used).
#[allow(clippy::too_many_arguments)]
pub fn align_points_to_map<T: Real, P: PointCodec<T>, E: Executor>(
    exec: &E,
    source: &[[T; 3]],
    work: &mut [u64],
    map: &MapView<'_, T, P>,
    initial_guess: &Pose<T>,
    max_distance: T,
    kernel: T,
    params: &IcpParams<T>,
) -> Alignment<T> {
    let mut out = Alignment {
        pose: *initial_guess,
        iterations: 0,
        correspondences: 0,
        converged: true,
        singular: false,
        rms: T::zero(),
    };
    if map.is_empty() {
        return out;
    }
    let chunks = load(source, work);
    let k2 = kernel * kernel;
    let mut step: (Matrix3<T>, Vector3<T>) = (
        initial_guess.rotation.to_rotation_matrix().into_inner(),
        initial_guess.translation.vector,
    );
    let mut t_icp = Pose::identity();
    out.converged = false;
    for _ in 0..params.max_iterations {
        let (rot, tr) = step;
        exec.for_each(chunks, &|c| {
            let Some((points, acc, count)) = parts(c) else {
                return;
            };
            *acc = [T::zero(); SYSTEM_LEN];
            let n = count.wide() as usize;
            for p in points.chunks_exact_mut(3).take(n) {
                let moved = rot * Vector3::new(p[0], p[1], p[2]) + tr;
                p.copy_from_slice(&[moved.x, moved.y, moved.z]);
                let s = Point::from(moved);
                if let Some((q, d2)) = map.closest_neighbor(&s, max_distance) {
                    let r = moved - q.coords;
                    let denom = kernel + d2;
                    accumulate(acc, &moved, &r, k2 / (denom * denom));
                }
            }
        });
        let mut sum = [T::zero(); SYSTEM_LEN];
        for c in chunks.iter_mut() {
            if let Some((_, sys, _)) = parts(c) {
                for (a, b) in sum.iter_mut().zip(sys.iter()) {
                    *a += *b;
                }
            }
        }
        out.iterations += 1;
        out.correspondences = sum[27].wide() as u32;
        out.rms = if sum[27] > T::zero() {
            (sum[28] / sum[27]).sqrt_l()
        } else {
            T::zero()
        };
        let dx = match solve(&sum) {
            Some(dx) => dx,
            None => {
                out.singular = true;
                out.converged = true;
                break;
            }
        };
        let estimation = se3_exp(&dx);
        t_icp = estimation * t_icp;
        step = (
            estimation.rotation.to_rotation_matrix().into_inner(),
            estimation.translation.vector,
        );
        if dx.norm() < params.convergence_criterion {
            out.converged = true;
            break;
        }
    }
    out.pose = t_icp * initial_guess;
    out
}

#[cfg(test)]
mod tests;
