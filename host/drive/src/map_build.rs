//! Building a prior map file (`kiss_odom_core::prior_map`) from world-frame points: the
//! voxel map that localization later registers against, written once, on the host.
//!
//! Points are admitted with the local map's own rule (at most `N` a voxel, none closer than
//! `sqrt(v^2 / N)` to one already there), so a map built with a run's voxel size holds what
//! that run's local map would, without its radius. The voxel map is the core's fixed-capacity
//! `LocalMap`; it grows by doubling *before* a batch could fill it, never after a point was
//! refused, so the kept points do not depend on the starting capacity. The kept points are
//! grouped into tiles by voxel, arranged as a record needs (`prior_map::arrange_tile`: sorted
//! by voxel and coordinates, not by table slot, which depends on the capacity) and encoded as
//! the file's bytes.

use anyhow::{bail, ensure, Context, Result};
use kiss_odom_core::prior_map::{
    arrange_tile, encode_map, Header, TileKey, MAX_TILES, MAX_TILE_POINTS,
};
use kiss_odom_core::stages::{point_to_voxel, LocalMap, Preprocessed, Preprocessor, BLOCK};
use kiss_odom_core::{Config, Exact, Point, Pose};
use std::collections::BTreeMap;

/// Nothing is pruned: a map being built has no sensor to measure distance from.
const NO_RADIUS: f64 = 1e9;
/// Voxels and points of a builder's first map; it doubles from there.
const FIRST_VOXELS: usize = 1 << 14;
/// Points of a builder's first map.
const FIRST_POINTS: usize = 1 << 16;

/// What the file is to be: the voxel size (a run's, to match its map), the tile edge, the
/// points per voxel and the map frame's name.
#[derive(Clone, Debug, PartialEq)]
pub struct MapParams {
    /// Voxel size `v` (m).
    pub voxel_size: f64,
    /// Tile edge `s` (m), a whole multiple of `v`.
    pub tile_size: f64,
    /// Points per voxel at most, `N` (3..=255).
    pub points_per_voxel: u32,
    /// The map frame's name: ASCII, at most 16 bytes.
    pub frame: String,
}

/// What a build kept, for the one line the command prints.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MapStats {
    /// Points offered: every point given to [`MapBuilder::add`], every point of a scan given
    /// to [`MapBuilder::add_scan`] (before its crop).
    pub points_in: usize,
    /// Points stored.
    pub points_kept: usize,
    /// Occupied voxels.
    pub voxels: usize,
    /// Tiles in the file.
    pub tiles: usize,
    /// The kept points' extent along `x` and `y` (m).
    pub extent: [f64; 2],
    /// Bytes of the file.
    pub bytes: usize,
}

/// A prior map being built: add points (world frame), then [`MapBuilder::encode`].
pub struct MapBuilder {
    params: MapParams,
    frame: [u8; 16],
    map: LocalMap<f64, Exact, Vec<u64>>,
    voxel_capacity: usize,
    point_capacity: usize,
    points_in: usize,
    scan: Vec<[f64; 3]>,
}

impl MapBuilder {
    /// An empty map; refuses parameters the file cannot hold (naming the one at fault).
    pub fn new(params: MapParams) -> Result<Self> {
        Self::with_capacity(params, FIRST_VOXELS, FIRST_POINTS)
    }

    /// [`Self::new`] starting from a map of `voxels` voxels and `points` points (at least one
    /// each): the capacity only changes how often it grows, never the result.
    pub fn with_capacity(params: MapParams, voxels: usize, points: usize) -> Result<Self> {
        let (v, s) = (params.voxel_size, params.tile_size);
        ensure!(
            v.is_finite() && v > 0.0,
            "voxel size {v} m: not a positive length"
        );
        let ratio = s / v;
        ensure!(
            s.is_finite()
                && (v..=1e5).contains(&s)
                && (ratio - ratio.round()).abs() <= 1e-9 * ratio,
            "tile size {s} m: not a whole multiple of the voxel size {v} m (at most 100 km)"
        );
        // The localizer reads a voxel's shape from its covariance, which needs 3 points: with
        // fewer, no registration is conditioned and no frame is ever localized.
        ensure!(
            (3..=255).contains(&params.points_per_voxel),
            "points per voxel {}: not in 3..=255 (the localizer reads a voxel's shape from \
             3 points or more)",
            params.points_per_voxel
        );
        let frame = Header::frame_field(&params.frame).with_context(|| {
            format!(
                "frame name {:?}: not ASCII of at most 16 bytes",
                params.frame
            )
        })?;
        let (voxels, points) = (voxels.max(1), points.max(BLOCK));
        let map = empty_map(&params, voxels, points)?;
        Ok(Self {
            params,
            frame,
            map,
            voxel_capacity: voxels,
            point_capacity: points,
            points_in: 0,
            scan: Vec::new(),
        })
    }

    /// Adds world-frame points in order with the local map's admission rule; a point that is
    /// not finite is counted and skipped.
    pub fn add(&mut self, points: &[[f64; 3]]) -> Result<()> {
        self.points_in += points.len();
        let mut rest = points;
        while !rest.is_empty() {
            let room = self.room();
            if room < rest.len().min(BLOCK * 1024) {
                self.grow()?;
                continue;
            }
            let (now, later) = rest.split_at(room.min(rest.len()));
            let finite = now.iter().filter(|p| p.iter().all(|c| c.is_finite()));
            let st = self.map.add_points(finite.map(|p| Point::from(*p)));
            // `room` bounds what the batch can take, so nothing is refused for capacity.
            ensure!(
                st.dropped_voxels == 0 && st.dropped_points == 0,
                "the map refused {} points within its room (a bug)",
                st.dropped_voxels + st.dropped_points
            );
            rest = later;
        }
        Ok(())
    }

    /// Adds one scan (sensor frame) as the odometry takes it in: deskewed with `motion` (the
    /// sensor's motion over the sweep, `inv(T_{k-1}) T_k`) when `stamps` are usable and the
    /// configuration deskews, cropped to `(min_range, max_range)`, then moved by `pose` (the
    /// end of the sweep's, as the odometry's poses are).
    pub fn add_scan(
        &mut self,
        points: &[[f64; 3]],
        stamps: Option<&[f64]>,
        motion: &Pose<f64>,
        pose: &Pose<f64>,
        config: &Config<f64>,
    ) -> Result<Preprocessed> {
        let span = Preprocessor::<f64>::span(config.deskew, stamps, points.len());
        let pre = Preprocessor::with_span(config.min_range, config.max_range, span, motion, None);
        let mut scan = std::mem::take(&mut self.scan);
        scan.clear();
        scan.resize(points.len(), [0.0; 3]);
        let done = pre.run(points, stamps, &mut scan);
        scan.truncate(done.kept);
        for p in scan.iter_mut() {
            let q = pose * Point::from(*p);
            *p = [q.x, q.y, q.z];
        }
        let added = self.add(&scan);
        self.points_in += points.len() - scan.len();
        self.scan = scan;
        added.map(|()| done)
    }

    /// Points offered so far.
    pub fn points_in(&self) -> usize {
        self.points_in
    }

    /// Points kept so far.
    pub fn points_kept(&self) -> usize {
        self.map.points()
    }

    /// The file's bytes and what they hold; refuses an empty map and one that a file cannot
    /// hold (too many tiles, or points in a tile).
    pub fn encode(&self) -> Result<(Vec<u8>, MapStats)> {
        ensure!(
            self.map.points() > 0,
            "the map is empty: no point of the input was kept"
        );
        let (v, s) = (self.params.voxel_size, self.params.tile_size);
        let mut header = Header {
            voxel_size: v,
            tile_size: s,
            points_per_voxel: self.params.points_per_voxel,
            tile_points: 0,
            tiles: 0,
            frame: self.frame,
        };
        let r = header.voxels_per_tile();
        let mut tiles: BTreeMap<TileKey, Vec<[f64; 3]>> = BTreeMap::new();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        self.map.view().for_each_point(|_, p| {
            // The tile of the point's voxel, so that each voxel lies in one tile.
            let k = point_to_voxel(&p, v);
            let key = TileKey {
                i: k[0].div_euclid(r),
                j: k[1].div_euclid(r),
            };
            tiles.entry(key).or_default().push([p.x, p.y, p.z]);
            for (a, c) in [p.x, p.y].into_iter().enumerate() {
                lo[a] = lo[a].min(c);
                hi[a] = hi[a].max(c);
            }
        });
        ensure!(
            tiles.len() <= MAX_TILES as usize,
            "{} tiles, more than a file's {MAX_TILES}: use larger tiles",
            tiles.len()
        );
        header.tiles = tiles.len() as u32;
        let offsets: Vec<(TileKey, Vec<[f32; 3]>)> = tiles
            .into_iter()
            .map(|(key, pts)| {
                let corner = [f64::from(key.i) * s, f64::from(key.j) * s];
                let mut off: Vec<[f32; 3]> = pts
                    .iter()
                    .map(|p| {
                        [
                            (p[0] - corner[0]) as f32,
                            (p[1] - corner[1]) as f32,
                            p[2] as f32,
                        ]
                    })
                    .collect();
                // Sorted by the voxel of the stored point (which rounding can move across a
                // voxel face), at most N a voxel.
                let kept = arrange_tile(&header, key, &mut off);
                off.truncate(kept);
                (key, off)
            })
            .collect();
        let most = offsets.iter().map(|(_, o)| o.len()).max().unwrap_or(0);
        ensure!(
            most <= MAX_TILE_POINTS as usize,
            "a tile holds {most} points, more than a file's {MAX_TILE_POINTS}: use smaller tiles"
        );
        header.tile_points = most.max(1) as u32;
        let refs: Vec<(TileKey, &[[f32; 3]])> =
            offsets.iter().map(|(k, o)| (*k, o.as_slice())).collect();
        let mut bytes = vec![0u8; header.file_len()];
        if !encode_map(&header, &refs, &mut bytes) {
            bail!("the map's tiles could not be encoded (a bug)");
        }
        let stats = MapStats {
            points_in: self.points_in,
            points_kept: offsets.iter().map(|(_, o)| o.len()).sum(),
            voxels: self.map.voxels(),
            tiles: offsets.len(),
            extent: [hi[0] - lo[0], hi[1] - lo[1]],
            bytes: bytes.len(),
        };
        Ok((bytes, stats))
    }

    /// Points the map can take now whatever they are: each may need a voxel and a block, and
    /// a voxel of `c` points holds at most `(c + BLOCK - 1) / BLOCK` blocks.
    fn room(&self) -> usize {
        let (voxels, points) = (self.map.voxels(), self.map.points());
        let blocks = self.point_capacity.div_ceil(BLOCK);
        let used = (points + (BLOCK - 1) * voxels).div_ceil(BLOCK);
        let free_voxels = self.voxel_capacity.saturating_sub(voxels);
        free_voxels.min(blocks.saturating_sub(used))
    }

    /// Moves the points to a map twice as large; they were admitted together, so every one
    /// is admitted again.
    fn grow(&mut self) -> Result<()> {
        let (voxels, points) = (self.voxel_capacity * 2, self.point_capacity * 2);
        let mut map = empty_map(&self.params, voxels, points)?;
        let mut old = Vec::with_capacity(self.map.points());
        self.map.view().for_each_point(|_, p| old.push(p));
        let st = map.add_points(old.into_iter());
        ensure!(
            map.points() == self.map.points() && st.dropped_voxels + st.dropped_points == 0,
            "the grown map kept {} of {} points (a bug)",
            map.points(),
            self.map.points()
        );
        self.map = map;
        self.voxel_capacity = voxels;
        self.point_capacity = points;
        Ok(())
    }
}

fn empty_map(
    params: &MapParams,
    voxels: usize,
    points: usize,
) -> Result<LocalMap<f64, Exact, Vec<u64>>> {
    let words = LocalMap::<f64, Exact, Vec<u64>>::words(voxels, points);
    LocalMap::new(
        params.voxel_size,
        NO_RADIUS,
        params.points_per_voxel,
        voxels,
        points,
        vec![0u64; words],
    )
    .map_err(|e| anyhow::anyhow!("a map of {voxels} voxels and {points} points: {e}"))
}

#[cfg(test)]
mod tests;
