//! Growing instead of dropping (`WhenFull::Refuse`, `Odometry::rehome`): a run that starts in
//! small storage, refuses each frame that would overfill it and moves into larger storage gives
//! the bits of a run that started large, in every scalar, map storage and mode, from any frame
//! and into any larger size; it never drops or evicts. A board's fixed storage keeps its rule.

use crate::common;

use common::*;
use kiss_odom_core::{
    Capacities, Config, ConfigError, Exact, Flag, FrameError, Odometry, PointCodec, Pose,
    Quantized, Real, WhenFull,
};
use proptest::prelude::*;

const RANGE: f64 = 40.0;

fn scans<T: Real>(frames: usize, seed: u64) -> Vec<Vec<[T; 3]>> {
    let s = street(seed);
    (0..frames).map(|i| narrow(&scan(&s, i, RANGE))).collect()
}

/// Capacities far below what the street needs.
fn cramped(plane_terms: bool) -> Capacities {
    Capacities {
        scan_points: 1_000,
        merge_points: 300,
        source_points: 50,
        map_voxels: 200,
        map_points: 800,
        plane_terms,
    }
}

/// Each capacity doubled, or raised to what was needed if that is more.
fn doubled(caps: Capacities, needed: Capacities) -> Capacities {
    let grow = |have: usize, need: usize| {
        if need > have {
            need.max(2 * have)
        } else {
            have
        }
    };
    Capacities {
        scan_points: grow(caps.scan_points, needed.scan_points),
        merge_points: grow(caps.merge_points, needed.merge_points),
        source_points: grow(caps.source_points, needed.source_points),
        map_voxels: grow(caps.map_voxels, needed.map_voxels),
        map_points: grow(caps.map_points, needed.map_points),
        plane_terms: caps.plane_terms,
    }
}

/// A run that refuses full frames, moving on each refusal into `grow(caps, needed)` and before
/// frame `k` into `extra[k]` if given (never smaller than the capacities in use): its poses and
/// moves. Every frame registered must have dropped and evicted nothing.
fn growing<T: Real, P: PointCodec<T>>(
    config: Config<T>,
    start: Capacities,
    scans: &[Vec<[T; 3]>],
    extra: &[(usize, Capacities)],
) -> (Vec<Pose<T>>, usize) {
    let new = |caps: Capacities| vec![0u64; caps.arena_words::<T, P>()].into_boxed_slice();
    let mut odom = Odometry::<T, P, _>::new(config, start, new(start)).unwrap();
    odom.set_when_full(WhenFull::Refuse);
    let (mut poses, mut moves) = (Vec::new(), 0);
    for (k, s) in scans.iter().enumerate() {
        if let Some((_, caps)) = extra.iter().find(|(at, _)| *at == k) {
            let caps = doubled(*caps, *odom.capacities());
            odom = odom.rehome(caps, new(caps)).unwrap();
            moves += 1;
        }
        let report = loop {
            match odom.register_frame(s, None) {
                Err(FrameError::Full) => {
                    let caps = doubled(*odom.capacities(), odom.room_needed());
                    assert_ne!(caps, *odom.capacities(), "frame {k}: refused with room");
                    odom = odom.rehome(caps, new(caps)).unwrap();
                    moves += 1;
                }
                other => break other.unwrap(),
            }
        };
        let d = report.dropped;
        assert!(
            !report.status.contains(Flag::Evicted) && !report.status.contains(Flag::Capacity),
            "frame {k}: {d:?}"
        );
        poses.push(report.pose);
    }
    (poses, moves)
}

/// An f64 odometry owning storage of exactly `caps`' size.
fn boxed(
    config: Config<f64>,
    caps: Capacities,
) -> Result<Odometry<f64, Exact, Box<[u64]>>, ConfigError> {
    let words = vec![0u64; caps.arena_words::<f64, Exact>()].into_boxed_slice();
    Odometry::new(config, caps, words)
}

/// Capacities that hold everything the street gives every mode (the accurate preset's
/// `r_max / 200` voxels included).
fn roomy(plane_terms: bool) -> Capacities {
    Capacities {
        source_points: 65_536,
        map_voxels: 65_536,
        map_points: 1 << 20,
        plane_terms,
        ..caps()
    }
}

/// A run in fixed storage that must drop nothing: its poses.
fn fixed<T: Real, P: PointCodec<T>>(
    config: Config<T>,
    caps: Capacities,
    scans: &[Vec<[T; 3]>],
) -> Vec<Pose<T>> {
    let words = vec![0u64; caps.arena_words::<T, P>()];
    let mut odom = Odometry::<T, P, _>::new(config, caps, words).unwrap();
    let mut poses = Vec::new();
    for (k, s) in scans.iter().enumerate() {
        let r = odom.register_frame(s, None).unwrap();
        assert!(
            !r.status.contains(Flag::Capacity),
            "frame {k}: {:?}",
            r.dropped
        );
        poses.push(r.pose);
    }
    poses
}

/// The same poses, bit for bit, from `cramped` storage grown as needed and from `roomy`.
fn check<T: Real, P: PointCodec<T>>(name: &str, config: Config<T>, plane_terms: bool) {
    let s = scans::<T>(12, 7);
    let want = fixed::<T, P>(config, roomy(plane_terms), &s);
    let (got, moves) = growing::<T, P>(config, cramped(plane_terms), &s, &[]);
    println!("{name}: {moves} moves over {} frames", s.len());
    assert!(moves >= 3, "{name}: the cramped run should have moved");
    for (k, (a, b)) in got.iter().zip(&want).enumerate() {
        assert_eq!(a, b, "{name}: frame {k}");
    }
}

#[test]
fn a_grown_run_gives_the_bits_of_a_run_that_started_large_in_every_scalar_and_storage() {
    check::<f64, Exact>("f64 exact", Config::new(RANGE), false);
    check::<f64, Quantized>("f64 quantized", Config::new(RANGE), false);
    check::<f32, Exact>("f32 exact", Config::new(RANGE as f32), false);
    check::<f32, Quantized>("f32 quantized", Config::new(RANGE as f32), false);
}

#[test]
fn a_grown_run_gives_the_bits_of_a_run_that_started_large_in_robust_mode_and_the_preset() {
    check::<f64, Exact>("robust", Config::robust(RANGE), true);
    check::<f64, Exact>("accurate", Config::accurate(RANGE), true);
    check::<f32, Quantized>("accurate f32", Config::accurate(RANGE as f32), true);
}

#[test]
fn fixed_storage_keeps_its_rule_and_a_move_must_hold_the_state() {
    let s = scans::<f64>(8, 7);
    let caps = Capacities {
        map_voxels: 1_000,
        map_points: 4_000,
        ..roomy(false)
    };
    let mut odom = boxed(Config::new(RANGE), caps).unwrap();
    assert_eq!(odom.when_full(), WhenFull::Drop);
    let mut evicted = false;
    for scan in &s {
        let r = odom.register_frame(scan, None).unwrap();
        evicted |= r.status.contains(Flag::Evicted);
    }
    assert!(evicted, "a board's full map evicts");
    assert_eq!(odom.room_needed(), caps, "nothing refused, nothing needed");
    // Smaller than what it holds: refused, and the odometry goes on as it was.
    let less = Capacities {
        map_voxels: odom.map().voxels() - 1,
        ..caps
    };
    let words = vec![0u64; less.arena_words::<f64, Exact>()];
    assert_eq!(odom.rehome(less, words).err(), Some(ConfigError::Holds));
    let short = vec![0u64; caps.arena_words::<f64, Exact>() - 1];
    assert_eq!(
        odom.rehome(caps, short).err(),
        Some(ConfigError::ArenaTooSmall)
    );
    let robust = boxed(Config::robust(RANGE), cramped(true)).unwrap();
    let words = vec![0u64; caps.arena_words::<f64, Exact>()];
    assert_eq!(
        robust.rehome(caps, words).err(),
        Some(ConfigError::PlaneTerms)
    );
    // The same storage size again: the same map, voxel for voxel and point for point.
    let words = vec![0u64; caps.arena_words::<f64, Exact>()];
    let moved = odom.rehome(caps, words).unwrap();
    let points = |o: &Odometry<f64, Exact, Vec<u64>>| {
        let mut v = Vec::new();
        o.map().for_each_point(|k, p| v.push((*k, [p.x, p.y, p.z])));
        v.sort_by(|a, b| a.partial_cmp(b).unwrap());
        v
    };
    let mut before = Vec::new();
    odom.map()
        .for_each_point(|k, p| before.push((*k, [p.x, p.y, p.z])));
    before.sort_by(|a, b| a.partial_cmp(b).unwrap());
    assert_eq!(points(&moved), before);
    assert_eq!(moved.high_water(), odom.high_water());
    assert_eq!((moved.pose(), moved.frames()), (odom.pose(), odom.frames()));
    assert_eq!(moved.merge_cloud(), odom.merge_cloud());
    assert_eq!(moved.source(), odom.source());
}

#[test]
fn a_refused_frame_changes_nothing() {
    let s = scans::<f64>(4, 7);
    let mut odom = boxed(Config::new(RANGE), roomy(false)).unwrap();
    for scan in &s[..3] {
        odom.register_frame(scan, None).unwrap();
    }
    let before = (
        *odom.pose(),
        *odom.last_delta(),
        odom.sigma(),
        odom.frames(),
    );
    let map = odom.map().points();
    // The next frame's map update could need more than the room left: refused.
    let tight = Capacities {
        map_voxels: odom.map().voxels() + 1,
        ..roomy(false)
    };
    let words = vec![0u64; tight.arena_words::<f64, Exact>()].into_boxed_slice();
    let mut tight_odom = odom.rehome(tight, words).unwrap();
    tight_odom.set_when_full(WhenFull::Refuse);
    assert_eq!(
        tight_odom.register_frame(&s[3], None),
        Err(FrameError::Full)
    );
    let after = (
        *tight_odom.pose(),
        *tight_odom.last_delta(),
        tight_odom.sigma(),
        tight_odom.frames(),
    );
    assert_eq!(after, before);
    assert_eq!(tight_odom.map().points(), map);
    assert!(tight_odom.room_needed().map_voxels > tight.map_voxels);
    assert_eq!(
        tight_odom.room_needed().merge_points,
        tight.merge_points,
        "only the short capacity is raised"
    );
}

/// Capacities from `cramped` up to `roomy`, each drawn on its own.
fn sizes() -> impl Strategy<Value = Capacities> {
    let (lo, hi) = (cramped(false), roomy(false));
    (
        lo.scan_points..hi.scan_points,
        lo.merge_points..hi.merge_points,
        lo.source_points..hi.source_points,
        lo.map_voxels..hi.map_voxels,
        lo.map_points..hi.map_points,
    )
        .prop_map(|(a, b, c, d, e)| Capacities {
            scan_points: a,
            merge_points: b,
            source_points: c,
            map_voxels: d,
            map_points: e,
            plane_terms: false,
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn moves_of_any_size_at_any_frame_give_the_bits_of_a_run_that_started_large(
        start in sizes(),
        at in proptest::collection::vec((0usize..8, sizes()), 0..3),
        quantized in any::<bool>(),
    ) {
        let s = scans::<f64>(8, 11);
        let config = Config::new(RANGE);
        if quantized {
            let want = fixed::<f64, Quantized>(config, roomy(false), &s);
            let (got, _) = growing::<f64, Quantized>(config, start, &s, &at);
            prop_assert_eq!(got, want);
        } else {
            let want = fixed::<f64, Exact>(config, roomy(false), &s);
            let (got, _) = growing::<f64, Exact>(config, start, &s, &at);
            prop_assert_eq!(got, want);
        }
    }
}
