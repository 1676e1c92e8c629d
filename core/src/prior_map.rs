//! The prior map file: square tiles of voxelized points, read from a byte slice (flash, a
//! memory-mapped file) without an allocator.
//!
//! All fields are little-endian. The file is a header, an index and the tile records:
//!
//! | bytes | field |
//! |---|---|
//! | header `0..8` | magic `KOMAP\0\0\0` |
//! | `8..12` | version, `u32` (2) |
//! | `12..16` | zero |
//! | `16..24` | voxel size `v` (m), `f64`: the map's points were kept at most `N` per voxel |
//! | `24..32` | tile edge `s` (m), `f64`, a whole multiple of `v`, so each voxel is in one tile |
//! | `32..36` | `N`, points per voxel at most, `u32` |
//! | `36..40` | record capacity: points per tile record, `u32` |
//! | `40..44` | tiles, `u32` |
//! | `44..48` | CRC-32 of the index |
//! | `48..64` | the map frame's name, ASCII, zero-padded |
//! | `64..124` | zero |
//! | `124..128` | CRC-32 of bytes `0..124` |
//! | index, 12 bytes a tile | tile column `i`, row `j` (`i32`), points (`u32`); sorted by `(i, j)` |
//! | records, `16 + 12 capacity` bytes each, in index order | `i`, `j`, points, CRC-32 of the record but these 4 bytes; then `capacity` points `x, y, z` (`f32`, from the tile's corner `(i s, j s, 0)`), unused ones zero |
//!
//! Tile `(i, j)` covers `[i s, (i + 1) s) x [j s, (j + 1) s)` of the map frame's `x, y`. A
//! point's voxel is `floor(p / v)` of its map-frame coordinates (`f64`: the corner plus the
//! stored offset); a tile's points are sorted by voxel (`x`, then `y`, then `z`), at most `N` a
//! voxel, and each voxel lies in its tile (`floor(key_x / (s / v)) = i`, alike for `j`). So a
//! voxel's points are one run of its tile's record, found by a binary search in place: the map
//! is never copied into memory.
//!
//! The header and the index are checked when the file is opened ([`TileMap::open`]), a tile's
//! CRC and order when it is read ([`TileMap::tile`]): a damaged tile is refused alone, the rest
//! stays usable.

mod crc;
mod write;

pub use crc::{crc32, Crc32};
pub use write::{arrange_tile, encode_index_entry, encode_map, encode_record};

use crate::geometry::Point;
use crate::scalar::Real;
use crate::voxel::{point_to_voxel, VoxelKey};
use core::ops::Range;

/// The first eight bytes of a map file.
pub const MAGIC: [u8; 8] = *b"KOMAP\0\0\0";
/// The format version this reader knows.
pub const VERSION: u32 = 2;
/// Header bytes.
pub const HEADER_LEN: usize = 128;
/// Index bytes per tile.
pub const INDEX_ENTRY_LEN: usize = 12;
/// A record's bytes before its points.
pub const RECORD_HEAD_LEN: usize = 16;
/// Bytes per stored point.
pub const POINT_LEN: usize = 12;
/// Bytes of the frame name.
pub const FRAME_LEN: usize = 16;
/// Most points a tile record may hold.
pub const MAX_TILE_POINTS: u32 = 1 << 24;
/// Most tiles a file may hold.
pub const MAX_TILES: u32 = 1 << 24;

const VERSION_AT: Range<usize> = 8..12;
const PAD_AT: Range<usize> = 12..16;
const VOXEL_AT: Range<usize> = 16..24;
const TILE_AT: Range<usize> = 24..32;
const PER_VOXEL_AT: Range<usize> = 32..36;
const CAPACITY_AT: Range<usize> = 36..40;
const TILES_AT: Range<usize> = 40..44;
const INDEX_CRC_AT: Range<usize> = 44..48;
const FRAME_AT: Range<usize> = 48..64;
const RESERVED_AT: Range<usize> = 64..124;
const HEADER_CRC_AT: Range<usize> = 124..128;

/// Why a map file cannot be used at all.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MapError {
    /// Shorter than its header, index and records say: a truncated copy.
    Truncated,
    /// Longer than its header, index and records say: not one map file.
    TrailingBytes,
    /// Not a map file (the first eight bytes).
    Magic,
    /// A version this reader does not know.
    Version,
    /// The header's CRC does not match: the header is damaged.
    HeaderChecksum,
    /// The index's CRC does not match: the index is damaged.
    IndexChecksum,
    /// A header field is out of range: voxel size or tile edge not positive and finite, the
    /// tile edge not a whole multiple of the voxel size, `N` not in `1..=255`, a count too
    /// large, reserved bytes not zero or a frame name that is not ASCII.
    Header,
    /// The index is not sorted by `(i, j)` or names a tile twice.
    IndexOrder,
    /// An index entry holds more points than a record can.
    TilePoints,
}

/// Why one tile cannot be used (the others still can).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TileError {
    /// The record's CRC does not match its bytes.
    Checksum,
    /// The record names another tile or point count than the index.
    Mismatch,
    /// No such tile: the index is shorter.
    Missing,
    /// A point is not finite or lies outside its tile.
    Points,
    /// The points are not sorted by voxel, a voxel holds more than `N` or lies in another
    /// tile.
    Order,
}

impl core::fmt::Display for MapError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Truncated => "the map file is shorter than its header and index say (truncated)",
            Self::TrailingBytes => "the map file has bytes after its last tile record",
            Self::Magic => "not a kiss-odom map file (wrong magic bytes)",
            Self::Version => "a map file version this build does not read",
            Self::HeaderChecksum => "the map file's header is damaged (checksum)",
            Self::IndexChecksum => "the map file's tile index is damaged (checksum)",
            Self::Header => "a map file header field is out of range",
            Self::IndexOrder => "the map file's tile index is not sorted or names a tile twice",
            Self::TilePoints => "a tile index entry holds more points than a record can",
        })
    }
}

impl core::fmt::Display for TileError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Checksum => "the tile's checksum does not match (damaged)",
            Self::Mismatch => "the tile record disagrees with the index",
            Self::Missing => "no such tile in the index",
            Self::Points => "a tile point is not finite or lies outside its tile",
            Self::Order => "a tile's points are not sorted by voxel, or a voxel is too full",
        })
    }
}

/// What the header says.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Header {
    /// Voxel size `v` (m).
    pub voxel_size: f64,
    /// Tile edge `s` (m).
    pub tile_size: f64,
    /// Points per voxel at most, `N`.
    pub points_per_voxel: u32,
    /// Points a tile record holds.
    pub tile_points: u32,
    /// Tiles in the file.
    pub tiles: u32,
    /// The map frame's name, zero-padded ASCII.
    pub frame: [u8; FRAME_LEN],
}

/// A tile's place in the grid and its point count.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct TileKey {
    /// Column: the tile covers `x` in `[i s, (i + 1) s)`.
    pub i: i32,
    /// Row: `y` in `[j s, (j + 1) s)`.
    pub j: i32,
}

impl TileKey {
    /// The tile holding map-frame `(x, y)` for tile edge `s` (saturating far outside `i32`).
    pub fn of(x: f64, y: f64, s: f64) -> Self {
        Self {
            i: libm::floor(x / s) as i32,
            j: libm::floor(y / s) as i32,
        }
    }
}

impl Header {
    /// The frame name without its padding (empty if not ASCII).
    pub fn frame_name(&self) -> &str {
        let end = self.frame.iter().position(|&b| b == 0).unwrap_or(FRAME_LEN);
        core::str::from_utf8(&self.frame[..end]).unwrap_or("")
    }

    /// A frame name field for `name`, or `None` if it is not ASCII of at most 16 bytes.
    pub fn frame_field(name: &str) -> Option<[u8; FRAME_LEN]> {
        let b = name.as_bytes();
        if b.len() > FRAME_LEN || !name.is_ascii() || b.contains(&0) {
            return None;
        }
        let mut f = [0u8; FRAME_LEN];
        f[..b.len()].copy_from_slice(b);
        Some(f)
    }

    /// Voxels along a tile's edge, `s / v` (a whole number, checked when the file is opened).
    pub fn voxels_per_tile(&self) -> i32 {
        libm::round(self.tile_size / self.voxel_size) as i32
    }

    /// Bytes of one tile record.
    pub fn record_len(&self) -> usize {
        RECORD_HEAD_LEN + POINT_LEN * self.tile_points as usize
    }

    /// Bytes of the whole file.
    pub fn file_len(&self) -> usize {
        let n = self.tiles as usize;
        HEADER_LEN + n * INDEX_ENTRY_LEN + n * self.record_len()
    }

    /// Whether every field is in range (see [`MapError::Header`]).
    fn valid(&self) -> bool {
        let (v, s) = (self.voxel_size, self.tile_size);
        let ratio = s / v;
        v.is_finite()
            && v > 0.0
            && s.is_finite()
            && s >= v
            && s <= 1e5
            && libm::fabs(ratio - libm::round(ratio)) <= 1e-9 * ratio
            && (1..=255).contains(&self.points_per_voxel)
            && (1..=MAX_TILE_POINTS).contains(&self.tile_points)
            && self.tiles <= MAX_TILES
            && self.frame.is_ascii()
    }
}

/// A record's CRC: every byte but the CRC's own four.
fn record_crc(record: &[u8]) -> u32 {
    Crc32::new()
        .update(&record[..12])
        .update(&record[RECORD_HEAD_LEN..])
        .value()
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    let mut w = [0u8; 4];
    w.copy_from_slice(&b[at..at + 4]);
    u32::from_le_bytes(w)
}

fn f64_at(b: &[u8], at: usize) -> f64 {
    let mut w = [0u8; 8];
    w.copy_from_slice(&b[at..at + 8]);
    f64::from_le_bytes(w)
}

/// A map file opened in place: its header and index checked, tiles read on demand.
#[derive(Clone, Copy, Debug)]
pub struct TileMap<'a> {
    header: Header,
    index: &'a [u8],
    records: &'a [u8],
}

impl<'a> TileMap<'a> {
    /// Checks the header and the index of the map file in `bytes` (see [`MapError`]).
    pub fn open(bytes: &'a [u8]) -> Result<Self, MapError> {
        let h = bytes.get(..HEADER_LEN).ok_or(MapError::Truncated)?;
        if h[..8] != MAGIC {
            return Err(MapError::Magic);
        }
        if u32_at(h, HEADER_CRC_AT.start) != crc32(&h[..HEADER_CRC_AT.start]) {
            return Err(MapError::HeaderChecksum);
        }
        if u32_at(h, VERSION_AT.start) != VERSION {
            return Err(MapError::Version);
        }
        let mut frame = [0u8; FRAME_LEN];
        frame.copy_from_slice(&h[FRAME_AT]);
        let header = Header {
            voxel_size: f64_at(h, VOXEL_AT.start),
            tile_size: f64_at(h, TILE_AT.start),
            points_per_voxel: u32_at(h, PER_VOXEL_AT.start),
            tile_points: u32_at(h, CAPACITY_AT.start),
            tiles: u32_at(h, TILES_AT.start),
            frame,
        };
        let reserved_zero = h[PAD_AT].iter().chain(&h[RESERVED_AT]).all(|&b| b == 0);
        if !header.valid() || !reserved_zero {
            return Err(MapError::Header);
        }
        let n = header.tiles as usize;
        let index_end = HEADER_LEN + n * INDEX_ENTRY_LEN;
        if bytes.len() < header.file_len() {
            return Err(MapError::Truncated);
        }
        if bytes.len() > header.file_len() {
            return Err(MapError::TrailingBytes);
        }
        let index = &bytes[HEADER_LEN..index_end];
        if crc32(index) != u32_at(h, INDEX_CRC_AT.start) {
            return Err(MapError::IndexChecksum);
        }
        let map = Self {
            header,
            index,
            records: &bytes[index_end..],
        };
        for t in 0..n {
            let (key, points) = map.entry_at(t);
            if points > header.tile_points {
                return Err(MapError::TilePoints);
            }
            if t > 0 && map.entry_at(t - 1).0 >= key {
                return Err(MapError::IndexOrder);
            }
        }
        Ok(map)
    }

    /// The header.
    pub fn header(&self) -> &Header {
        &self.header
    }

    /// Tiles in the file.
    pub fn len(&self) -> usize {
        self.header.tiles as usize
    }

    /// Whether the file holds no tile.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Index entry `t`: its tile and point count (`None` past the last tile).
    pub fn entry(&self, t: usize) -> Option<(TileKey, u32)> {
        (t < self.len()).then(|| self.entry_at(t))
    }

    /// Index entry `t < len()`.
    fn entry_at(&self, t: usize) -> (TileKey, u32) {
        let e = &self.index[t * INDEX_ENTRY_LEN..(t + 1) * INDEX_ENTRY_LEN];
        let key = TileKey {
            i: u32_at(e, 0) as i32,
            j: u32_at(e, 4) as i32,
        };
        (key, u32_at(e, 8))
    }

    /// The index position of tile `key`, if the file has it (a binary search).
    pub fn find(&self, key: TileKey) -> Option<usize> {
        let (mut lo, mut hi) = (0, self.len());
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            match self.entry_at(mid).0.cmp(&key) {
                core::cmp::Ordering::Less => lo = mid + 1,
                core::cmp::Ordering::Greater => hi = mid,
                core::cmp::Ordering::Equal => return Some(mid),
            }
        }
        None
    }

    /// Tile `t`'s points, its record checked against its CRC and the index.
    pub fn tile(&self, t: usize) -> Result<Tile<'a>, TileError> {
        let (key, points) = self.entry(t).ok_or(TileError::Missing)?;
        let len = self.header.record_len();
        let record = &self.records[t * len..(t + 1) * len];
        if u32_at(record, 12) != record_crc(record) {
            return Err(TileError::Checksum);
        }
        let named = (u32_at(record, 0) as i32, u32_at(record, 4) as i32);
        if named != (key.i, key.j) || u32_at(record, 8) != points {
            return Err(TileError::Mismatch);
        }
        let end = RECORD_HEAD_LEN + POINT_LEN * points as usize;
        let s = self.header.tile_size as f32;
        let tile = Tile {
            key,
            corner: [
                f64::from(key.i) * self.header.tile_size,
                f64::from(key.j) * self.header.tile_size,
            ],
            voxel: self.header.voxel_size,
            points: &record[RECORD_HEAD_LEN..end],
        };
        let inside = tile
            .offsets()
            .all(|[x, y, z]| (0.0..=s).contains(&x) && (0.0..=s).contains(&y) && z.is_finite());
        if !inside {
            return Err(TileError::Points);
        }
        let ratio = self.header.voxels_per_tile();
        let mut run = (None, 0u32);
        for k in 0..tile.len() {
            let v = tile.voxel_at(k);
            let home = TileKey {
                i: v[0].div_euclid(ratio),
                j: v[1].div_euclid(ratio),
            };
            run = match run {
                (Some(last), n) if last == v => (Some(v), n + 1),
                (Some(last), _) if last > v => return Err(TileError::Order),
                _ => (Some(v), 1),
            };
            if home != key || run.1 > self.header.points_per_voxel {
                return Err(TileError::Order);
            }
        }
        Ok(tile)
    }
}

/// One tile's points, checked.
#[derive(Clone, Copy, Debug)]
pub struct Tile<'a> {
    /// Its place in the grid.
    pub key: TileKey,
    corner: [f64; 2],
    voxel: f64,
    points: &'a [u8],
}

impl Tile<'_> {
    /// Points stored.
    pub fn len(&self) -> usize {
        self.points.len() / POINT_LEN
    }

    /// Whether the tile holds no point.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The points in the map frame, in stored order.
    pub fn points(&self) -> impl Iterator<Item = [f64; 3]> + '_ {
        (0..self.len()).map(|k| self.point(k))
    }

    /// Point `k < len()` in the map frame.
    #[inline]
    pub fn point(&self, k: usize) -> [f64; 3] {
        let p = &self.points[k * POINT_LEN..(k + 1) * POINT_LEN];
        let c = |at: usize| f32::from_le_bytes([p[at], p[at + 1], p[at + 2], p[at + 3]]);
        self.at([c(0), c(4), c(8)])
    }

    /// An offset from the tile's corner in the map frame.
    #[inline]
    fn at(&self, o: [f32; 3]) -> [f64; 3] {
        [
            self.corner[0] + f64::from(o[0]),
            self.corner[1] + f64::from(o[1]),
            f64::from(o[2]),
        ]
    }

    /// The voxel of point `k < len()`.
    #[inline]
    pub fn voxel_at(&self, k: usize) -> VoxelKey {
        let [x, y, z] = self.point(k);
        point_to_voxel(&Point::new(x, y, z), self.voxel)
    }

    /// The points of voxel `key`, a range of indices (empty if it holds none): a binary
    /// search, the record sorted by voxel.
    pub fn voxel(&self, key: &VoxelKey) -> Range<usize> {
        let (mut lo, mut hi) = (0, self.len());
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            if self.voxel_cmp(mid, key).is_lt() {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        let mut end = lo;
        while end < self.len() && self.voxel_cmp(end, key).is_eq() {
            end += 1;
        }
        lo..end
    }

    /// The voxel of point `k` against `key`, as [`Self::voxel_at`] would compare, an axis at a
    /// time (most points differ in `x` already).
    #[inline]
    fn voxel_cmp(&self, k: usize, key: &VoxelKey) -> core::cmp::Ordering {
        let p = self.point(k);
        for (c, want) in p.iter().zip(key) {
            let o = (c / self.voxel).floor_i32().cmp(want);
            if o.is_ne() {
                return o;
            }
        }
        core::cmp::Ordering::Equal
    }

    /// The points as stored: offsets from the tile's corner.
    fn offsets(&self) -> impl Iterator<Item = [f32; 3]> + '_ {
        self.points.chunks_exact(POINT_LEN).map(|p| {
            let c = |k: usize| f32::from_le_bytes([p[k], p[k + 1], p[k + 2], p[k + 3]]);
            [c(0), c(4), c(8)]
        })
    }
}

#[cfg(test)]
mod tests;
