//! Growing instead of dropping: the odometry moved into larger storage, for a host.
//!
//! A board's arena is fixed, and a full buffer drops by its rule (a full map evicts its
//! farthest voxels, see `local_map`). A host has an allocator: with [`WhenFull::Refuse`], a
//! frame that would drop or evict anything is refused with [`FrameError::Full`] before any
//! state changes, [`Odometry::room_needed`] says which capacities would hold it, and
//! [`Odometry::rehome`] copies the whole state into storage of those capacities. Registered
//! again there, the frame and every later one give the bits a run that started in that storage
//! would have given: no step reads a capacity it has not reached (the map's search, admission
//! and pruning find voxels by key, the clouds are as long as their points).

use super::state::{Buffers, WhenFull};
use super::Odometry;
use crate::config::{Capacities, Degeneracy};
use crate::downsample::cloud_words;
use crate::error::{ConfigError, FrameError};
use crate::local_map::{MapMut, PointCodec, BLOCK};
use crate::scalar::Real;
use crate::storage::{Region, Storage};

impl<T: Real, P: PointCodec<T>, S: Storage> Odometry<T, P, S> {
    /// Chooses what a frame that would overfill a buffer does (default [`WhenFull::Drop`]).
    pub fn set_when_full(&mut self, when: WhenFull) {
        self.buffers.when_full = when;
    }

    /// What a frame that would overfill a buffer does.
    pub fn when_full(&self) -> WhenFull {
        self.buffers.when_full
    }

    /// After [`FrameError::Full`]: the capacities in use, each raised to what the refused frame
    /// needed. Without a refusal, the capacities in use.
    pub fn room_needed(&self) -> Capacities {
        self.buffers.needed
    }

    /// The whole state moved into `storage`, laid out for `caps`: pose, velocity, threshold,
    /// map, the last clouds, counters and high-water marks; the same bits follow as if the
    /// odometry had been built there. `caps` must hold what the odometry holds now
    /// ([`ConfigError::Holds`]) and `storage` have `caps.arena_words::<T, P>()` words.
    pub fn rehome<S2: Storage>(
        &self,
        caps: Capacities,
        mut storage: S2,
    ) -> Result<Odometry<T, P, S2>, ConfigError> {
        caps.validate()?;
        if self.config.degeneracy == Degeneracy::Robust && !caps.plane_terms {
            return Err(ConfigError::PlaneTerms);
        }
        let b = &self.buffers;
        let holds = caps.merge_points >= b.merge_len
            && caps.source_points >= b.source_len
            && caps.map_voxels >= self.map.voxels()
            && caps.map_points.div_ceil(BLOCK) >= self.map.blocks_in_use();
        if !holds {
            return Err(ConfigError::Holds);
        }
        let layout = super::Layout::new::<T, P>(&caps);
        let words = storage.as_mut();
        if words.len() < layout.words {
            return Err(ConfigError::ArenaTooSmall);
        }
        words[..layout.words].fill(0);
        let old = b.storage.as_ref();
        let n = cloud_words::<T>(b.merge_len);
        copy_words(old, b.layout.merge, words, layout.merge, n)?;
        let n = cloud_words::<T>(b.source_len);
        copy_words(old, b.layout.source, words, layout.source, n)?;
        let mut map = self
            .map
            .resized(caps.map_voxels, &layout.map)
            .ok_or(ConfigError::PointsPerVoxel)?;
        let map_words = words
            .get_mut(layout.map.keys.start..)
            .ok_or(ConfigError::ArenaTooSmall)?;
        let copied = MapMut::<T, P>::of(&mut map, &layout.map, map_words)?.copy_from(&self.map());
        if !copied {
            return Err(ConfigError::Holds);
        }
        let mut buffers = Buffers::new(storage, layout, caps, b.when_full);
        (buffers.merge_len, buffers.source_len, buffers.high) = (b.merge_len, b.source_len, b.high);
        Ok(Odometry {
            motion: self.motion,
            sweep: self.sweep,
            threshold: self.threshold,
            config: self.config,
            map,
            buffers,
            strategy: self.strategy,
            _codec: core::marker::PhantomData,
        })
    }

    /// With [`WhenFull::Refuse`], refuses the frame if `need` exceeds a capacity in use,
    /// noting what it needs for [`Self::room_needed`].
    pub(super) fn room_for(&mut self, need: Capacities) -> Result<(), FrameError> {
        let b = &mut self.buffers;
        match shortfall(&b.caps, b.when_full, &need) {
            Some(needed) => {
                b.needed = needed;
                Err(FrameError::Full)
            }
            None => Ok(()),
        }
    }

    /// [`Self::room_for`] a whole scan of `points` points.
    pub(super) fn room_for_scan(&mut self, points: usize) -> Result<(), FrameError> {
        self.room_for(Capacities {
            scan_points: points,
            ..nothing()
        })
    }

    /// What a map update adding `merge` points can need: a voxel and a block for each.
    pub(super) fn map_room(&self, merge: usize) -> Capacities {
        Capacities {
            map_voxels: self.map.voxels() + merge,
            map_points: (self.map.blocks_in_use() + merge) * BLOCK,
            ..nothing()
        }
    }
}

/// With [`WhenFull::Refuse`] and `need` above a capacity of `caps`: `caps` with each
/// capacity raised to `need`'s.
pub(super) fn shortfall(
    caps: &Capacities,
    when: WhenFull,
    need: &Capacities,
) -> Option<Capacities> {
    let short = need.scan_points > caps.scan_points
        || need.merge_points > caps.merge_points
        || need.source_points > caps.source_points
        || need.map_voxels > caps.map_voxels
        || need.map_points > caps.map_points;
    (when == WhenFull::Refuse && short).then_some(Capacities {
        scan_points: caps.scan_points.max(need.scan_points),
        merge_points: caps.merge_points.max(need.merge_points),
        source_points: caps.source_points.max(need.source_points),
        map_voxels: caps.map_voxels.max(need.map_voxels),
        map_points: caps.map_points.max(need.map_points),
        plane_terms: caps.plane_terms,
    })
}

/// A need of nothing: every capacity 0.
pub(super) const fn nothing() -> Capacities {
    Capacities {
        scan_points: 0,
        merge_points: 0,
        source_points: 0,
        map_voxels: 0,
        map_points: 0,
        plane_terms: false,
    }
}

/// Copies the first `n` words of region `from` of `src` to region `to` of `dst`.
fn copy_words(
    src: &[u64],
    from: Region,
    dst: &mut [u64],
    to: Region,
    n: usize,
) -> Result<(), ConfigError> {
    let short = ConfigError::ArenaTooSmall;
    let s = src.get(from.start..from.start + n).ok_or(short)?;
    let d = dst.get_mut(to.start..to.start + n).ok_or(short)?;
    d.copy_from_slice(s);
    Ok(())
}
