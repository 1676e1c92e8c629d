//! The tiles within reach of the pose, kept in the prior map's fixed storage.
//!
//! The tiles needed are those whose square comes within `reach` of the pose (in `x, y`). When
//! one of them is not held, the map is cleared and filled again with every tile within
//! `reach + s / 2`, in key order: the same pose gives the same map, bit for bit, whatever
//! came before, and the robot can travel half a tile before the next load. A load's work is
//! bounded by the tiles held at most times a record's points.

use crate::geometry::Point;
use crate::local_map::{MapMut, PointCodec};
use crate::prior_map::{TileKey, TileMap};
use crate::scalar::Real;

/// Most tiles held at once.
pub const MAX_TILES_HELD: usize = 64;

/// The keys of the tiles held (sorted), damaged ones included so they are not read again.
#[derive(Clone, Copy, Debug)]
pub(super) struct Held {
    keys: [TileKey; MAX_TILES_HELD],
    len: usize,
}

/// What one load did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Loaded {
    /// Tiles read into the map.
    pub tiles: u32,
    /// Tiles refused for a damaged record (see [`crate::prior_map::TileError`]).
    pub damaged: u32,
    /// Points the map had no room for.
    pub dropped_points: u32,
}

/// Most tiles of edge `s` a disc of radius `r` can touch.
pub fn tiles_touched(r: f64, s: f64) -> usize {
    let n = libm::floor(2.0 * r / s) as usize + 2;
    n * n
}

impl Held {
    pub(super) const fn new() -> Self {
        Self {
            keys: [TileKey { i: 0, j: 0 }; MAX_TILES_HELD],
            len: 0,
        }
    }

    fn holds(&self, key: TileKey) -> bool {
        self.keys[..self.len].binary_search(&key).is_ok()
    }

    /// Loads the tiles around `(x, y)` into `map` if one within `reach` is missing.
    pub(super) fn around<T: Real, P: PointCodec<T>>(
        &mut self,
        file: &TileMap<'_>,
        map: &mut MapMut<'_, T, P>,
        x: f64,
        y: f64,
        reach: f64,
    ) -> Option<Loaded> {
        let s = file.header().tile_size;
        let mut missing = false;
        for_each_touched(x, y, reach, s, |key| {
            missing |= !self.holds(key) && file.find(key).is_some();
        });
        if !missing {
            return None;
        }
        self.len = 0;
        for_each_touched(x, y, reach + 0.5 * s, s, |key| {
            if file.find(key).is_some() && self.len < MAX_TILES_HELD {
                self.keys[self.len] = key;
                self.len += 1;
            }
        });
        self.keys[..self.len].sort_unstable();
        map.clear();
        let mut loaded = Loaded::default();
        for key in &self.keys[..self.len] {
            let Some(t) = file.find(*key) else { continue };
            match file.tile(t) {
                Ok(tile) => {
                    let points = tile
                        .points()
                        .map(|p| Point::new(T::of(p[0]), T::of(p[1]), T::of(p[2])));
                    let stats = map.add_points(points);
                    loaded.tiles += 1;
                    loaded.dropped_points += (stats.dropped_points + stats.dropped_voxels) as u32;
                }
                Err(_) => loaded.damaged += 1,
            }
        }
        Some(loaded)
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
