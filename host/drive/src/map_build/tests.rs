use super::*;
use kiss_odom_core::prior_map::TileMap;
use std::collections::HashMap;

/// A small deterministic generator (SplitMix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn params(voxel_size: f64, tile_size: f64, points_per_voxel: u32) -> MapParams {
    MapParams {
        voxel_size,
        tile_size,
        points_per_voxel,
        frame: "map".into(),
    }
}

/// `n` points in `[-12, 12) x [-12, 12) x [-2, 2)` (several tiles of 4 m on each side of the
/// origin), clustered so many voxels get more than `N` candidates, and at least 1e-3 m from
/// every voxel face of size 1, so the stored `f32` offsets stay in their voxel.
fn cloud(seed: u64, n: usize) -> Vec<[f64; 3]> {
    let mut rng = Rng(seed);
    let coord = |lo: f64, cells: f64, rng: &mut Rng| {
        let cell = lo + (rng.unit() * cells).floor();
        cell + 1e-3 + 0.998 * rng.unit()
    };
    (0..n)
        .map(|k| {
            // Every third point lands in a 4 x 4 x 2 m block, the rest anywhere.
            let (lo, cells) = if k % 3 == 0 {
                ([1.0, -3.0, 0.0], [4.0, 4.0, 2.0])
            } else {
                ([-12.0, -12.0, -2.0], [24.0, 24.0, 4.0])
            };
            [
                coord(lo[0], cells[0], &mut rng),
                coord(lo[1], cells[1], &mut rng),
                coord(lo[2], cells[2], &mut rng),
            ]
        })
        .collect()
}

fn build(p: MapParams, voxels: usize, points: usize, batches: &[&[[f64; 3]]]) -> Vec<u8> {
    let mut b = MapBuilder::with_capacity(p, voxels, points).unwrap();
    for batch in batches {
        b.add(batch).unwrap();
    }
    b.encode().unwrap().0
}

fn voxel_of(p: &[f64; 3], v: f64) -> [i64; 3] {
    p.map(|c| (c / v).floor() as i64)
}

#[test]
fn the_file_reads_back_with_every_input_point_near_a_stored_one_and_n_at_most_a_voxel() {
    let (v, s, n) = (1.0, 4.0, 5);
    let input = cloud(7, 40_000);
    let mut b = MapBuilder::new(params(v, s, n)).unwrap();
    b.add(&input).unwrap();
    let (bytes, stats) = b.encode().unwrap();
    let map = TileMap::open(&bytes).unwrap();
    let h = map.header();
    assert_eq!((h.voxel_size, h.tile_size, h.points_per_voxel), (v, s, n));
    assert_eq!((h.frame_name(), map.len()), ("map", stats.tiles));
    assert_eq!(stats.bytes, bytes.len());
    assert_eq!(stats.points_in, input.len());
    let mut stored: HashMap<[i64; 3], Vec<[f64; 3]>> = HashMap::new();
    let mut most = 0;
    for t in 0..map.len() {
        let tile = map.tile(t).unwrap();
        most = most.max(tile.len());
        for p in tile.points() {
            let (i, j) = (tile.key.i as f64, tile.key.j as f64);
            assert!(
                (i * s..(i + 1.0) * s).contains(&p[0]) && (j * s..(j + 1.0) * s).contains(&p[1]),
                "{p:?} outside tile {:?}",
                tile.key
            );
            stored.entry(voxel_of(&p, v)).or_default().push(p);
        }
    }
    assert_eq!(
        h.tile_points as usize, most,
        "record capacity = largest tile"
    );
    let kept: usize = stored.values().map(Vec::len).sum();
    assert_eq!((kept, stored.len()), (stats.points_kept, stats.voxels));
    assert!(kept < input.len(), "clustered input must be thinned");
    let fullest = stored.values().map(Vec::len).max().unwrap();
    assert!(
        fullest <= n as usize,
        "a voxel holds {fullest} > {n} points"
    );
    assert_eq!(fullest, n as usize, "the cluster fills some voxel");
    // Every input point's own voxel holds a stored point, so one is within the diagonal.
    let tolerance = v * 3f64.sqrt();
    let mut worst = 0.0f64;
    for p in &input {
        let near = stored
            .get(&voxel_of(p, v))
            .into_iter()
            .flatten()
            .map(|q| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt())
            .fold(f64::INFINITY, f64::min);
        worst = worst.max(near);
    }
    println!("worst input-to-map distance {worst:.4} m (tolerance {tolerance:.4} m)");
    assert!(worst <= tolerance);
}

#[test]
fn growing_from_one_voxel_gives_the_bytes_of_a_map_large_enough_from_the_start() {
    let input = cloud(11, 30_000);
    let (a, b) = input.split_at(12_345);
    let p = || params(0.5, 2.0, 3);
    let large = build(p(), 1 << 17, 1 << 19, &[&input]);
    let tiny = build(p(), 1, 1, &[a, b]);
    let default = build(p(), FIRST_VOXELS, FIRST_POINTS, &[b, a]);
    assert!(tiny == large, "grown map differs from the large one");
    assert!(default != large, "another order keeps other points");
}

#[test]
fn the_same_points_give_the_same_bytes() {
    let input = cloud(3, 20_000);
    let p = || params(1.0, 8.0, 5);
    let once = build(p(), 64, 256, &[&input]);
    let again = build(p(), 64, 256, &[&input]);
    let split = build(
        p(),
        64,
        256,
        &[&input[..1], &input[1..9_999], &input[9_999..]],
    );
    assert!(once == again && once == split);
    let other = build(p(), 64, 256, &[&cloud(4, 20_000)]);
    assert!(once != other);
}

#[test]
fn non_finite_points_are_skipped_and_an_empty_map_is_refused() {
    let mut b = MapBuilder::new(params(1.0, 4.0, 5)).unwrap();
    b.add(&[[f64::NAN, 0.0, 0.0], [0.0, f64::INFINITY, 0.0]])
        .unwrap();
    assert_eq!((b.points_in(), b.points_kept()), (2, 0));
    let e = b.encode().unwrap_err().to_string();
    assert!(e.contains("empty"), "{e}");
    b.add(&[[0.5, 0.5, 0.5]]).unwrap();
    let (bytes, stats) = b.encode().unwrap();
    assert_eq!((stats.points_in, stats.points_kept, stats.tiles), (3, 1, 1));
    assert_eq!(TileMap::open(&bytes).unwrap().len(), 1);
}

#[test]
fn parameters_a_file_cannot_hold_are_refused_naming_the_reason() {
    let refused = |p: MapParams| MapBuilder::new(p).err().expect("refused").to_string();
    for (v, s) in [(0.5, 0.75), (1.0, 0.5), (1.0, f64::NAN), (0.3, 1.0)] {
        let e = refused(params(v, s, 5));
        assert!(e.contains("whole multiple"), "{v} {s}: {e}");
    }
    assert!(
        MapBuilder::new(params(0.3, 0.9, 5)).is_ok(),
        "3 x 0.3 m tiles"
    );
    assert!(refused(params(0.0, 1.0, 5)).contains("voxel size"));
    for n in [0, 2, 256] {
        assert!(refused(params(1.0, 4.0, n)).contains("points per voxel"));
    }
    for name in ["seventeen-bytes-x", "caf\u{e9}", "a\0b"] {
        let mut p = params(1.0, 4.0, 5);
        p.frame = name.into();
        assert!(refused(p).contains("frame name"), "{name:?}");
    }
    let mut p = params(1.0, 4.0, 5);
    p.frame = "sixteen-bytes-ok".into();
    assert!(MapBuilder::new(p).is_ok());
}

#[test]
fn a_scan_is_deskewed_cropped_and_moved_by_its_pose() {
    let mut config = Config::<f64>::new(50.0);
    config.min_range = 2.0;
    config.deskew = true;
    // Straight ahead at 10 m when the sweep starts, half way and at its end; one too close,
    // one too far.
    let points = [
        [10.0, 0.0, 0.0],
        [10.0, 0.0, 0.0],
        [0.0, 10.0, 0.0],
        [1.0, 0.0, 0.0],
        [60.0, 0.0, 0.0],
    ];
    let stamps = [0.0, 0.05, 0.1, 0.1, 0.1];
    // 1 m forward over the sweep: a point seen at its start moves 1 m back to its end.
    let motion = Pose::translation(1.0, 0.0, 0.0);
    let pose = Pose::translation(100.0, 200.0, 3.0);
    let mut b = MapBuilder::new(params(0.25, 5.0, 3)).unwrap();
    let pre = b
        .add_scan(&points, Some(&stamps), &motion, &pose, &config)
        .unwrap();
    assert!(pre.deskewed);
    assert_eq!((pre.kept, pre.out_of_range), (3, 2));
    let (bytes, stats) = b.encode().unwrap();
    assert_eq!((stats.points_in, stats.points_kept), (5, 3));
    let map = TileMap::open(&bytes).unwrap();
    let mut got: Vec<[f64; 3]> = (0..map.len())
        .flat_map(|t| map.tile(t).unwrap().points().collect::<Vec<_>>())
        .collect();
    got.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let want = [
        [100.0, 210.0, 3.0],
        [109.0, 200.0, 3.0],
        [109.5, 200.0, 3.0],
    ];
    for (g, w) in got.iter().zip(&want) {
        let d = (0..3).map(|k| (g[k] - w[k]).abs()).fold(0.0, f64::max);
        assert!(d < 1e-4, "{g:?} != {w:?}");
    }
    assert_eq!(got.len(), want.len());
}
