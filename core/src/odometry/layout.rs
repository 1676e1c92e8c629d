//! The pipeline's storage, named: which region of the words each buffer lives in.
//!
//! Each stage sizes its own buffers ([`crate::downsample`] the clouds and their scratch,
//! [`crate::registration`] ICP's work chunks, [`crate::local_map`] the table and pool); this
//! module only places them one after the other, in the order the frame uses them.

use crate::config::Capacities;
use crate::downsample::{cloud_words, scratch_words_for};
use crate::error::ConfigError;
use crate::local_map::{MapLayout, PointCodec};
use crate::registration::work_words;
use crate::scalar::Real;
use crate::storage::{split_off, view, Carver, Region};

/// Where every buffer of an [`crate::Odometry`] sits, in `u64` words.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Layout {
    /// `P*_merge`: the scan downsampled with voxels of `alpha v` (Sec. III-B), sensor frame.
    pub merge: Region,
    /// `P^*`: the merge cloud downsampled with voxels of `beta v`, sensor frame.
    pub source: Region,
    /// The dedup grid of either downsampling, then the reference-order reconstruction.
    pub scratch: Region,
    /// ICP's chunks: the source points it moves and their partial normal equations (and, with
    /// [`Capacities::plane_terms`], their planes and point-to-plane equations).
    pub icp: Region,
    /// The local map's table and point pool.
    pub map: MapLayout,
    /// Words in all.
    pub words: usize,
}

impl Layout {
    /// The layout for `caps` with scalar `T` and map point codec `P`.
    pub const fn new<T: Real, P: PointCodec<T>>(caps: &Capacities) -> Self {
        let mut c = Carver::new();
        let merge = c.take(cloud_words::<T>(caps.merge_points));
        let source = c.take(cloud_words::<T>(caps.source_points));
        // Either downsampling's grid is sized by its output buffer.
        let largest = if caps.merge_points > caps.source_points {
            caps.merge_points
        } else {
            caps.source_points
        };
        let scratch = c.take(scratch_words_for(largest));
        let icp = c.take(work_words::<T>(caps.source_points, caps.plane_terms));
        let map = MapLayout::carve(
            caps.map_voxels,
            caps.map_points,
            core::mem::size_of::<P::Stored>(),
            &mut c,
        );
        Self {
            merge,
            source,
            scratch,
            icp,
            map,
            words: c.used(),
        }
    }

    /// The buffers in `words`, typed.
    pub(crate) fn split<'w, T: Real>(
        &self,
        caps: &Capacities,
        words: &'w mut [u64],
    ) -> Result<Parts<'w, T>, ConfigError> {
        let (merge, rest) = split_off(words, self.merge)?;
        let (source, rest) = split_off(rest, self.source)?;
        let (scratch, rest) = split_off(rest, self.scratch)?;
        let (icp, map) = split_off(rest, self.icp)?;
        Ok(Parts {
            merge: view(merge, caps.merge_points)?,
            source: view(source, caps.source_points)?,
            scratch,
            icp,
            map,
        })
    }
}

/// The pipeline's buffers for one call.
pub(crate) struct Parts<'w, T> {
    pub(crate) merge: &'w mut [[T; 3]],
    pub(crate) source: &'w mut [[T; 3]],
    pub(crate) scratch: &'w mut [u64],
    pub(crate) icp: &'w mut [u64],
    /// The words from the map's first region on.
    pub(crate) map: &'w mut [u64],
}

impl Capacities {
    /// `u64` words of storage an [`crate::Odometry`] with scalar `T` and map point codec `P`
    /// needs (a `const fn`, so the storage can be a `static`).
    pub const fn arena_words<T: Real, P: PointCodec<T>>(&self) -> usize {
        Layout::new::<T, P>(self).words
    }

    /// Bytes of the map alone (voxel table and point pool) with map points of `stored_size`
    /// bytes, for comparison with the reference's local map.
    pub const fn map_bytes(&self, stored_size: usize) -> usize {
        MapLayout::new(self.map_voxels, self.map_points, stored_size).words() * 8
    }
}
