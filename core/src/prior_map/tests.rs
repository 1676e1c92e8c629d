use super::*;
use std::vec;
use std::vec::Vec;

fn header(tiles: u32) -> Header {
    Header {
        voxel_size: 1.0,
        tile_size: 50.0,
        points_per_voxel: 4,
        tile_points: 3,
        tiles,
        frame: Header::frame_field("site").unwrap(),
    }
}

/// Three tiles: one empty, one full, one of a point, at negative and positive keys.
fn sample() -> (Header, Vec<u8>) {
    let a = [[0.5f32, 1.25, -0.5], [10.0, 20.0, 3.0], [49.9, 0.0, 2.0]];
    let b = [[1.0f32, 2.0, 3.0]];
    let tiles: [(TileKey, &[[f32; 3]]); 3] = [
        (TileKey { i: -2, j: 7 }, &a),
        (TileKey { i: -2, j: 8 }, &[]),
        (TileKey { i: 3, j: -1 }, &b),
    ];
    let h = header(3);
    let mut out = vec![0u8; h.file_len()];
    assert!(encode_map(&h, &tiles, &mut out));
    (h, out)
}

#[test]
fn a_written_map_reads_back_tile_by_tile() {
    let (h, bytes) = sample();
    let map = TileMap::open(&bytes).unwrap();
    assert_eq!(*map.header(), h);
    assert_eq!(map.header().frame_name(), "site");
    assert_eq!(map.len(), 3);
    let t = map.find(TileKey { i: -2, j: 7 }).unwrap();
    let pts: Vec<[f64; 3]> = map.tile(t).unwrap().points().collect();
    assert_eq!(pts[0], [-100.0 + 0.5, 350.0 + 1.25, -0.5]);
    assert_eq!(pts[2], [-100.0 + f64::from(49.9f32), 350.0, 2.0]);
    assert_eq!(pts.len(), 3);
    assert!(map
        .tile(map.find(TileKey { i: -2, j: 8 }).unwrap())
        .unwrap()
        .is_empty());
    let t = map.find(TileKey { i: 3, j: -1 }).unwrap();
    assert_eq!(
        map.tile(t).unwrap().points().next(),
        Some([151.0, -48.0, 3.0])
    );
    assert_eq!(map.find(TileKey { i: 3, j: 0 }), None);
    assert_eq!(map.find(TileKey { i: -3, j: 7 }), None);
    assert_eq!(TileKey::of(-100.0, 399.99, 50.0), TileKey { i: -2, j: 7 });
    assert_eq!(TileKey::of(-100.01, 400.0, 50.0), TileKey { i: -3, j: 8 });
}

#[test]
fn every_damaged_header_or_index_byte_is_refused_and_a_damaged_record_only_loses_its_tile() {
    let (h, bytes) = sample();
    let index_end = HEADER_LEN + 3 * INDEX_ENTRY_LEN;
    for at in 0..bytes.len() {
        let mut bad = bytes.clone();
        bad[at] ^= 0x10;
        match TileMap::open(&bad) {
            Err(e) => assert!(at < index_end, "byte {at}: {e}"),
            Ok(map) => {
                assert!(
                    at >= index_end,
                    "byte {at} of the header or index was accepted"
                );
                let t = (at - index_end) / h.record_len();
                let damaged = map.tile(t).err();
                assert!(
                    damaged.is_some(),
                    "byte {at}: tile {t} read although damaged"
                );
                for other in (0..3).filter(|&o| o != t) {
                    assert!(map.tile(other).is_ok(), "byte {at} broke tile {other}");
                }
            }
        }
    }
}

#[test]
fn a_truncated_or_extended_file_is_refused_saying_so() {
    let (_, bytes) = sample();
    for len in 0..bytes.len() {
        let e = TileMap::open(&bytes[..len]).unwrap_err();
        assert!(len < 8 || e == MapError::Truncated, "length {len}: {e:?}");
    }
    let mut long = bytes.clone();
    long.push(0);
    assert_eq!(TileMap::open(&long).unwrap_err(), MapError::TrailingBytes);
}

#[test]
fn an_unsorted_index_and_out_of_range_fields_are_refused_naming_them() {
    let a = [[0.0f32; 3]];
    let tiles: [(TileKey, &[[f32; 3]]); 2] =
        [(TileKey { i: 1, j: 0 }, &a), (TileKey { i: 0, j: 5 }, &a)];
    let h = header(2);
    let mut out = vec![0u8; h.file_len()];
    assert!(
        !encode_map(&h, &tiles, &mut out),
        "the writer sorts nothing"
    );
    // Swap two sorted entries by hand, with valid checksums.
    let sorted = [tiles[1], tiles[0]];
    assert!(encode_map(&h, &sorted, &mut out));
    let (e0, e1) = (HEADER_LEN, HEADER_LEN + INDEX_ENTRY_LEN);
    let first: Vec<u8> = out[e0..e1].to_vec();
    out.copy_within(e1..e1 + INDEX_ENTRY_LEN, e0);
    out[e1..e1 + INDEX_ENTRY_LEN].copy_from_slice(&first);
    let fixed = h.encode(crc32(&out[e0..e1 + INDEX_ENTRY_LEN]));
    out[..HEADER_LEN].copy_from_slice(&fixed);
    assert_eq!(TileMap::open(&out).unwrap_err(), MapError::IndexOrder);

    for bad in [
        Header {
            tile_size: 50.5,
            ..h
        },
        Header {
            voxel_size: 0.0,
            ..h
        },
        Header {
            voxel_size: f64::NAN,
            ..h
        },
        Header {
            points_per_voxel: 0,
            ..h
        },
        Header {
            points_per_voxel: 256,
            ..h
        },
        Header {
            tile_points: 0,
            ..h
        },
    ] {
        let mut out = vec![0u8; bad.file_len()];
        out[..HEADER_LEN].copy_from_slice(&bad.encode(0));
        assert_eq!(
            TileMap::open(&out).unwrap_err(),
            MapError::Header,
            "{bad:?}"
        );
    }
    assert_eq!(Header::frame_field("a name of more than 16"), None);
    // Points outside their tile or not finite, with valid checksums, are refused by the tile.
    for bad in [[50.5f32, 1.0, 0.0], [-0.1, 1.0, 0.0], [1.0, 1.0, f32::NAN]] {
        let tiles: [(TileKey, &[[f32; 3]]); 1] = [(TileKey { i: 0, j: 0 }, &[bad])];
        let h = Header {
            tile_points: 1,
            tiles: 1,
            ..header(1)
        };
        let mut out = vec![0u8; h.file_len()];
        assert!(encode_map(&h, &tiles, &mut out));
        let map = TileMap::open(&out).unwrap();
        assert_eq!(map.tile(0).unwrap_err(), TileError::Points, "{bad:?}");
        assert_eq!(map.tile(1).unwrap_err(), TileError::Missing);
    }
    assert_eq!(Header::frame_field("caf\u{e9}"), None);
}

#[test]
fn a_tile_out_of_voxel_order_or_too_full_is_refused_and_arranging_fixes_it() {
    let h = Header {
        points_per_voxel: 2,
        tile_points: 6,
        tiles: 1,
        ..header(1)
    };
    let key = TileKey { i: -1, j: 2 };
    let encode = |pts: &[[f32; 3]]| {
        let mut out = vec![0u8; h.file_len()];
        assert!(encode_map(&h, &[(key, pts)], &mut out));
        out
    };
    // Voxels (-40, 110, 0) and (-50, 100, 0): out of order.
    let unsorted = [[10.5f32, 10.5, 0.5], [0.5, 0.5, 0.5]];
    let bytes = encode(&unsorted);
    assert_eq!(
        TileMap::open(&bytes).unwrap().tile(0).unwrap_err(),
        TileError::Order
    );
    // Three points in one voxel where N is 2.
    let crowded = [[0.1f32, 0.1, 0.1], [0.2, 0.2, 0.2], [0.3, 0.3, 0.3]];
    let bytes = encode(&crowded);
    assert_eq!(
        TileMap::open(&bytes).unwrap().tile(0).unwrap_err(),
        TileError::Order
    );
    // Arranged: sorted, the voxel trimmed to its first two by coordinates, the point outside
    // the tile left out; each voxel's run found in place.
    let mut pts = vec![
        [10.5f32, 10.5, 0.5],
        [0.3, 0.3, 0.3],
        [60.0, 1.0, 1.0],
        [0.1, 0.1, 0.1],
        [0.2, 0.2, 0.2],
        [0.5, 0.5, -0.5],
    ];
    let kept = arrange_tile(&h, key, &mut pts);
    assert_eq!(kept, 4);
    let bytes = encode(&pts[..kept]);
    let map = TileMap::open(&bytes).unwrap();
    let tile = map.tile(0).unwrap();
    assert_eq!(tile.voxel(&[-50, 100, -1]), 0..1);
    assert_eq!(tile.voxel(&[-50, 100, 0]), 1..3);
    assert_eq!(
        tile.point(1),
        [
            -50.0 + f64::from(0.1f32),
            100.0 + f64::from(0.1f32),
            f64::from(0.1f32)
        ]
    );
    assert_eq!(tile.voxel(&[-40, 110, 0]), 3..4);
    assert!(tile.voxel(&[-41, 110, 0]).is_empty());
    assert!(tile.voxel(&[-30, 110, 0]).is_empty());
}
