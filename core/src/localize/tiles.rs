//! The tiles within reach of the pose, read in place from the map file, and the voxels they
//! hold as the registration sees them ([`HeldVoxels`]).
//!
//! The tiles needed are those whose square comes within `reach` of the pose (in `x, y`). When
//! one of them is not held, the held set becomes every tile within `reach + s / 2`, in key
//! order: the same pose gives the same map whatever came before, and the robot can travel half
//! a tile before the next load. A tile is checked (CRC, order) when it joins the set; tiles
//! already held are kept without reading them again. Nothing is copied: a voxel's points are
//! found by a binary search in its tile's record.

use crate::geometry::Point;
use crate::local_map::Voxels;
use crate::prior_map::{Tile, TileKey, TileMap};
use crate::scalar::Real;
use crate::voxel::VoxelKey;

/// Most tiles held at once.
pub const MAX_TILES_HELD: usize = 64;

/// The tiles held, sorted by key; a damaged one is held as `None` so it is not read again.
#[derive(Clone, Copy, Debug)]
pub(super) struct Held<'m> {
    keys: [TileKey; MAX_TILES_HELD],
    tiles: [Option<Tile<'m>>; MAX_TILES_HELD],
    len: usize,
}

/// What one load did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Loaded {
    /// Tiles that joined the held set, checked.
    pub tiles: u32,
    /// Tiles refused for a damaged record (see [`crate::prior_map::TileError`]).
    pub damaged: u32,
}

/// Most tiles of edge `s` a disc of radius `r` can touch.
pub fn tiles_touched(r: f64, s: f64) -> usize {
    let n = libm::floor(2.0 * r / s) as usize + 2;
    n * n
}

impl<'m> Held<'m> {
    pub(super) const fn new() -> Self {
        Self {
            keys: [TileKey { i: 0, j: 0 }; MAX_TILES_HELD],
            tiles: [None; MAX_TILES_HELD],
            len: 0,
        }
    }

    fn position(&self, key: TileKey) -> Option<usize> {
        self.keys[..self.len].binary_search(&key).ok()
    }

    /// Tiles held, damaged ones included.
    pub(super) fn len(&self) -> usize {
        self.len
    }

    /// Points held (of the tiles not damaged).
    pub(super) fn points(&self) -> usize {
        self.tiles[..self.len].iter().flatten().map(Tile::len).sum()
    }

    /// Holds the tiles around `(x, y)` if one within `reach` is missing.
    pub(super) fn around(
        &mut self,
        file: &TileMap<'m>,
        x: f64,
        y: f64,
        reach: f64,
    ) -> Option<Loaded> {
        let s = file.header().tile_size;
        let mut missing = false;
        for_each_touched(x, y, reach, s, |key| {
            missing |= self.position(key).is_none() && file.find(key).is_some();
        });
        if !missing {
            return None;
        }
        // Each tile in the file with its index entry, looked up once; the keys are distinct,
        // so sorting them is deterministic.
        let mut found = [(TileKey { i: 0, j: 0 }, 0usize); MAX_TILES_HELD];
        let mut n = 0;
        for_each_touched(x, y, reach + 0.5 * s, s, |key| {
            if n < MAX_TILES_HELD {
                if let Some(t) = file.find(key) {
                    found[n] = (key, t);
                    n += 1;
                }
            }
        });
        let found = &mut found[..n];
        found.sort_unstable_by_key(|&(key, _)| key);
        let before = *self;
        let mut loaded = Loaded::default();
        for (k, &(key, t)) in found.iter().enumerate() {
            self.keys[k] = key;
            self.tiles[k] = match before.position(key) {
                Some(b) => before.tiles[b],
                None => {
                    let tile = file.tile(t).ok();
                    match tile {
                        Some(_) => loaded.tiles += 1,
                        None => loaded.damaged += 1,
                    }
                    tile
                }
            };
        }
        self.len = n;
        Some(loaded)
    }

    /// The held tiles as voxels of size `v` (`ratio` voxels along a tile's edge).
    pub(super) fn voxels<T: Real>(&self, v: f64, ratio: i32) -> HeldVoxels<'_, 'm, T> {
        HeldVoxels {
            held: self,
            voxel_size: T::of(v),
            ratio,
        }
    }
}

/// The held tiles' voxels: what the localizer registers to.
pub(super) struct HeldVoxels<'h, 'm, T> {
    held: &'h Held<'m>,
    voxel_size: T,
    ratio: i32,
}

/// A voxel's points: its tile's place in the held set and their range in the record.
#[derive(Clone, Copy, Debug)]
pub(super) struct Run {
    tile: u8,
    start: u32,
    end: u32,
}

impl<T: Real> Voxels<T> for HeldVoxels<'_, '_, T> {
    type Slot = Run;

    fn voxel_size(&self) -> T {
        self.voxel_size
    }

    fn is_empty(&self) -> bool {
        self.held.points() == 0
    }

    fn find(&self, key: &VoxelKey) -> Option<Run> {
        let home = TileKey {
            i: key[0].div_euclid(self.ratio),
            j: key[1].div_euclid(self.ratio),
        };
        let t = self.held.position(home)?;
        let range = self.held.tiles[t]?.voxel(key);
        (!range.is_empty()).then_some(Run {
            tile: t as u8,
            start: range.start as u32,
            end: range.end as u32,
        })
    }

    fn count(&self, run: Run) -> u32 {
        run.end - run.start
    }

    fn for_each_in(&self, run: Run, mut f: impl FnMut(Point<T>) -> bool) {
        let Some(tile) = self.held.tiles[usize::from(run.tile)] else {
            return;
        };
        for k in run.start as usize..run.end as usize {
            let [x, y, z] = tile.point(k);
            if !f(Point::new(T::of(x), T::of(y), T::of(z))) {
                return;
            }
        }
    }
}

/// Calls `f` with every tile key whose square comes within `r` of `(x, y)`, row by row.
fn for_each_touched(x: f64, y: f64, r: f64, s: f64, mut f: impl FnMut(TileKey)) {
    let lo = TileKey::of(x - r, y - r, s);
    let hi = TileKey::of(x + r, y + r, s);
    for i in lo.i..=hi.i {
        for j in lo.j..=hi.j {
            let (x0, y0) = (f64::from(i) * s, f64::from(j) * s);
            let dx = (x0 - x).max(x - (x0 + s)).max(0.0);
            let dy = (y0 - y).max(y - (y0 + s)).max(0.0);
            if dx * dx + dy * dy <= r * r {
                f(TileKey { i, j });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prior_map::{encode_map, Header};
    use std::vec::Vec;

    /// A map of 9 x 9 tiles of 10 m, one point in each.
    fn grid() -> Vec<u8> {
        let keys: Vec<TileKey> = (0..9)
            .flat_map(|i| (0..9).map(move |j| TileKey { i, j }))
            .collect();
        let point = [[1.5f32, 1.5, 0.0]];
        let tiles: Vec<(TileKey, &[[f32; 3]])> = keys.iter().map(|k| (*k, &point[..])).collect();
        let h = Header {
            voxel_size: 1.0,
            tile_size: 10.0,
            points_per_voxel: 1,
            tile_points: 1,
            tiles: 81,
            frame: Header::frame_field("map").unwrap(),
        };
        let mut out = std::vec![0u8; h.file_len()];
        assert!(encode_map(&h, &tiles, &mut out));
        out
    }

    #[test]
    fn a_load_holds_every_tile_within_reach_and_half_a_tile_in_key_order() {
        let bytes = grid();
        let file = TileMap::open(&bytes).unwrap();
        for (x, y, reach) in [(45.0, 45.0, 12.0), (31.0, 58.5, 9.0), (3.0, 88.0, 20.0)] {
            let mut held = Held::new();
            let loaded = held.around(&file, x, y, reach).unwrap();
            // Every tile whose square comes within reach + s / 2 of (x, y), counted here
            // from the squares themselves.
            let want: Vec<TileKey> = (0..9)
                .flat_map(|i| (0..9).map(move |j| TileKey { i, j }))
                .filter(|k| {
                    let (x0, y0) = (10.0 * f64::from(k.i), 10.0 * f64::from(k.j));
                    let dx = (x0 - x).max(x - x0 - 10.0).max(0.0);
                    let dy = (y0 - y).max(y - y0 - 10.0).max(0.0);
                    dx.hypot(dy) <= reach + 5.0
                })
                .collect();
            assert_eq!(
                &held.keys[..held.len],
                &want[..],
                "({x}, {y}) reach {reach}"
            );
            assert_eq!((loaded.tiles, loaded.damaged), (want.len() as u32, 0));
            assert_eq!(held.points(), want.len());
            // Nothing within reach is missing: no second load.
            assert!(held.around(&file, x, y, reach).is_none());
        }
        // All 81 tiles within reach: the first 64 met are held, no more.
        let mut held = Held::new();
        let loaded = held.around(&file, 45.0, 45.0, 80.0).unwrap();
        assert_eq!((held.len, loaded.tiles), (MAX_TILES_HELD, 64));
    }

    #[test]
    fn the_tiles_touched_are_those_within_reach_and_never_more_than_the_bound() {
        let mut seen = std::vec::Vec::new();
        for_each_touched(25.0, 25.0, 30.0, 50.0, |k| seen.push(k));
        // A disc of 30 m around the centre of tile (0, 0) reaches its four neighbours only.
        assert_eq!(seen.len(), 5, "{seen:?}");
        for (x, y, r) in [(0.0, 0.0, 120.0), (13.7, -88.1, 145.0), (-1e3, 1e3, 60.0)] {
            let mut n = 0;
            for_each_touched(x, y, r, 50.0, |_| n += 1);
            assert!(n <= tiles_touched(r, 50.0), "{n} tiles at r {r}");
        }
    }
}
