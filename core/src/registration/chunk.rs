//! ICP's work chunks (step 4's unit of parallel work): the two layouts, the reference's
//! [`Chunk`] and robust mode's [`PlaneChunk`], their parts, and the words they need.

use super::planes::{Cached, CACHED};
use super::system::SYSTEM_LEN;
use crate::geometry::Point;
use crate::scalar::Real;
use crate::storage::{view, words_for};
use bytemuck::Pod;

/// Source points per chunk: the unit of parallel work and of the fixed reduction order (chunk
/// sums are added in chunk order whatever the thread count).
pub const CHUNK: usize = 64;
/// Scalars per point kept from its last search: the answer's `x, y, z` (infinite: none), and the
/// search's `others` and `face` bounds less the distance the point moved since (and a rounding
/// allowance per step).
pub(super) const KEPT: usize = 5;
/// Scalars in one chunk: its points (`3 * CHUNK`), what each kept (`KEPT * CHUNK`), its partial
/// system, its point count and where it stands in the current iteration (see `Parts::progress`).
pub const CHUNK_LEN: usize = (3 + KEPT) * CHUNK + SYSTEM_LEN + 4;
/// Scalars in one chunk of robust mode: a [`Chunk`], then the partial system of its
/// point-to-plane terms and each point's cached plane (see `planes`).
pub const PLANE_CHUNK_LEN: usize = CHUNK_LEN + SYSTEM_LEN + CACHED * CHUNK;

/// One chunk of ICP work: up to [`CHUNK`] source points, moved in place from iteration to
/// iteration, the neighbour each found and how long that holds, and the partial normal
/// equations they gave in the last iteration.
pub type Chunk<T> = [T; CHUNK_LEN];

/// One chunk of robust mode's ICP work: a [`Chunk`] and its point-to-plane part.
pub type PlaneChunk<T> = [T; PLANE_CHUNK_LEN];

/// Scalars in one chunk of the layout `planes` picks.
pub const fn chunk_len(planes: bool) -> usize {
    if planes {
        PLANE_CHUNK_LEN
    } else {
        CHUNK_LEN
    }
}

/// Chunks for `points` source points.
pub const fn chunks_for(points: usize) -> usize {
    points.div_ceil(CHUNK)
}

/// `u64` words of ICP work space for `points` source points of scalar `T`, with room for
/// point-to-plane terms (robust mode) if `planes`.
pub const fn work_words<T>(points: usize, planes: bool) -> usize {
    words_for(chunks_for(points) * chunk_len(planes) * core::mem::size_of::<T>())
}

/// A chunk's parts.
pub(super) struct Parts<'c, T> {
    /// `x, y, z` per point.
    pub(super) points: &'c mut [T; 3 * CHUNK],
    /// Per point: what its last search found (see [`KEPT`]); infinite coordinates: no
    /// candidate, a negative room: search now.
    pub(super) kept: &'c mut [T; KEPT * CHUNK],
    pub(super) system: &'c mut [T; SYSTEM_LEN],
    pub(super) count: &'c mut T,
    /// In the current iteration: work units spent in the last round, points answered, and 1 if
    /// the next point was already moved when its share ran out (0 otherwise).
    pub(super) progress: &'c mut [T; 3],
    /// Robust mode's point-to-plane part; `None` in the reference's layout.
    pub(super) planes: Option<PlaneParts<'c, T>>,
}

/// A [`PlaneChunk`]'s own parts.
pub(super) struct PlaneParts<'c, T> {
    /// The point-to-plane terms' partial system.
    pub(super) system: &'c mut [T; SYSTEM_LEN],
    /// Per point: the plane last read for it (see `planes::Cached`).
    pub(super) cached: &'c mut [T; CACHED * CHUNK],
}

/// A chunk of ICP work in one of the two layouts ([`Chunk`], [`PlaneChunk`]).
pub(super) trait WorkChunk<T>: Pod + Send {
    fn parts(&mut self) -> Option<Parts<'_, T>>;
}

impl<T: Real> WorkChunk<T> for Chunk<T> {
    #[inline]
    fn parts(&mut self) -> Option<Parts<'_, T>> {
        let (points, rest) = self.split_first_chunk_mut::<{ 3 * CHUNK }>()?;
        let (kept, rest) = rest.split_first_chunk_mut::<{ KEPT * CHUNK }>()?;
        let (system, rest) = rest.split_first_chunk_mut::<SYSTEM_LEN>()?;
        let (count, rest) = rest.split_first_mut()?;
        Some(Parts {
            points,
            kept,
            system,
            count,
            progress: rest.first_chunk_mut::<3>()?,
            planes: None,
        })
    }
}

impl<T: Real> WorkChunk<T> for PlaneChunk<T> {
    #[inline]
    fn parts(&mut self) -> Option<Parts<'_, T>> {
        let (base, rest) = self.split_first_chunk_mut::<CHUNK_LEN>()?;
        let (system, rest) = rest.split_first_chunk_mut::<SYSTEM_LEN>()?;
        let cached = rest.first_chunk_mut::<{ CACHED * CHUNK }>()?;
        let mut parts = base.parts()?;
        parts.planes = Some(PlaneParts { system, cached });
        Some(parts)
    }
}

/// Copies `source` into the chunks of `work` (as many as fit), nothing kept or cached; returns
/// the chunks in use.
pub(super) fn load<'w, T: Real, C: WorkChunk<T>>(
    source: &[[T; 3]],
    work: &'w mut [u64],
) -> &'w mut [C] {
    let fit = (work.len() * 8) / core::mem::size_of::<C>();
    let n = chunks_for(source.len()).min(fit);
    let Ok(chunks) = view::<C>(work, n) else {
        return &mut [];
    };
    for (c, pts) in chunks.iter_mut().zip(source.chunks(CHUNK)) {
        if let Some(c) = c.parts() {
            for (dst, p) in c.points.chunks_exact_mut(3).zip(pts) {
                dst.copy_from_slice(p);
            }
            for k in c.kept.chunks_exact_mut(KEPT) {
                k[3] = -T::one();
            }
            *c.count = T::of(pts.len() as f64);
            if let Some(pl) = c.planes {
                pl.cached.chunks_exact_mut(CACHED).for_each(Cached::clear);
            }
        }
    }
    chunks
}

/// The points ICP moved, in source order (world frame, as the last iteration left them), from
/// work laid out for `planes` as [`super::align_points_to_map`] left it. It takes the words
/// mutably only to read them through `WorkChunk::parts`, the one statement of each layout.
pub fn moved_points<T: Real>(
    work: &mut [u64],
    n: usize,
    planes: bool,
) -> impl Iterator<Item = Point<T>> + '_ {
    let (reference, robust) = if planes {
        (None, Some(moved_in::<T, PlaneChunk<T>>(work, n)))
    } else {
        (Some(moved_in::<T, Chunk<T>>(work, n)), None)
    };
    reference
        .into_iter()
        .flatten()
        .chain(robust.into_iter().flatten())
}

/// [`moved_points`] of work in the layout `C`.
fn moved_in<T: Real, C: WorkChunk<T>>(
    work: &mut [u64],
    n: usize,
) -> impl Iterator<Item = Point<T>> + '_ {
    let chunks = view::<C>(work, chunks_for(n)).unwrap_or_default();
    chunks.iter_mut().filter_map(C::parts).flat_map(|c| {
        let (points, count): (&[T; 3 * CHUNK], usize) = (c.points, c.count.wide() as usize);
        points
            .chunks_exact(3)
            .take(count)
            .map(|p| Point::new(p[0], p[1], p[2]))
    })
}
