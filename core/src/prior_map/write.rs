//! Writing a map file: the header, the index entries, a tile's points arranged as a record
//! needs, and the whole file. No allocator: the caller gives the bytes to fill.

use super::*;

impl Header {
    /// The header's bytes, the index's CRC given.
    pub fn encode(&self, index_crc: u32) -> [u8; HEADER_LEN] {
        let mut h = [0u8; HEADER_LEN];
        h[..8].copy_from_slice(&MAGIC);
        h[VERSION_AT].copy_from_slice(&VERSION.to_le_bytes());
        h[VOXEL_AT].copy_from_slice(&self.voxel_size.to_le_bytes());
        h[TILE_AT].copy_from_slice(&self.tile_size.to_le_bytes());
        h[PER_VOXEL_AT].copy_from_slice(&self.points_per_voxel.to_le_bytes());
        h[CAPACITY_AT].copy_from_slice(&self.tile_points.to_le_bytes());
        h[TILES_AT].copy_from_slice(&self.tiles.to_le_bytes());
        h[INDEX_CRC_AT].copy_from_slice(&index_crc.to_le_bytes());
        h[FRAME_AT].copy_from_slice(&self.frame);
        let crc = crc32(&h[..HEADER_CRC_AT.start]);
        h[HEADER_CRC_AT].copy_from_slice(&crc.to_le_bytes());
        h
    }
}

/// An index entry's bytes.
pub fn encode_index_entry(key: TileKey, points: u32) -> [u8; INDEX_ENTRY_LEN] {
    let mut e = [0u8; INDEX_ENTRY_LEN];
    e[0..4].copy_from_slice(&key.i.to_le_bytes());
    e[4..8].copy_from_slice(&key.j.to_le_bytes());
    e[8..12].copy_from_slice(&points.to_le_bytes());
    e
}

/// Writes tile `key`'s record into `out` (exactly [`Header::record_len`] bytes) from its points'
/// offsets from the tile's corner. Returns `false`, writing nothing, if `out` has the wrong
/// length or there are more points than it holds.
pub fn encode_record(key: TileKey, offsets: &[[f32; 3]], out: &mut [u8]) -> bool {
    let capacity = out.len().saturating_sub(RECORD_HEAD_LEN) / POINT_LEN;
    if out.len() != RECORD_HEAD_LEN + capacity * POINT_LEN || offsets.len() > capacity {
        return false;
    }
    out.fill(0);
    out[..8].copy_from_slice(&encode_index_entry(key, 0)[..8]);
    out[8..12].copy_from_slice(&(offsets.len() as u32).to_le_bytes());
    for (p, o) in out[RECORD_HEAD_LEN..]
        .chunks_exact_mut(POINT_LEN)
        .zip(offsets)
    {
        for (b, c) in p.chunks_exact_mut(4).zip(o) {
            b.copy_from_slice(&c.to_le_bytes());
        }
    }
    let crc = record_crc(out);
    out[12..16].copy_from_slice(&crc.to_le_bytes());
    true
}

/// Puts tile `key`'s points (offsets from its corner) in the order a record needs, in place:
/// sorted by voxel and then by coordinates, at most `N` a voxel (the first by coordinates),
/// without points that are not finite, leave the tile's square or whose voxel lies in another
/// tile (within rounding of a tile edge). Returns how many are kept, at the front.
pub fn arrange_tile(header: &Header, key: TileKey, offsets: &mut [[f32; 3]]) -> usize {
    let s = header.tile_size as f32;
    let ratio = header.voxels_per_tile();
    let probe = Tile {
        key,
        corner: [
            f64::from(key.i) * header.tile_size,
            f64::from(key.j) * header.tile_size,
        ],
        voxel: header.voxel_size,
        points: &[],
    };
    let voxel = |o: &[f32; 3]| {
        let p = probe.at(*o);
        point_to_voxel(&Point::new(p[0], p[1], p[2]), header.voxel_size)
    };
    let fits = |o: &[f32; 3]| {
        let inside = (0.0..=s).contains(&o[0]) && (0.0..=s).contains(&o[1]) && o[2].is_finite();
        let v = voxel(o);
        inside && v[0].div_euclid(ratio) == key.i && v[1].div_euclid(ratio) == key.j
    };
    let mut kept = 0;
    for k in 0..offsets.len() {
        if fits(&offsets[k]) {
            offsets.swap(kept, k);
            kept += 1;
        }
    }
    let live = &mut offsets[..kept];
    live.sort_unstable_by(|a, b| {
        let c = |k: usize| a[k].total_cmp(&b[k]);
        voxel(a).cmp(&voxel(b)).then(c(0)).then(c(1)).then(c(2))
    });
    let (mut out, mut run) = (0, 0);
    for k in 0..kept {
        run = if k > 0 && voxel(&live[k]) == voxel(&live[k - 1]) {
            run + 1
        } else {
            1
        };
        if run <= header.points_per_voxel {
            live[out] = live[k];
            out += 1;
        }
    }
    out
}

/// Writes a whole map file into `out` (exactly [`Header::file_len`] bytes): `header` (its
/// `tiles` must be `tiles.len()`) and `tiles`, sorted by key, each with its points' offsets
/// from its corner. Returns `false`, with `out` unspecified, if the lengths disagree, the tiles
/// are not sorted or one has more points than a record holds.
pub fn encode_map(header: &Header, tiles: &[(TileKey, &[[f32; 3]])], out: &mut [u8]) -> bool {
    if out.len() != header.file_len() || tiles.len() != header.tiles as usize {
        return false;
    }
    if tiles.windows(2).any(|w| w[0].0 >= w[1].0) {
        return false;
    }
    let (head, rest) = out.split_at_mut(HEADER_LEN);
    let (index, records) = rest.split_at_mut(tiles.len() * INDEX_ENTRY_LEN);
    let len = header.record_len();
    for (t, (key, offsets)) in tiles.iter().enumerate() {
        let e = encode_index_entry(*key, offsets.len() as u32);
        index[t * INDEX_ENTRY_LEN..(t + 1) * INDEX_ENTRY_LEN].copy_from_slice(&e);
        if !encode_record(*key, offsets, &mut records[t * len..(t + 1) * len]) {
            return false;
        }
    }
    head.copy_from_slice(&header.encode(crc32(index)));
    true
}
