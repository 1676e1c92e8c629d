//! Where the map's buffers sit in the storage, and their typed views.

use crate::error::ConfigError;
use crate::storage::{split_off, view, view_ref, words_for, Carver, Region};
use crate::voxel::{slots_for, VoxelKey};

/// Points per map block; a voxel owns a chain of blocks, so memory follows the points a voxel
/// really holds instead of reserving `N_max` for each one.
pub const BLOCK: usize = 4;

/// Where the map's buffers sit, in `u64` words: the voxel table (slots for `voxels` at load
/// <= 3/4) and the block pool (`points / BLOCK` blocks, rounded up).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MapLayout {
    /// Slots of the voxel table.
    pub slots: usize,
    /// Blocks in the point pool.
    pub blocks: usize,
    /// Voxel keys, 12 bytes a slot.
    pub keys: Region,
    /// First block of each slot's chain, 4 bytes a slot.
    pub heads: Region,
    /// Points in each slot's voxel (0: empty slot), 1 byte a slot.
    pub counts: Region,
    /// The block pool, `BLOCK` stored points a block.
    pub points: Region,
    /// Next block of each block's chain (or of the free list), 4 bytes a block.
    pub links: Region,
}

impl MapLayout {
    /// The layout for `voxels` voxels and `points` points of `stored_size` bytes each, placed at
    /// the carver's position.
    pub(crate) const fn carve(
        voxels: usize,
        points: usize,
        stored_size: usize,
        c: &mut Carver,
    ) -> Self {
        let slots = slots_for(voxels);
        let blocks = points.div_ceil(BLOCK);
        Self {
            slots,
            blocks,
            keys: c.take(words_for(slots * 12)),
            heads: c.take(words_for(slots * 4)),
            counts: c.take(words_for(slots)),
            points: c.take(words_for(blocks * BLOCK * stored_size)),
            links: c.take(words_for(blocks * 4)),
        }
    }

    /// The layout of a map on its own storage (regions from word 0).
    pub const fn new(voxels: usize, points: usize, stored_size: usize) -> Self {
        Self::carve(voxels, points, stored_size, &mut Carver::new())
    }

    /// Words from the first region's start to the last one's end.
    pub const fn words(&self) -> usize {
        self.links.end() - self.keys.start
    }

    /// The map's buffers in `words`, which start at the first region.
    pub(super) fn split<'w, P: bytemuck::Pod>(
        &self,
        words: &'w mut [u64],
    ) -> Result<MapBuffers<'w, P>, ConfigError> {
        let (k, rest) = split_off(words, self.keys)?;
        let (h, rest) = split_off(rest, self.heads)?;
        let (c, rest) = split_off(rest, self.counts)?;
        let (p, rest) = split_off(rest, self.points)?;
        let (l, _) = split_off(rest, self.links)?;
        Ok(MapBuffers {
            keys: view(k, self.slots)?,
            heads: view(h, self.slots)?,
            counts: view(c, self.slots)?,
            points: view(p, self.blocks * BLOCK)?,
            links: view(l, self.blocks)?,
        })
    }

    /// Read-only [`Self::split`].
    pub(super) fn split_ref<'w, P: bytemuck::Pod>(
        &self,
        words: &'w [u64],
    ) -> Result<MapSlices<'w, P>, ConfigError> {
        let at = |r: Region| words.get(r.start - self.keys.start..r.end() - self.keys.start);
        let short = ConfigError::ArenaTooSmall;
        Ok(MapSlices {
            keys: view_ref(at(self.keys).ok_or(short)?, self.slots)?,
            heads: view_ref(at(self.heads).ok_or(short)?, self.slots)?,
            counts: view_ref(at(self.counts).ok_or(short)?, self.slots)?,
            points: view_ref(at(self.points).ok_or(short)?, self.blocks * BLOCK)?,
            links: view_ref(at(self.links).ok_or(short)?, self.blocks)?,
        })
    }
}

/// The map's buffers, mutable.
pub(super) struct MapBuffers<'a, S> {
    pub(super) keys: &'a mut [VoxelKey],
    pub(super) heads: &'a mut [u32],
    pub(super) counts: &'a mut [u8],
    pub(super) points: &'a mut [S],
    pub(super) links: &'a mut [u32],
}

/// The map's buffers, read-only.
pub(super) struct MapSlices<'a, S> {
    pub(super) keys: &'a [VoxelKey],
    pub(super) heads: &'a [u32],
    pub(super) counts: &'a [u8],
    pub(super) points: &'a [S],
    pub(super) links: &'a [u32],
}
