use super::*;
use crate::testutil::Rng;
use crate::voxel::point_to_voxel;

const BLOCKS: usize = 40;
const WORDS: usize = LocalMap::<f64, Exact, &mut [u64]>::words(48, BLOCKS * BLOCK);

/// A map of 1 m voxels pruned at 10 m with `max_voxels` voxels and `BLOCKS` blocks.
fn map(words: &mut [u64], max_voxels: usize, n_max: u32) -> LocalMap<f64, Exact, &mut [u64]> {
    LocalMap::new(1.0, 10.0, n_max, max_voxels, BLOCKS * BLOCK, words).unwrap()
}

#[test]
fn admission_skips_points_closer_than_the_map_resolution() {
    let mut w = [0u64; WORDS];
    let mut map = map(&mut w, 32, 20);
    // resolution = sqrt(1 / 20) = 0.2236 m
    let st = map.add_points(
        [
            Point::new(0.1, 0.1, 0.1),
            Point::new(0.3, 0.1, 0.1), // 0.2 m from the first: skipped
            Point::new(0.4, 0.1, 0.1), // 0.3 m: added
            Point::new(0.1, 0.1, 0.3), // 0.2 m from the first: skipped
        ]
        .into_iter(),
    );
    assert_eq!((st.added, map.voxels(), map.points()), (2, 1, 2));
}

#[test]
fn voxels_never_exceed_n_max_points() {
    let mut w = [0u64; WORDS];
    let mut map = map(&mut w, 32, 5);
    let mut rng = Rng(7);
    for _ in 0..200 {
        map.add_points(core::iter::once(Point::new(
            rng.next(),
            rng.next(),
            rng.next(),
        )));
    }
    let mut per_voxel = 0;
    map.view().for_each_point(|k, _| {
        assert_eq!(*k, [0, 0, 0]);
        per_voxel += 1;
    });
    assert_eq!(per_voxel, 5);
    assert_eq!(map.points(), 5);
}

#[test]
fn full_table_and_pool_drop_new_content_and_count_it() {
    let mut w = [0u64; WORDS];
    // 3 voxels allowed; the pool has 40 blocks.
    let mut small = map(&mut w, 3, 20);
    let pts = (0..5).map(|i| Point::new(i as f64 + 0.5, 0.5, 0.5));
    let st = small.add_points(pts);
    assert_eq!((st.added, st.dropped_voxels, small.voxels()), (3, 2, 3));
    assert_eq!(small.view().high_water_voxels(), 3);

    let mut w = [0u64; WORDS];
    let mut map = map(&mut w, 48, 20);
    // 48 voxels would need 48 blocks; only 40 exist.
    let st = map.add_points((0..48).map(|i| Point::new((i % 8) as f64, (i / 8) as f64, 0.5)));
    assert_eq!((st.added, st.dropped_points), (40, 8));
    assert_eq!(map.view().high_water_point_slots(), 40 * BLOCK);
}

#[test]
fn pruning_removes_exactly_the_voxels_whose_first_point_is_beyond_range() {
    let mut w = [0u64; WORDS];
    let mut map = map(&mut w, 48, 20);
    let mut rng = Rng(99);
    let mut inside = 0;
    for _ in 0..60 {
        let p = Point::new(
            rng.next() * 30.0 - 15.0,
            rng.next() * 30.0 - 15.0,
            rng.next(),
        );
        let before = map.voxels();
        map.add_points(core::iter::once(p));
        if map.voxels() > before && p.coords.norm_squared() < 100.0 {
            inside += 1;
        }
    }
    let removed = map.remove_far_from(&Point::origin());
    assert_eq!(map.voxels(), inside);
    assert!(removed > 0);
    map.view()
        .for_each_point(|_, p| assert!(p.coords.norm() < 10.0 + 1.8));
    // Every remaining voxel is still findable after the backward shifts.
    let mut keys = [[0i32; 3]; 48];
    let mut n = 0;
    map.view().for_each_point(|k, _| {
        if !keys[..n].contains(k) {
            keys[n] = *k;
            n += 1;
        }
    });
    for k in &keys[..n] {
        assert!(map.view().find(k).is_some());
    }
    // Freed blocks are reusable: fill the map again without pool drops.
    map.clear();
    let st = map.add_points((0..40).map(|i| Point::new((i % 8) as f64, (i / 8) as f64, 0.5)));
    assert_eq!(st.dropped_points, 0);
}

#[test]
fn closest_neighbor_equals_brute_force_over_the_27_voxels() {
    let mut w = [0u64; WORDS];
    let mut map = map(&mut w, 48, 20);
    let mut rng = Rng(12345);
    let mut stored = [Point::origin(); 160];
    let mut n = 0;
    for _ in 0..400 {
        let p = Point::new(rng.next() * 4.0, rng.next() * 4.0, rng.next() * 2.0);
        map.add_points(core::iter::once(p));
    }
    map.view().for_each_point(|_, p| {
        stored[n] = p;
        n += 1;
    });
    assert!(n > 40);
    // Miri interprets every step: a few dozen queries there, the full set natively.
    let queries = if cfg!(miri) { 30 } else { 500 };
    for _ in 0..queries {
        let q = Point::new(
            rng.next() * 5.0 - 0.5,
            rng.next() * 5.0 - 0.5,
            rng.next() * 3.0 - 0.5,
        );
        let tau = 0.05 + rng.next() * 1.5;
        let kq = point_to_voxel(&q, 1.0);
        let mut want: Option<(Point<f64>, f64)> = None;
        for p in &stored[..n] {
            let kp = point_to_voxel(p, 1.0);
            if (0..3).any(|a| (kp[a] - kq[a]).abs() > 1) {
                continue;
            }
            let d = (p - q).norm();
            if want.is_none_or(|(_, best)| d < best) {
                want = Some((*p, d));
            }
        }
        let want = want.filter(|(_, d)| *d < tau).map(|(p, _)| p);
        assert_eq!(map.closest_neighbor(&q, tau).map(|(p, _)| p), want);
    }
}
