//! Step 3 (Sec. III-C): the local map, a voxel hash map of points, and correspondence search.
//!
//! Voxels of size `v` hold at most `N_max` points each. A scan's merge cloud, registered into
//! the world frame, is added point by point with the reference's admission rule: a point is
//! skipped if its voxel is full or already holds a point closer than `sqrt(v^2 / N_max)`.
//! After each update, voxels whose first point is `r_max` or more from the sensor are removed.
//!
//! Storage is fixed: an open-addressing table of voxel keys (linear probing, load at most 3/4,
//! backward-shift deletion, so no tombstones accumulate over hours) and a pool of
//! [`BLOCK`]-point blocks chained per voxel, so a voxel holding 3 points costs one block, not
//! `N_max` slots. A full map degrades the way a smaller `r_max` would: the update evicts the
//! voxels farthest from the sensor and shrinks the map's radius, never refusing the structure
//! next to the sensor that the next scan registers against (`update`); the radius grows back
//! while there is room.
//!
//! The map is its bookkeeping ([`MapState`], a few words) plus five buffers in named regions
//! ([`MapLayout`], in `layout`). [`MapView`] (`view`, `search`) reads them: correspondence
//! search, every point; the update (`update`) works on a mutable view. [`LocalMap`] owns (or borrows) storage for a map on its own; inside
//! [`crate::Odometry`] the regions are part of the pipeline's one storage.

mod codec;
mod copy;
mod evict;
mod layout;
mod search;
mod state;
mod update;
mod view;

pub use codec::{Exact, PointCodec, Quantized};
pub use evict::{EVICT_TO, RADIUS_BINS};
pub use layout::MapLayout;
pub use layout::BLOCK;
pub use search::{Nearest, Voxels};
pub(crate) use state::MapState;
pub use state::{MapCapacity, UpdateStats};
pub(crate) use update::MapMut;
pub use update::{GROW_BELOW, GROW_STEP};
pub use view::MapView;

use crate::error::ConfigError;
use crate::geometry::{Point, Pose};
use crate::scalar::Real;
use crate::storage::Storage;
use core::marker::PhantomData;

/// A local map on storage of its own (owned or borrowed), for using the map as a stage: the
/// cross-check, benches and bindings that mirror the reference's `VoxelHashMap`.
pub struct LocalMap<T: Real, P: PointCodec<T>, S: Storage> {
    state: MapState<T>,
    layout: MapLayout,
    storage: S,
    _codec: PhantomData<P>,
}

impl<T: Real, P: PointCodec<T>, S: Storage> LocalMap<T, P, S> {
    /// Words of storage for `voxels` voxels and `points` points.
    pub const fn words(voxels: usize, points: usize) -> usize {
        MapLayout::new(voxels, points, core::mem::size_of::<P::Stored>()).words()
    }

    /// An empty map with voxels of `voxel_size`, pruned beyond `max_distance`, holding at most
    /// `max_points_per_voxel` points per voxel (1..=255), `voxels` voxels and `points` points, in
    /// `storage` (at least [`Self::words`] words).
    pub fn new(
        voxel_size: T,
        max_distance: T,
        max_points_per_voxel: u32,
        voxels: usize,
        points: usize,
        mut storage: S,
    ) -> Result<Self, ConfigError> {
        let layout = MapLayout::new(voxels, points, core::mem::size_of::<P::Stored>());
        let mut state = MapState::new(
            voxel_size,
            max_distance,
            max_points_per_voxel,
            voxels,
            &layout,
        )
        .ok_or(ConfigError::PointsPerVoxel)?;
        MapMut::<T, P>::of(&mut state, &layout, storage.as_mut())?.clear();
        Ok(Self {
            state,
            layout,
            storage,
            _codec: PhantomData,
        })
    }

    /// Read access.
    pub fn view(&self) -> MapView<'_, T, P> {
        // `new` checked the storage's length; a storage whose length changed since reads as an
        // empty map rather than panicking.
        MapView::of(&self.state, &self.layout, self.storage.as_ref())
            .unwrap_or_else(|_| MapView::empty(&self.state))
    }

    fn with_mut<R: Default>(&mut self, f: impl FnOnce(&mut MapMut<'_, T, P>) -> R) -> R {
        match MapMut::of(&mut self.state, &self.layout, self.storage.as_mut()) {
            Ok(mut m) => f(&mut m),
            Err(_) => R::default(),
        }
    }

    /// Removes every voxel.
    pub fn clear(&mut self) {
        self.with_mut(|m| m.clear())
    }

    /// Adds world-frame points in order with the reference's admission rule; with no pose to
    /// evict around, what does not fit is dropped and counted.
    pub fn add_points(&mut self, points: impl Iterator<Item = Point<T>>) -> UpdateStats {
        self.with_mut(|m| m.add_points(points))
    }

    /// Removes voxels whose first point is at least `r_max` from `origin`.
    pub fn remove_far_from(&mut self, origin: &Point<T>) -> usize {
        self.with_mut(|m| m.remove_far_from(origin))
    }

    /// The reference's `Update`: adds `local` moved by `pose`, then prunes around the pose; a
    /// full map evicts its farthest voxels first (see the module doc), counting every point of
    /// the scan as a voxel of its own ([`Self::update_with`] tallies them exactly).
    pub fn update(&mut self, local: &[[T; 3]], pose: &Pose<T>) -> UpdateStats {
        self.update_with(local, pose, &mut [])
    }

    /// [`Self::update`] with `scratch` to tally the scan's voxels when the map is full (16
    /// bytes per point of `local` are enough; the pipeline lends its downsampling scratch).
    pub fn update_with(
        &mut self,
        local: &[[T; 3]],
        pose: &Pose<T>,
        scratch: &mut [u64],
    ) -> UpdateStats {
        self.with_mut(|m| m.update(local, pose, scratch))
    }

    /// The closest map point to `query` within `max_distance`, with its squared distance.
    pub fn closest_neighbor(&self, query: &Point<T>, max_distance: T) -> Option<(Point<T>, T)> {
        self.view().closest_neighbor(query, max_distance)
    }

    /// Occupied voxels.
    pub fn voxels(&self) -> usize {
        self.state.voxels
    }

    /// Stored points.
    pub fn points(&self) -> usize {
        self.state.n_points
    }

    /// The radius in force: `max_distance`, or less after the map filled.
    pub fn radius(&self) -> T {
        self.state.radius()
    }
}

#[cfg(test)]
mod tests;
