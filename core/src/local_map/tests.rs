use super::*;
use crate::testutil::Rng;
use crate::voxel::{point_to_voxel, VoxelKey};

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
#[cfg_attr(
    miri,
    ignore = "minutes under Miri; quicker tests reach the same storage"
)]
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
    for _ in 0..500 {
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

/// The first point of every voxel, as `(key, distance from origin)`.
fn voxels_by_distance(map: &LocalMap<f64, Exact, &mut [u64]>) -> std::vec::Vec<(VoxelKey, f64)> {
    let mut firsts: std::vec::Vec<(VoxelKey, f64)> = std::vec::Vec::new();
    map.view().for_each_point(|k, p| {
        if !firsts.iter().any(|(q, _)| q == k) {
            firsts.push((*k, p.coords.norm()));
        }
    });
    firsts
}

#[test]
fn a_full_map_evicts_its_farthest_voxels_and_keeps_every_voxel_inside_the_new_radius() {
    let mut w = [0u64; WORDS];
    let mut scratch = [0u64; 256];
    // 32 voxels allowed, pruned at 10 m: fill it with 32 voxels at 1-9.5 m from the sensor.
    let mut map = map(&mut w, 32, 20);
    let mut rng = Rng(3);
    let mut scan = std::vec::Vec::new();
    while scan.len() < 32 {
        let (r, a) = (1.0 + 8.5 * rng.next(), core::f64::consts::TAU * rng.next());
        let p = [r * libm::cos(a), r * libm::sin(a), 0.5];
        let key = point_to_voxel(&Point::from(p), 1.0);
        if !scan
            .iter()
            .any(|q: &[f64; 3]| point_to_voxel(&Point::from(*q), 1.0) == key)
        {
            scan.push(p);
        }
    }
    let st = map.update_with(&scan, &Pose::identity(), &mut scratch);
    assert_eq!((map.voxels(), st.evicted, st.filled), (32, false, None));
    assert_eq!(map.radius(), 10.0);
    let before = voxels_by_distance(&map);

    // One more voxel, next to the sensor: the map makes room from the outside in.
    let st = map.update_with(&[[0.5, -0.5, 0.5]], &Pose::identity(), &mut scratch);
    let r = map.radius();
    std::println!(
        "evicted {} of 32 voxels, radius 10 -> {r:.3} m, {} voxels now",
        st.evicted_voxels,
        map.voxels()
    );
    assert!(st.evicted && st.filled == Some(MapCapacity::Voxels));
    assert_eq!(st.added, 1, "the near point joins");
    assert!(
        r < 10.0 && st.evicted_voxels >= 4,
        "down to 9/10 of 32 at most"
    );
    assert!(map.voxels() <= 32 * 9 / 10 + 1);
    let after = voxels_by_distance(&map);
    for (k, d) in &before {
        let kept = after.iter().any(|(q, _)| q == k);
        assert_eq!(kept, *d < r, "voxel at {d:.3} m, radius {r:.3} m");
    }
    assert_eq!((st.dropped_voxels, st.dropped_points), (0, 0));
    // The farthest kept voxel is nearer than the nearest evicted one.
    let nearest_gone = before
        .iter()
        .filter(|(k, _)| !after.iter().any(|(q, _)| q == k))
        .map(|(_, d)| *d)
        .fold(f64::INFINITY, f64::min);
    let farthest_kept = after.iter().map(|(_, d)| *d).fold(0.0, f64::max);
    assert!(farthest_kept < nearest_gone);
}

#[test]
fn a_scan_larger_than_the_map_keeps_its_nearest_points_and_drops_its_farthest() {
    let mut w = [0u64; WORDS];
    let mut scratch = [0u64; 256];
    let mut map = map(&mut w, 32, 20);
    // 60 points in distinct voxels along a ray, in shuffled order: only about 32 fit.
    let mut order: std::vec::Vec<usize> = (0..60).collect();
    let mut rng = Rng(11);
    for i in (1..order.len()).rev() {
        order.swap(i, (rng.next() * (i + 1) as f64) as usize % (i + 1));
    }
    let scan: std::vec::Vec<[f64; 3]> = order
        .iter()
        .map(|&i| {
            [
                0.15 * i as f64 + 0.05,
                0.5 + (i % 2) as f64,
                0.5 + (i / 2 % 3) as f64,
            ]
        })
        .collect();
    let st = map.update_with(&scan, &Pose::identity(), &mut scratch);
    let r = map.radius();
    std::println!(
        "radius {r:.3} m, {} voxels, {} dropped, {} beyond",
        map.voxels(),
        st.dropped_voxels,
        st.beyond_radius
    );
    assert!(st.evicted && r < 10.0);
    assert!(map.voxels() <= 32);
    // Every scan point nearer than the radius is in the map; none at or beyond it.
    for p in &scan {
        let p = Point::from(*p);
        let near = p.coords.norm() < r;
        let key = point_to_voxel(&p, 1.0);
        let in_map = map.view().find(&key).is_some();
        if near {
            assert!(in_map, "{p:?} within {r:.3} m was left out");
        }
    }
    for (_, d) in voxels_by_distance(&map) {
        assert!(d < r, "voxel at {d:.3} m beyond the radius {r:.3} m");
    }
}

#[test]
fn a_full_point_pool_evicts_too_and_the_radius_grows_back_while_there_is_room() {
    let mut w = [0u64; WORDS];
    let mut scratch = [0u64; 256];
    // 48 voxels allowed but 40 blocks: the pool fills first.
    let mut map = map(&mut w, 48, 20);
    let scan: std::vec::Vec<[f64; 3]> = (0..40)
        .map(|i| [(i % 8) as f64 + 0.5, (i / 8) as f64 + 0.5, 0.5])
        .collect();
    map.update_with(&scan, &Pose::identity(), &mut scratch);
    let st = map.update_with(&[[-0.5, -0.5, 0.5]], &Pose::identity(), &mut scratch);
    assert_eq!(st.filled, Some(MapCapacity::Points));
    let shrunk = map.radius();
    assert!(shrunk < 10.0, "radius {shrunk}");
    // At 9/10 the radius holds; once the sensor has moved on and the map is below 8/10 of both
    // capacities, it grows by r_max / 20 a scan.
    let st = map.update_with(&[[-0.5, -0.5, 0.5]], &Pose::identity(), &mut scratch);
    assert!(!st.evicted && map.radius() == shrunk);
    let away = Pose::translation(30.0, 0.0, 0.0);
    let mut r = shrunk;
    for _ in 0..20 {
        let st = map.update_with(&[[-0.5, -0.5, 0.5]], &away, &mut scratch);
        assert!(!st.evicted);
        let next = map.radius();
        assert!(
            next == 10.0 || (next - (r + 0.5)).abs() < 1e-9,
            "{r} -> {next}"
        );
        r = next;
    }
    assert_eq!(r, 10.0);
}

#[test]
fn the_next_occupied_slot_is_the_first_nonzero_count_from_where_the_scan_stands() {
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    let mut counts = [0u8; 77];
    for trial in 0..200 {
        // Sparse tables (most slots empty), a slot of every word position, and a tail shorter
        // than a word.
        let density = [0.02, 0.1, 0.5][trial % 3];
        for c in counts.iter_mut() {
            *c = if rng.next() < density {
                1 + (rng.next() * 20.0) as u8
            } else {
                0
            };
        }
        for from in 0..=counts.len() + 1 {
            let want = (from..counts.len()).find(|&i| counts[i] != 0);
            let got = super::update::next_occupied(&counts, from);
            assert_eq!(got, want, "trial {trial}, from {from}");
        }
    }
}
