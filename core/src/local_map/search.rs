//! Nearest-neighbour search over the 27 voxels around a query (Sec. III-C).
//!
//! Result-identical to the reference's `GetClosestNeighbor`: voxels are visited in its order,
//! points in insertion order, and a candidate replaces the best only if its *norm* is strictly
//! smaller, so equidistant points resolve the same way. Two exact shortcuts make it fast: a
//! voxel is skipped when the distance from the query to the voxel's box (shrunk by a rounding
//! margin) already rules out every point in it, either against the best so far or against the
//! correspondence threshold, which the reference applies after the search anyway.
//!
//! The search and the covariances read the map through [`Voxels`]: a local map ([`MapView`])
//! or a prior map's tiles read in place (`crate::localize`) answer the same way.
//!
//! [`Voxels::nearest`] also reports a lower bound on the distance of every other candidate
//! (visited points and skipped voxels alike) and the distance to the query's voxel faces. A
//! query that then moves by `m` still has the same answer while the kept point is closer than
//! every other bound less `m` (and, past a face, still among the 27 voxels): ICP moves its points
//! by small steps as it converges, so it can keep answers instead of searching again, and the
//! answer kept is the one a new search would give, bit for bit.

use super::codec::PointCodec;
use super::view::MapView;
use crate::scalar::{norm_lt, sqrt_lt, Real};
use crate::voxel::{point_to_voxel, VoxelKey, NEIGHBOUR_SHIFTS};

/// Each neighbour offset's position in the reference's visiting order, indexed by
/// `(dx + 1) * 9 + (dy + 1) * 3 + (dz + 1)`.
const REFERENCE_RANK: [u8; 27] = {
    let mut rank = [0u8; 27];
    let mut i = 0;
    while i < 27 {
        let s = NEIGHBOUR_SHIFTS[i];
        rank[((s[0] + 1) * 9 + (s[1] + 1) * 3 + (s[2] + 1)) as usize] = i as u8;
        i += 1;
    }
    rank
};
use crate::geometry::Point;

/// Whether `x` is NaN (the only value not ordered against itself).
#[inline]
fn is_nan<T: PartialOrd>(x: T) -> bool {
    x.partial_cmp(&x).is_none()
}

/// A search's answer and what bounds every other point: enough to tell, after the query moved
/// a little, whether a new search would give the same answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nearest<T: Real> {
    /// The closest map point among the 27 voxels (whatever its distance) with its squared
    /// distance; `None` if no point was visited.
    pub best: Option<(Point<T>, T)>,
    /// Every other point of the 27 voxels is at least this far from the query (a distance).
    pub others: T,
    /// Distance from the query to the nearest face of its voxel: moving less keeps the same 27
    /// voxels; moving more brings in voxels at least `v + face` away from where it was.
    pub face: T,
    /// Work done, in units: 1 for the query, 1 per voxel looked up, 1 per point compared. At most
    /// `1 + 27 (1 + N_max)`.
    pub work: u32,
}

impl<T: Real> Nearest<T> {
    /// The answer of [`Voxels::closest_neighbor`]: the closest point if it lies within
    /// `max_distance`.
    #[inline]
    pub fn within(&self, max_distance: T) -> Option<(Point<T>, T)> {
        self.best.filter(|(_, d2)| sqrt_lt(*d2, max_distance))
    }
}

/// Read access to voxelized points: what the correspondence search and the covariances need.
pub trait Voxels<T: Real>: Sync {
    /// Where one voxel's points are.
    type Slot: Copy;
    /// Voxel size `v`.
    fn voxel_size(&self) -> T;
    /// Whether no voxel holds a point.
    fn is_empty(&self) -> bool;
    /// The voxel `key`, if it holds points.
    fn find(&self, key: &VoxelKey) -> Option<Self::Slot>;
    /// Points in the voxel at `slot`.
    fn count(&self, slot: Self::Slot) -> u32;
    /// Calls `f` on each point of the voxel at `slot`, in stored order, until it returns
    /// `false`.
    fn for_each_in(&self, slot: Self::Slot, f: impl FnMut(Point<T>) -> bool);

    /// The closest map point to `query` among the 27 surrounding voxels if its distance is
    /// below `max_distance`, with its squared distance.
    #[inline]
    fn closest_neighbor(&self, query: &Point<T>, max_distance: T) -> Option<(Point<T>, T)> {
        self.nearest(query, max_distance, u32::MAX)
            .ok()
            .and_then(|n| n.within(max_distance))
    }

    /// The search behind [`Self::closest_neighbor`], reporting bounds on the other points too
    /// (points beyond `max_distance` may be left out, which `within` and `others` account for).
    /// If it would take more than `cap` work units (`Nearest::work`) it gives up before the
    /// unit that would pass `cap`: `Err` with the units spent.
    #[inline]
    fn nearest(&self, query: &Point<T>, max_distance: T, cap: u32) -> Result<Nearest<T>, u32> {
        let inf = T::max_value().unwrap_or(T::one() / T::zero());
        let mut out = Nearest {
            best: None,
            others: inf,
            face: inf,
            work: 1,
        };
        if cap < 1 {
            return Err(0);
        }
        if self.is_empty() {
            return Ok(out);
        }
        let v = self.voxel_size();
        let key = point_to_voxel(query, v);
        let margin = v * T::of(1e-3);
        // Squared distance from the query to the slab of neighbour offsets -1, 0, +1, per axis,
        // and to the nearest face of its own voxel.
        let mut slab = [[T::zero(); 3]; 3];
        for a in 0..3 {
            let lo = T::of(key[a] as f64) * v;
            let (below, above) = (query[a] - lo, lo + v - query[a]);
            out.face = out.face.min(below).min(above);
            let below = (below - margin).max(T::zero());
            let above = (above - margin).max(T::zero());
            slab[a] = [below * below, T::zero(), above * above];
        }
        let limit2 = max_distance * max_distance * (T::one() + T::of(8.0) * T::EPS);
        // Per axis, offsets nearest first (own voxel, near side, far side): finding a close point
        // early lets the bound skip more voxels. Ties go to the reference's visiting order (its
        // rank), so the order here changes nothing but the work.
        let order = |a: usize| -> [usize; 3] {
            if slab[a][0] <= slab[a][2] {
                [1, 0, 2]
            } else {
                [1, 2, 0]
            }
        };
        // The closest point so far with its rank, and a lower bound on the squared distance of
        // every other point.
        let mut best2 = inf;
        let mut best: Option<(Point<T>, u16)> = None;
        let mut other2 = inf;
        for ix in order(0) {
            let lx = slab[0][ix];
            if lx > best2 || lx >= limit2 {
                other2 = other2.min(lx);
                continue;
            }
            for iy in order(1) {
                let lxy = lx + slab[1][iy];
                if lxy > best2 || lxy >= limit2 {
                    other2 = other2.min(lxy);
                    continue;
                }
                for iz in order(2) {
                    let lb2 = lxy + slab[2][iz];
                    if lb2 > best2 || lb2 >= limit2 {
                        other2 = other2.min(lb2);
                        continue;
                    }
                    let nk = [
                        key[0].wrapping_add(ix as i32 - 1),
                        key[1].wrapping_add(iy as i32 - 1),
                        key[2].wrapping_add(iz as i32 - 1),
                    ];
                    if out.work >= cap {
                        return Err(out.work);
                    }
                    out.work += 1;
                    let Some(slot) = self.find(&nk) else {
                        continue;
                    };
                    let points = self.count(slot);
                    if points > cap - out.work {
                        return Err(out.work);
                    }
                    out.work += points;
                    let rank = u16::from(REFERENCE_RANK[ix * 9 + iy * 3 + iz]) << 8;
                    let mut i = 0;
                    self.for_each_in(slot, |p| {
                        let d2 = (p - query).norm_squared();
                        let r = rank | i;
                        i += 1;
                        let wins = norm_lt(d2, best2)
                            || best.is_some_and(|(_, br)| {
                                r < br && !norm_lt(best2, d2) && !is_nan(d2)
                            });
                        if wins {
                            other2 = other2.min(best2);
                            best2 = d2;
                            best = Some((p, r));
                        } else {
                            other2 = other2.min(d2);
                        }
                        true
                    });
                }
            }
        }
        out.best = best.map(|(p, _)| (p, best2));
        out.others = other2.sqrt_l();
        Ok(out)
    }

    /// Number of points and their covariance in the 27 voxels around the voxel `key` (GenZ-ICP's
    /// neighbourhood), visited in `NEIGHBOUR_SHIFTS` order; `None` without any point.
    fn neighbourhood_covariance(&self, key: &VoxelKey) -> Option<(usize, nalgebra::Matrix3<T>)> {
        let mut slots: [Option<Self::Slot>; 27] = [None; 27];
        let mut found = 0;
        for s in NEIGHBOUR_SHIFTS.iter() {
            let nk = [
                key[0].wrapping_add(s[0]),
                key[1].wrapping_add(s[1]),
                key[2].wrapping_add(s[2]),
            ];
            if let Some(slot) = self.find(&nk) {
                slots[found] = Some(slot);
                found += 1;
            }
        }
        self.covariance_of(slots[..found].iter().flatten().copied())
    }

    /// Number of points and their covariance in the voxel holding `p`, if it exists.
    fn voxel_covariance(&self, p: &Point<T>) -> Option<(usize, nalgebra::Matrix3<T>)> {
        let slot = self.find(&point_to_voxel(p, self.voxel_size()))?;
        self.covariance_of(core::iter::once(slot))
    }

    /// Number of points and their covariance (mean first, then the spread about it) over the
    /// voxels in `slots`, in that order; `None` without any point.
    fn covariance_of(
        &self,
        slots: impl Iterator<Item = Self::Slot> + Clone,
    ) -> Option<(usize, nalgebra::Matrix3<T>)> {
        let mut n = 0usize;
        let mut mean = nalgebra::Vector3::zeros();
        for slot in slots.clone() {
            self.for_each_in(slot, |q| {
                mean += q.coords;
                n += 1;
                true
            });
        }
        if n == 0 {
            return None;
        }
        mean /= T::of(n as f64);
        let mut cov = nalgebra::Matrix3::zeros();
        for slot in slots {
            self.for_each_in(slot, |q| {
                let d = q.coords - mean;
                cov += d * d.transpose();
                true
            });
        }
        Some((n, cov / T::of(n as f64)))
    }
}

impl<T: Real, P: PointCodec<T>> Voxels<T> for MapView<'_, T, P> {
    type Slot = usize;
    #[inline]
    fn voxel_size(&self) -> T {
        MapView::voxel_size(self)
    }
    #[inline]
    fn is_empty(&self) -> bool {
        MapView::is_empty(self)
    }
    #[inline]
    fn find(&self, key: &VoxelKey) -> Option<usize> {
        MapView::find(self, key)
    }
    #[inline]
    fn count(&self, slot: usize) -> u32 {
        u32::from(self.counts[slot])
    }
    #[inline]
    fn for_each_in(&self, slot: usize, f: impl FnMut(Point<T>) -> bool) {
        MapView::for_each_in(self, slot, f);
    }
}
