//! Step 4 (Sec. III-E): robust point-to-point ICP, Gauss-Newton on SE(3).
//!
//! The source points `S = T_{t-1} T_pred P^` (Eq. (9)) are associated with their nearest map
//! points within `tau = 3 sigma` (Eq. (10)); each iteration solves the Geman-McClure weighted
//! normal equations for a twist `dx` (Eq. (11), weight `k^2 / (k + |r|^2)^2` with
//! `k = kernel_scale * sigma`, as the reference computes it), moves the points by `Exp(dx)`
//! (Eq. (12)) and stops once `|dx| < gamma` or at the iteration cap (with plane terms, optionally
//! also once the iterate goes round a loop, see `cycle`). The result is
//! `T_t = dT_icp T_{t-1} T_pred`.
//!
//! Determinism: the source is split into chunks of [`CHUNK`] points; each chunk's partial
//! system is summed in point order and the partials are added in chunk order, so the result is
//! bit-identical whichever [`Executor`] ran the chunks and on how many threads.

pub use chunk::{
    chunk_len, chunks_for, moved_points, work_words, Chunk, PlaneChunk, CHUNK, CHUNK_LEN,
    PLANE_CHUNK_LEN,
};
use chunk::{load, Parts, WorkChunk, KEPT};
use cycle::Recent;
pub use cycle::LEN as CYCLE_LEN;
use planes::{accumulate_plane, Cached, CACHED};
pub use planes::{MIN_POINTS, PLANARITY, PLANE_KERNEL_SCALE};
pub use prior::MotionPrior;
pub use system::SYSTEM_LEN;
use system::{accumulate, upper};

use crate::geometry::{Point, Pose};
use crate::lie::se3_exp;
use crate::local_map::{Nearest, Voxels};
use crate::scalar::{sqrt_lt, Real};
use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

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

/// ICP's stopping rule and what robust mode adds to its terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IcpParams<T: Real> {
    /// `gamma`.
    pub convergence_criterion: T,
    /// Iteration cap.
    pub max_iterations: u32,
    /// Work units (see `local_map::Nearest::work`) the whole registration may spend;
    /// `None`: no limit. ICP stops with its last complete iterate before exceeding it.
    pub budget: Option<u64>,
    /// Point-to-plane terms where the map is planar (robust mode, see `planes`); `false`:
    /// point-to-point everywhere, as the reference.
    pub planes: bool,
    /// Soft terms for what the correspondences leave free (robust mode, see `prior`);
    /// `None`: none, as the reference.
    pub prior: Option<MotionPrior<T>>,
    /// Also stop when the iterate comes back within `gamma` of one of the last
    /// [`CYCLE_LEN`] iterates (see `cycle`); `false`: `gamma` and the cap only, as the
    /// reference.
    pub stop_on_cycle: bool,
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
    /// Of those, the point-to-plane ones (0 without plane terms).
    pub plane_correspondences: u32,
    /// Whether `|dx| < gamma` was reached, or the iterate came back to an earlier one with
    /// [`IcpParams::stop_on_cycle`] (false when the cap stopped it).
    pub converged: bool,
    /// Whether a normal-equation system could not be solved (fewer than 3 usable
    /// correspondences); the correction of that iteration is zero.
    pub singular: bool,
    /// RMS residual of the last iteration's correspondences (m): point-to-point, or along the
    /// normal for point-to-plane terms.
    pub rms: T,
    /// Work spent, in units (see [`IcpParams::budget`]).
    pub work: u64,
    /// Whether the budget stopped ICP (an iteration that could not finish within it was
    /// abandoned; the pose is the iterate before it).
    pub budget_spent: bool,
}

impl<T: Real> Alignment<T> {
    /// No registration: `pose` as it was given, no iteration run.
    pub fn at(pose: Pose<T>) -> Self {
        Alignment {
            pose,
            iterations: 0,
            correspondences: 0,
            plane_correspondences: 0,
            converged: true,
            singular: false,
            rms: T::zero(),
            work: 0,
            budget_spent: false,
        }
    }
}

/// The system ICP solves from the summed chunk systems: the point-to-point one as it is when
/// there are no planar terms (the reference), else `(1 - a) point + a plane`, `a` the share of
/// planar correspondences (GenZ-ICP's weight, see `planes`).
fn combine<T: Real>(point: &[T; SYSTEM_LEN], plane: &[T; SYSTEM_LEN]) -> [T; SYSTEM_LEN] {
    let planar = plane[27];
    if planar <= T::zero() {
        return *point;
    }
    let mut out = [T::zero(); SYSTEM_LEN];
    let a = planar / (planar + point[27]);
    for (o, (p, q)) in out.iter_mut().zip(point.iter().zip(plane)).take(27) {
        *o = (T::one() - a) * *p + a * *q;
    }
    out[27] = point[27] + planar;
    out[28] = point[28] + plane[28];
    out
}

/// Solves `H dx = -g` from a combined system; `None` if `H` is not positive definite.
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

/// One round of a chunk's work in an iteration: moves its points by `(rot, tr)` and sums their
/// weighted correspondences into the chunk's system, from where the last round stopped, within
/// `share` work units. A point whose search would pass the share is left for the next round
/// (it was moved; its kept answer is dropped, so it searches from scratch then).
#[inline]
#[allow(clippy::too_many_arguments)]
fn correspond<T: Real, M: Voxels<T>>(
    c: Parts<'_, T>,
    map: &M,
    rot: &Matrix3<T>,
    tr: &Vector3<T>,
    max_distance: T,
    kernel: T,
    slack: T,
    share: u64,
) {
    let k2 = kernel * kernel;
    let (acc, mut planes) = (c.system, c.planes);
    let n = c.count.wide() as usize;
    let start = c.progress[1].wide() as usize;
    let pending = c.progress[2] > T::zero();
    if start >= n {
        c.progress[0] = T::zero();
        return;
    }
    if start == 0 && !pending {
        *acc = [T::zero(); SYSTEM_LEN];
        if let Some(pl) = planes.as_mut() {
            *pl.system = [T::zero(); SYSTEM_LEN];
        }
    }
    let mut used = 0u64;
    let points = c
        .points
        .chunks_exact_mut(3)
        .zip(c.kept.chunks_exact_mut(KEPT));
    for (k, (p, kept)) in points.enumerate().take(n).skip(start) {
        let at = Vector3::new(p[0], p[1], p[2]);
        let (before, moved) = if k == start && pending {
            (at, at)
        } else {
            (at, rot * at + tr)
        };
        p.copy_from_slice(&[moved.x, moved.y, moved.z]);
        let cap = u32::try_from(share - used).unwrap_or(u32::MAX);
        match closest_from(kept, map, &before, &moved, max_distance, slack, cap) {
            Ok((found, work)) => {
                used += u64::from(work);
                let Some((q, d2)) = found else { continue };
                let r = moved - q.coords;
                let plane = planes.as_mut().and_then(|pl| {
                    let cached = pl.cached.get_mut(k * CACHED..(k + 1) * CACHED)?;
                    let n = Cached::normal(cached, map, &Point::from(moved))?;
                    Some((&mut *pl.system, n))
                });
                match plane {
                    Some((sys, n)) => {
                        let rn = n.dot(&r);
                        let denom = kernel + rn * rn;
                        accumulate_plane(sys, &moved, &n, rn, k2 / (denom * denom));
                    }
                    None => {
                        let denom = kernel + d2;
                        accumulate(acc, &moved, &r, k2 / (denom * denom));
                    }
                }
            }
            Err(spent) => {
                used += u64::from(spent);
                kept[3] = -T::one();
                *c.progress = [T::of(used as f64), T::of(k as f64), T::one()];
                return;
            }
        }
    }
    *c.progress = [T::of(used as f64), T::of(n as f64), T::zero()];
}

/// A correspondence query's answer: the map point and its squared distance, if any within the
/// threshold.
type Answer<T> = Option<(Point<T>, T)>;

/// The closest map point to `moved` within `max_distance`, exactly as
/// [`Voxels::closest_neighbor`] gives it, for a point that moved from `before` and whose last
/// search left `kept` (updated here); and the work it took (1 when it came from `kept`). If that
/// would take more than `cap` work units: `Err` with the units spent before giving up.
#[inline]
fn closest_from<T: Real, M: Voxels<T>>(
    kept: &mut [T],
    map: &M,
    before: &Vector3<T>,
    moved: &Vector3<T>,
    max_distance: T,
    slack: T,
    cap: u32,
) -> Result<(Answer<T>, u32), u32> {
    if cap < 1 {
        return Err(0);
    }
    let s = Point::from(*moved);
    let step = (moved - before).norm() + slack;
    kept[3] -= step;
    kept[4] -= step;
    match rerank(kept, &s, map.voxel_size(), max_distance, slack) {
        Some(found) => Ok((found, 1)),
        None => {
            let nearest = map.nearest(&s, max_distance, cap)?;
            keep(kept, &nearest, slack);
            Ok((nearest.within(max_distance), nearest.work))
        }
    }
}

/// Rounding allowance for the distances a kept answer relies on: 16 ulps of `reach`, a bound on
/// the coordinates of the points and their neighbours.
fn slack_for<T: Real>(reach: T) -> T {
    T::of(16.0) * T::EPS * reach
}

/// Stores what a search found for a point (see [`KEPT`]).
#[inline]
fn keep<T: Real>(kept: &mut [T], nearest: &Nearest<T>, slack: T) {
    let none = T::one() / T::zero();
    let q = nearest.best.map_or([none; 3], |(q, _)| [q.x, q.y, q.z]);
    kept[..3].copy_from_slice(&q);
    kept[3] = nearest.others - slack;
    kept[4] = nearest.face - slack;
}

/// The answer a new search from `s` would give, from what the point's last search kept, if that
/// is certain: `Some(answer)`; `None` if the point must search again. `slack` covers rounding.
#[inline]
fn rerank<T: Real>(
    kept: &[T],
    s: &Point<T>,
    v: T,
    max_distance: T,
    slack: T,
) -> Option<Option<(Point<T>, T)>> {
    // Every other point of the searched 27 voxels is at least `others` away now. Past a face of
    // the searched voxel, the 27 voxels around `s` also hold points the search did not see:
    // they lie outside its 3x3x3 block, at least `v + face` away. A kept point that left the 27
    // voxels around `s` is at least `v` away (less rounding) and cannot pass that bound.
    let (others, face) = (kept[3], kept[4]);
    (others > T::zero()).then_some(())?;
    let bound = if face > T::zero() {
        others
    } else {
        others.min(face + v - slack)
    };
    if !kept[0].is_finite() {
        // No point was found; none can come within the threshold.
        return (bound > max_distance).then_some(None);
    }
    let q = Point::new(kept[0], kept[1], kept[2]);
    let d2 = (q - s).norm_squared();
    // Strictly closer than every other point: no rank decides, the search picks it too.
    // (`sqrt_lt` squares its bound: a bound that went negative must fail first.)
    let beats_all = bound > T::zero() && sqrt_lt(d2, bound);
    beats_all.then_some(Some((q, d2)).filter(|_| sqrt_lt(d2, max_distance)))
}

/// Runs one iteration's correspondence search over every chunk, in rounds: each round shares the
/// budget left equally among the chunks not yet done (a fixed rule, so the iteration ends the
/// same way whichever thread runs which chunk), until all are done (`true`) or a round makes no
/// progress (`false`). Without a budget one round does it all.
#[allow(clippy::too_many_arguments)]
fn run_iteration<T: Real, M: Voxels<T>, E: Executor, C: WorkChunk<T>>(
    exec: &E,
    chunks: &mut [C],
    map: &M,
    (rot, tr): &(Matrix3<T>, Vector3<T>),
    max_distance: T,
    kernel: T,
    slack: T,
    params: &IcpParams<T>,
    out: &mut Alignment<T>,
) -> bool {
    for c in chunks.iter_mut() {
        if let Some(c) = c.parts() {
            *c.progress = [T::zero(); 3];
        }
    }
    loop {
        let open = chunks
            .iter_mut()
            .filter_map(C::parts)
            .filter(|c| c.progress[1] < *c.count)
            .count() as u64;
        if open == 0 {
            return true;
        }
        let left = params
            .budget
            .map_or(u64::MAX, |b| b.saturating_sub(out.work));
        let share = left / open;
        if share == 0 {
            return false;
        }
        exec.for_each(chunks, &|c| {
            if let Some(c) = c.parts() {
                correspond(c, map, rot, tr, max_distance, kernel, slack, share);
            }
        });
        let spent: u64 = chunks
            .iter_mut()
            .filter_map(C::parts)
            .map(|c| c.progress[0].wide() as u64)
            .sum();
        out.work += spent;
        // Nothing spent, nothing answered (each answer costs a unit): the round is stuck.
        if spent == 0 {
            return false;
        }
    }
}

/// The chunks' partial systems summed in chunk order, combined (see [`combine`]), and the
/// number of point-to-plane correspondences among them.
fn summed<T: Real, C: WorkChunk<T>>(chunks: &mut [C]) -> ([T; SYSTEM_LEN], T) {
    let mut point = [T::zero(); SYSTEM_LEN];
    let mut plane = [T::zero(); SYSTEM_LEN];
    for c in chunks.iter_mut() {
        if let Some(c) = c.parts() {
            for (a, b) in point.iter_mut().zip(c.system.iter()) {
                *a += *b;
            }
            if let Some(pl) = c.planes {
                for (a, b) in plane.iter_mut().zip(pl.system.iter()) {
                    *a += *b;
                }
            }
        }
    }
    (combine(&point, &plane), plane[27])
}

/// Registers `source` (sensor frame) to `map` starting from `initial_guess` (the reference's
/// `AlignPointsToMap`), moving a copy of the points in `work`, which needs
/// [`work_words`]`::<T>(source.len(), params.planes)` words (points beyond what fits are not
/// used).
#[allow(clippy::too_many_arguments)]
pub fn align_points_to_map<T: Real, M: Voxels<T>, E: Executor>(
    exec: &E,
    source: &[[T; 3]],
    work: &mut [u64],
    map: &M,
    initial_guess: &Pose<T>,
    max_distance: T,
    kernel: T,
    params: &IcpParams<T>,
) -> Alignment<T> {
    let mut out = Alignment::at(*initial_guess);
    if map.is_empty() {
        return out;
    }
    let icp = Icp {
        exec,
        map,
        initial_guess,
        max_distance,
        kernel,
        params,
    };
    if params.planes {
        icp.run(load::<T, PlaneChunk<T>>(source, work), source, &mut out);
    } else {
        icp.run(load::<T, Chunk<T>>(source, work), source, &mut out);
    }
    out
}

/// One registration's inputs.
struct Icp<'a, T: Real, M: Voxels<T>, E> {
    exec: &'a E,
    map: &'a M,
    initial_guess: &'a Pose<T>,
    max_distance: T,
    kernel: T,
    params: &'a IcpParams<T>,
}

impl<T: Real, M: Voxels<T>, E: Executor> Icp<'_, T, M, E> {
    /// Gauss-Newton over the loaded `chunks` of `source`, into `out`.
    fn run<C: WorkChunk<T>>(&self, chunks: &mut [C], source: &[[T; 3]], out: &mut Alignment<T>) {
        let (initial_guess, params) = (self.initial_guess, self.params);
        // Points and their neighbours stay within |t| + max |p| (plus a few voxels) of the
        // origin: the rounding allowance is taken on twice that.
        let extent = source
            .iter()
            .map(|p| Vector3::new(p[0], p[1], p[2]).norm_squared())
            .fold(T::zero(), |a, b| a.max(b))
            .sqrt_l();
        let reach = T::of(2.0) * (extent + initial_guess.translation.vector.norm())
            + T::of(4.0) * self.map.voxel_size();
        let slack = slack_for(reach);
        let mut step: (Matrix3<T>, Vector3<T>) = (
            initial_guess.rotation.to_rotation_matrix().into_inner(),
            initial_guess.translation.vector,
        );
        let mut t_icp = Pose::identity();
        let mut recent = Recent::new(t_icp);
        out.converged = false;
        for _ in 0..params.max_iterations {
            let (d, k) = (self.max_distance, self.kernel);
            if !run_iteration(self.exec, chunks, self.map, &step, d, k, slack, params, out) {
                // An iteration that cannot finish within the budget is abandoned: the pose
                // stays the last complete iterate.
                out.budget_spent = true;
                break;
            }
            let (mut sum, planar) = summed(chunks);
            if let Some(prior) = &params.prior {
                prior.add(&mut sum, &(t_icp * initial_guess).translation.vector);
            }
            out.iterations += 1;
            out.correspondences = sum[27].wide() as u32;
            out.plane_correspondences = planar.wide() as u32;
            out.rms = if sum[27] > T::zero() {
                (sum[28] / sum[27]).sqrt_l()
            } else {
                T::zero()
            };
            let Some(dx) = solve(&sum) else {
                out.singular = true;
                out.converged = true;
                break;
            };
            let estimation = se3_exp(&dx);
            t_icp = estimation * t_icp;
            step = (
                estimation.rotation.to_rotation_matrix().into_inner(),
                estimation.translation.vector,
            );
            let gamma = params.convergence_criterion;
            if dx.norm() < gamma || (params.stop_on_cycle && recent.returns_to(&t_icp, gamma)) {
                out.converged = true;
                break;
            }
            recent.push(t_icp);
        }
        out.pose = t_icp * initial_guess;
    }
}

mod chunk;
mod cycle;
mod planes;
mod prior;
mod system;
#[cfg(test)]
mod tests;
