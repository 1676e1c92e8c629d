//! Properties of the core over generated inputs (proptest): registration recovers bounded rigid
//! motions of a structured scene, the map never outgrows its capacities, and no input makes
//! `Odometry` panic or return a non-finite pose.
//!
//! A failure prints proptest's shrunk input; the seed of a failing run is also saved beside this
//! file in `properties.proptest-regressions` and replayed first by later runs. Set
//! `PROPTEST_CASES` for a longer soak than the CI counts below.
//!
//! Miri skips this file: it exercises no `unsafe` beyond what the unit tests reach, and proptest
//! would take hours under the interpreter.
#![cfg(not(miri))]

use crate::common;

use common::street;
use kiss_odom_core::stages::{
    align_points_to_map, work_words, IcpParams, LocalMap, VoxelKey, BLOCK,
};
use kiss_odom_core::{
    Capacities, Config, ConfigError, Exact, FrameError, Odometry, Point, PointCodec, Pose,
    Quantized, Real, Sequential,
};
use nalgebra::{Translation3, UnitQuaternion, Vector3};
use proptest::prelude::*;
use proptest::test_runner::Config as ProptestConfig;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// `cases` unless `PROPTEST_CASES` says otherwise; shrinking is bounded so that a failure of an
/// expensive property is reported in seconds, not minutes.
fn config(cases: u32) -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(cases);
    ProptestConfig {
        cases,
        max_shrink_iters: 2048,
        max_shrink_time: 60_000,
        ..ProptestConfig::default()
    }
}

fn is_finite_pose<T: Real>(p: &Pose<T>) -> bool {
    p.translation.vector.iter().all(|v| v.is_finite())
        && p.rotation.coords.iter().all(|v| v.is_finite())
}

/// A `LocalMap` over a `Vec`: `voxels` voxels, `points` points.
fn new_map<P: PointCodec<f64>>(
    voxel: f64,
    range: f64,
    n_max: u32,
    voxels: usize,
    points: usize,
) -> LocalMap<f64, P, Vec<u64>> {
    let words = vec![0u64; LocalMap::<f64, P, Vec<u64>>::words(voxels, points)];
    LocalMap::new(voxel, range, n_max, voxels, points, words).expect("N_max in 1..=255")
}

// ---------------------------------------------------------------------------------------------
// (a) Registration recovers bounded rigid motions of a structured scene.

/// Largest translation and rotation of the generated motions.
const MAX_SHIFT: f64 = 0.5;
const MAX_ANGLE: f64 = 3.0 * core::f64::consts::PI / 180.0;
/// Scene radius around the sensor: the lever arm `R` of the error bound below.
const SCENE_RADIUS: f64 = 30.0;
/// `gamma`, the reference's convergence criterion on the correction twist.
const GAMMA: f64 = 1e-4;
/// Allowed translation (m) and rotation (rad) error of a recovered motion.
///
/// Why this bound: every source point is an exact copy of a map point moved by `truth^-1`, so
/// the residuals vanish at `truth` and, once the nearest neighbours are the twins (they are
/// whenever the error is below half the map resolution, 0.11 m), Gauss-Newton on a zero-residual
/// problem converges quadratically. The only non-linearity is the rotation: linearising `Exp` at
/// a step of size `|dx|` misplaces a point at lever arm `R` by at most `R |dx|^2 / 2`. ICP stops
/// after applying a step with `|dx| < gamma`, and that step was within `O(|dx|^2)` of the error
/// before it, so the error left is at most about `R gamma^2 / 2 = 30 * 1e-8 / 2 = 1.5e-7` m
/// (and that over `R` in rad), plus rounding (~1e-13). 1e-6 leaves a factor 6 over that.
const RECOVERY_TOL: f64 = 1e-6;

/// Largest error seen, as `f64` bits (non-negative floats order like their bits).
static WORST_RECOVERY: AtomicU64 = AtomicU64::new(0);

/// A jittered street (see `common::street`, non-periodic: a lattice would let ICP lock onto a
/// shift by one lattice step), cropped to `SCENE_RADIUS` around the origin.
fn scene(seed: u64) -> Vec<[f64; 3]> {
    street(seed)
        .into_iter()
        .filter(|p| Vector3::from(*p).norm() < SCENE_RADIUS)
        .collect()
}

/// A motion of at most `MAX_SHIFT` and `MAX_ANGLE` from unit-box samples (scaled down when
/// outside the ball, so shrinking goes to the identity).
fn motion(t: [f64; 3], r: [f64; 3]) -> Pose<f64> {
    let mut t = Vector3::from(t) * MAX_SHIFT;
    if t.norm() > MAX_SHIFT {
        t *= MAX_SHIFT / t.norm();
    }
    let mut r = Vector3::from(r) * MAX_ANGLE;
    if r.norm() > MAX_ANGLE {
        r *= MAX_ANGLE / r.norm();
    }
    Pose::from_parts(Translation3::from(t), UnitQuaternion::from_scaled_axis(r))
}

fn unit3() -> impl Strategy<Value = [f64; 3]> {
    [-1.0..=1.0f64, -1.0..=1.0f64, -1.0..=1.0f64]
}

proptest! {
    #![proptest_config(config(40))]

    #[test]
    fn registration_recovers_bounded_rigid_motions_of_a_structured_scene(
        seed in any::<u64>(),
        t in unit3(),
        r in unit3(),
    ) {
        let truth = motion(t, r);
        let pts = scene(seed);
        // Voxel 1 m, N_max 20, r_max 100 m: the reference defaults for a 100 m sensor.
        let mut map = new_map::<Exact>(1.0, 100.0, 20, 20_000, 16_384 * BLOCK);
        let st = map.update(&pts, &Pose::identity());
        prop_assert_eq!(st.dropped_voxels + st.dropped_points, 0);
        // The source is what the map admitted, seen from `truth`: every point has a twin.
        let inv = truth.inverse();
        let mut source = Vec::with_capacity(map.points());
        map.view().for_each_point(|_, p| {
            let q = inv * p;
            source.push([q.x, q.y, q.z]);
        });
        let mut work = vec![0u64; work_words::<f64>(source.len(), false)];
        // The second frame of a run: identity guess, the threshold's seed sigma = 2 m, so the
        // correspondence gate is 3 sigma = 6 m and the kernel sigma = 2 m.
        let params = IcpParams { convergence_criterion: GAMMA, max_iterations: 500, budget: None, planes: false, prior: None, stop_on_cycle: false };
        let a = align_points_to_map(
            &Sequential, &source, &mut work, &map.view(), &Pose::identity(), 6.0, 2.0, &params,
        );
        let d = a.pose.inverse() * truth;
        let (et, er) = (d.translation.vector.norm(), d.rotation.angle());
        prop_assert!(a.converged && !a.singular, "stopped after {} iterations", a.iterations);
        let worst = f64::from_bits(WORST_RECOVERY.fetch_max(et.max(er).to_bits(), Relaxed));
        if et.max(er) > worst {
            println!(
                "worst recovery so far: {:.2e} m, {:.2e} rad after {} iterations (allowed {:.0e})",
                et, er, a.iterations, RECOVERY_TOL
            );
        }
        prop_assert!(
            et < RECOVERY_TOL && er < RECOVERY_TOL,
            "truth {:?}: error {:.2e} m, {:.2e} rad (allowed {:.0e}), {} iterations",
            truth, et, er, RECOVERY_TOL, a.iterations
        );
    }
}

// ---------------------------------------------------------------------------------------------
// (b) The map never exceeds its capacities.

/// A coordinate: mostly in `[-r, r]`, sometimes a special or arbitrary value.
fn coord(r: f64) -> impl Strategy<Value = f64> {
    prop_oneof![
        12 => -r..=r,
        1 => prop::sample::select(vec![
            f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 0.0, -0.0, 1e300, -1e300, f64::MAX,
            f64::MIN, f64::MIN_POSITIVE, 5e-324, 1e15, -3e9,
        ]),
        1 => any::<f64>(),
    ]
}

fn points(r: f64, max_len: usize) -> impl Strategy<Value = Vec<[f64; 3]>> {
    prop::collection::vec([coord(r), coord(r), coord(r)], 0..=max_len)
}

/// An arbitrary pose: any rotation, translations up to `r` and sometimes huge or non-finite.
fn any_pose(r: f64) -> impl Strategy<Value = Pose<f64>> {
    (
        [coord(r), coord(r), coord(r)],
        [-4.0..=4.0f64, -4.0..=4.0f64, -4.0..=4.0f64],
    )
        .prop_map(|(t, w)| {
            Pose::from_parts(
                Translation3::new(t[0], t[1], t[2]),
                UnitQuaternion::from_scaled_axis(Vector3::from(w)),
            )
        })
}

/// The map's voxels and points as seen through `for_each_point`: per-voxel counts and the
/// first point of each voxel.
fn census<P: PointCodec<f64>>(
    map: &LocalMap<f64, P, Vec<u64>>,
) -> BTreeMap<VoxelKey, (usize, Point<f64>)> {
    let mut voxels = BTreeMap::new();
    map.view()
        .for_each_point(|k, p| voxels.entry(*k).or_insert((0, p)).0 += 1);
    voxels
}

fn check_map_caps<P: PointCodec<f64>>(
    voxel: f64,
    range: f64,
    n_max: u32,
    max_voxels: usize,
    blocks: usize,
    updates: &[(Vec<[f64; 3]>, Pose<f64>)],
) -> Result<(), TestCaseError> {
    let mut map = new_map::<P>(voxel, range, n_max, max_voxels, blocks * BLOCK);
    prop_assert!(map.view().voxel_capacity() <= max_voxels);
    prop_assert_eq!(map.view().point_capacity(), blocks * BLOCK);
    for (i, (pts, pose)) in updates.iter().enumerate() {
        map.update(pts, pose);
        let seen = census(&map);
        let map = map.view();
        prop_assert!(
            map.voxels() <= map.voxel_capacity(),
            "update {}: {} voxels",
            i,
            map.voxels()
        );
        prop_assert!(
            map.points() <= map.point_capacity(),
            "update {}: {} points",
            i,
            map.points()
        );
        prop_assert!(map.high_water_voxels() <= map.voxel_capacity());
        prop_assert!(map.high_water_point_slots() <= map.point_capacity());
        // The counters agree with the content, and no voxel holds more than N_max points.
        prop_assert_eq!(seen.len(), map.voxels());
        prop_assert_eq!(seen.values().map(|v| v.0).sum::<usize>(), map.points());
        prop_assert!(seen.values().all(|v| v.0 <= n_max as usize));
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn the_local_map_never_exceeds_its_capacities(
        voxel in prop_oneof![0.05..5.0f64, Just(1e-3), Just(1e6)],
        range in 0.5..200.0f64,
        n_max in 1u32..=255,
        max_voxels in 1usize..=96,
        blocks in 0usize..=64,
        updates in prop::collection::vec((points(30.0, 120), any_pose(30.0)), 1..8),
        quantized in any::<bool>(),
    ) {
        if quantized {
            check_map_caps::<Quantized>(voxel, range, n_max, max_voxels, blocks, &updates)?;
        } else {
            check_map_caps::<Exact>(voxel, range, n_max, max_voxels, blocks, &updates)?;
            // With exact storage the pruning rule is checkable: after an update, no voxel's
            // first point is at or beyond the map's radius from the pose (`r_max`, or less
            // once the map has filled), and the radius never exceeds `r_max`.
            let mut map = new_map::<Exact>(voxel, range, n_max, max_voxels, blocks * BLOCK);
            let mut scratch = vec![0u64; 2 * 120];
            for (pts, pose) in &updates {
                map.update_with(pts, pose, &mut scratch);
                let origin = Point::from(pose.translation.vector);
                let r = map.radius();
                prop_assert!(r <= range, "radius {} above r_max {}", r, range);
                for (k, (_, first)) in census(&map) {
                    let d = (first - origin).norm();
                    prop_assert!(d < range && d <= r || d.is_nan(), "voxel {:?} kept at {} m, radius {} m", k, d, r);
                }
            }
        }
    }

    #[test]
    fn a_full_map_evicts_the_same_way_every_run(
        voxel in 0.2..3.0f64,
        range in 5.0..60.0f64,
        n_max in 1u32..=30,
        max_voxels in 1usize..=64,
        blocks in 1usize..=48,
        updates in prop::collection::vec((points(40.0, 120), any_pose(10.0)), 1..8),
        tallied in any::<bool>(),
    ) {
        // Two maps, the same updates: the same voxels, points, radius and counts, bit for bit.
        let run = || {
            let mut map = new_map::<Exact>(voxel, range, n_max, max_voxels, blocks * BLOCK);
            let mut scratch = vec![0u64; if tallied { 2 * 120 } else { 0 }];
            let mut trace = Vec::new();
            for (pts, pose) in &updates {
                let st = map.update_with(pts, pose, &mut scratch);
                let mut points = Vec::new();
                map.view().for_each_point(|k, p| points.push((*k, p.coords.map(f64::to_bits))));
                trace.push((st, map.radius().to_bits(), points));
            }
            trace
        };
        let (a, b) = (run(), run());
        prop_assert!(a == b, "two runs differ");
    }
}

/// Small capacities: every buffer fills within a few frames.
fn small_caps() -> impl Strategy<Value = Capacities> {
    caps_up_to(400, 200, 80, 120, 400)
}

/// Capacities from 1 up to the given ones.
fn caps_up_to(
    scan: usize,
    merge: usize,
    source: usize,
    voxels: usize,
    points: usize,
) -> impl Strategy<Value = Capacities> {
    (1..=scan, 1..=merge, 1..=source, 1..=voxels, 1..=points).prop_map(
        |(scan_points, merge_points, source_points, map_voxels, map_points)| Capacities {
            scan_points,
            merge_points,
            source_points,
            map_voxels,
            map_points,
            plane_terms: false,
        },
    )
}

proptest! {
    #![proptest_config(config(128))]

    #[test]
    fn odometry_buffers_never_exceed_their_capacities(
        caps in small_caps(),
        voxel in 0.2..3.0f64,
        n_max in 1u32..=40,
        spread in prop_oneof![Just(1.0), 0.02..1.0f64],
        scans in prop::collection::vec(points(25.0, 500), 1..8),
    ) {
        // Shrinking the scene packs points into few voxels, so voxels fill up as well.
        let scans: Vec<Vec<[f64; 3]>> =
            scans.iter().map(|s| s.iter().map(|p| p.map(|c| c * spread)).collect()).collect();
        let mut config = Config::new(30.0);
        config.voxel_size = voxel;
        config.max_points_per_voxel = n_max;
        config.max_iterations = 30;
        let mut arena = vec![0u64; caps.arena_words::<f64, Exact>()];
        let mut odom = Odometry::<f64, Exact, _>::new(config, caps, &mut arena[..]).unwrap();
        for (i, scan) in scans.iter().enumerate() {
            let Ok(r) = odom.register_frame(scan, None) else { continue };
            // Points are stored in blocks of BLOCK, so the pool holds `map_points` rounded up
            // to a whole block (see the report of this suite).
            let point_cap = caps.map_points.next_multiple_of(BLOCK);
            prop_assert!(r.merge_points as usize <= caps.merge_points, "frame {}", i);
            prop_assert!(r.source_points as usize <= caps.source_points, "frame {}", i);
            prop_assert!(r.map_voxels as usize <= caps.map_voxels, "frame {}", i);
            prop_assert!(r.map_points as usize <= point_cap, "frame {}: {} points", i, r.map_points);
            prop_assert_eq!(r.dropped.truncated as usize, scan.len().saturating_sub(caps.scan_points));
            let hw = odom.high_water();
            prop_assert!(hw.merge_points <= caps.merge_points);
            prop_assert!(hw.source_points <= caps.source_points);
            prop_assert!(hw.map_voxels <= caps.map_voxels);
            prop_assert!(hw.map_point_slots <= point_cap);
            prop_assert!(odom.merge_cloud().len() <= caps.merge_points);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// (c) No input makes `Odometry` panic or return a non-finite pose.

/// A furnished room in voxel units (floor, three walls, a box, about 700 points sampled every
/// 0.6 voxel with jitter, in shuffled order so that truncation keeps a bit of everything).
fn room(seed: u64) -> Vec<[f64; 3]> {
    let mut rng = common::Rng(seed | 1);
    let mut j = move || 0.6 * (rng.uniform() - 0.5);
    let mut pts = Vec::new();
    for a in 0..17 {
        for b in 0..17 {
            pts.push([
                -5.0 + 0.6 * a as f64 + j(),
                -5.0 + 0.6 * b as f64 + j(),
                -1.5,
            ]);
        }
        for k in 0..8 {
            let (u, z) = (-5.0 + 0.6 * a as f64 + j(), -1.5 + 0.6 * k as f64 + j());
            pts.push([u, 5.2, z]);
            pts.push([5.3, u, z]);
            pts.push([-5.1, u * 0.7, z]);
        }
    }
    for a in 0..5 {
        for k in 0..4 {
            let (u, z) = (1.0 + 0.6 * a as f64 + j(), -1.5 + 0.6 * k as f64 + j());
            pts.push([u, -2.0, z]);
            pts.push([1.0, -2.0 + 0.5 * (u - 1.0), z]);
        }
    }
    let mut rng = common::Rng(seed.rotate_left(17) | 1);
    for i in (1..pts.len()).rev() {
        pts.swap(i, (rng.uniform() * (i + 1) as f64) as usize);
    }
    pts
}

/// One call: a scan of arbitrary points; the room seen after a small motion of the sensor
/// (up to half a voxel and 3 degrees, so ICP has work), with some coordinates replaced by
/// arbitrary values; or `skip_frame`. Each scan comes with arbitrary stamps.
#[derive(Clone, Debug)]
enum Scan {
    Fresh(Vec<[f64; 3]>, Stamps),
    Room {
        t: [f64; 3],
        w: [f64; 3],
        garbage: Vec<(usize, usize, f64)>,
        stamps: Stamps,
    },
    Skip,
}

/// Per-point timestamps: none, a ramp (increasing, decreasing or constant), arbitrary values
/// (NaN, infinities, huge, negative) one per point, or the wrong number of them.
#[derive(Clone, Debug)]
enum Stamps {
    None,
    Ramp(f64, f64),
    Values(Vec<f64>),
    WrongLength(Vec<f64>),
}

impl Stamps {
    fn make(&self, n: usize) -> Option<Vec<f64>> {
        match self {
            Stamps::None => None,
            Stamps::Ramp(a, b) => Some((0..n).map(|i| a + b * i as f64).collect()),
            // Cycled to the scan's length, whatever it turns out to be.
            Stamps::Values(v) if v.is_empty() => Some(vec![0.0; n]),
            Stamps::Values(v) => Some(v.iter().copied().cycle().take(n).collect()),
            Stamps::WrongLength(v) if v.len() == n => Some(vec![0.0; n + 1]),
            Stamps::WrongLength(v) => Some(v.clone()),
        }
    }
}

fn stamps() -> impl Strategy<Value = Stamps> {
    let value = prop_oneof![
        8 => -1.0..1.0f64,
        1 => prop::sample::select(vec![
            f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -0.0, 1e308, -1e308, 5e-324,
        ]),
        1 => any::<f64>(),
    ];
    prop_oneof![
        2 => Just(Stamps::None),
        3 => (-1e3..1e3f64, prop_oneof![-1.0..1.0f64, Just(0.0), Just(1e-300), Just(1e300)])
            .prop_map(|(a, b)| Stamps::Ramp(a, b)),
        2 => prop::collection::vec(value.clone(), 0..40).prop_map(Stamps::Values),
        1 => prop::collection::vec(value, 0..8).prop_map(Stamps::WrongLength),
    ]
}

fn scan() -> impl Strategy<Value = Scan> {
    prop_oneof![
        2 => (points(1.0, 300), stamps()).prop_map(|(p, s)| Scan::Fresh(p, s)),
        6 => (
            unit3(),
            unit3(),
            prop::collection::vec((0usize..1000, 0usize..3, coord(1e3)), 0..6),
            stamps(),
        )
            .prop_map(|(t, w, garbage, stamps)| Scan::Room { t, w, garbage, stamps }),
        1 => Just(Scan::Skip),
    ]
}

/// Valid configurations over the knobs that move the numbers: range (up to `f64::MAX`),
/// voxel size, `N_max`, deskewing, the threshold and the ICP stopping rule.
#[derive(Clone, Debug)]
struct Knobs {
    max_range: f64,
    voxel_div: f64,
    min_range_frac: f64,
    n_max: u32,
    deskew: bool,
    initial_threshold: f64,
    gamma: f64,
    max_iterations: u32,
    kernel_scale: f64,
}

fn knobs(top: f64) -> impl Strategy<Value = Knobs> {
    (
        prop_oneof![
            4 => 1.0..200.0f64,
            1 => prop::sample::select(vec![1e-3, 1e6, 1e12, 1e30, top * 0.5, top]),
        ],
        prop_oneof![3 => Just(100.0), 2 => 1.0..1000.0f64, 1 => Just(1e9)],
        prop_oneof![3 => Just(0.0), 1 => 0.0..0.9f64],
        1u32..=255,
        any::<bool>(),
        prop_oneof![Just(2.0), 1e-6..100.0f64],
        prop_oneof![Just(1e-4), Just(0.0), 0.0..1.0f64],
        prop_oneof![1u32..=20, Just(500)],
        prop_oneof![Just(1.0), 1e-3..10.0f64],
    )
        .prop_map(
            |(max_range, voxel_div, min_range_frac, n_max, deskew, it, gamma, iters, ks)| Knobs {
                max_range,
                voxel_div,
                min_range_frac,
                n_max,
                deskew,
                initial_threshold: it,
                gamma,
                max_iterations: iters,
                kernel_scale: ks,
            },
        )
}

fn make_config<T: Real>(k: &Knobs) -> Config<T> {
    let mut c = Config::new(T::of(k.max_range));
    c.voxel_size = T::of(k.max_range / k.voxel_div);
    c.min_range = T::of(k.max_range * k.min_range_frac);
    c.max_points_per_voxel = k.n_max;
    c.deskew = k.deskew;
    c.initial_threshold = T::of(k.initial_threshold);
    c.convergence_criterion = T::of(k.gamma);
    c.max_iterations = k.max_iterations;
    c.kernel_scale = T::of(k.kernel_scale);
    c
}

/// Runs `scans` and checks after every call that nothing panicked (proptest catches panics),
/// that errors are only `EmptyScan` and leave the pose alone, and that every pose is finite.
fn check_no_bad_pose<T: Real, P: PointCodec<T>>(
    seed: u64,
    knobs: &Knobs,
    caps: Capacities,
    scans: &[Scan],
) -> Result<(), TestCaseError> {
    let config = make_config::<T>(knobs);
    // Knob combinations that round to an invalid config (e.g. a subnormal voxel in f32) are
    // refused by `new`; that is the documented answer, not a failure.
    if config.validate().is_err() {
        return Ok(());
    }
    let mut arena = vec![0u64; caps.arena_words::<T, P>()];
    let mut odom = Odometry::<T, P, _>::new(config, caps, &mut arena[..]).unwrap();
    // Arbitrary points span the range (and beyond: up to 1e300 times it); the room is in voxels.
    let range = knobs.max_range.min(1e300);
    let voxel = knobs.max_range / knobs.voxel_div;
    let room = room(seed);
    let mut sensor = Pose::<f64>::identity();
    for (i, s) in scans.iter().enumerate() {
        let (pts, stamps): (Vec<[f64; 3]>, _) = match s {
            Scan::Fresh(p, st) => (p.iter().map(|q| q.map(|c| c * range)).collect(), st),
            Scan::Room {
                t,
                w,
                garbage,
                stamps,
            } => {
                let m = motion(*t, *w);
                sensor *=
                    Pose::from_parts(Translation3::from(m.translation.vector * voxel), m.rotation);
                let inv = sensor.inverse();
                let mut pts: Vec<[f64; 3]> = room
                    .iter()
                    .map(|p| {
                        let q = inv * Point::from(p.map(|c| c * voxel));
                        [q.x, q.y, q.z]
                    })
                    .collect();
                for &(k, axis, v) in garbage {
                    let n = pts.len();
                    pts[k % n][axis] = v * range;
                }
                (pts, stamps)
            }
            Scan::Skip => {
                let p = odom.skip_frame();
                prop_assert!(is_finite_pose(&p), "frame {}: skip_frame gave {:?}", i, p);
                continue;
            }
        };
        let stamps = stamps.make(pts.len());
        let narrow: Vec<[T; 3]> = pts.iter().map(|p| p.map(T::of)).collect();
        let before = *odom.pose();
        match odom.register_frame(&narrow, stamps.as_deref()) {
            Ok(r) => {
                prop_assert!(is_finite_pose(&r.pose), "frame {}: pose {:?}", i, r.pose);
            }
            Err(e) => {
                prop_assert_eq!(e, FrameError::EmptyScan);
                prop_assert_eq!(*odom.pose(), before);
            }
        }
        prop_assert!(is_finite_pose(odom.pose()));
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(200))]

    #[test]
    fn no_input_makes_f64_odometry_panic_or_return_a_non_finite_pose(
        knobs in knobs(f64::MAX),
        caps in prop_oneof![small_caps(), caps_up_to(1000, 800, 400, 800, 4000)],
        seed in any::<u64>(),
        scans in prop::collection::vec(scan(), 1..8),
    ) {
        check_no_bad_pose::<f64, Exact>(seed, &knobs, caps, &scans)?;
    }

    #[test]
    fn no_input_makes_f32_quantised_odometry_panic_or_return_a_non_finite_pose(
        knobs in knobs(f32::MAX as f64),
        caps in prop_oneof![small_caps(), caps_up_to(1000, 800, 400, 800, 4000)],
        seed in any::<u64>(),
        scans in prop::collection::vec(scan(), 1..8),
    ) {
        check_no_bad_pose::<f32, Quantized>(seed, &knobs, caps, &scans)?;
    }
}

/// The threshold squares `2 r_max sin(theta / 2)` (Eq. (6)-(7)), which overflows f64 for
/// `r_max` beyond about 1e154: `Config::validate` refuses ranges above
/// [`Config::MAX_RANGE_LIMIT`], and at that limit sigma stays finite.
#[test]
fn the_threshold_stays_finite_for_every_valid_range() {
    let mut config = Config::new(1e200f64);
    config.voxel_size = 1.0;
    assert_eq!(config.validate(), Err(ConfigError::Range));
    let s = street(7);
    let mut config = Config::new(Config::<f64>::MAX_RANGE_LIMIT);
    config.voxel_size = 1.0;
    let caps = common::caps();
    let mut arena = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut odom = Odometry::<f64, Exact, _>::new(config, caps, &mut arena[..]).unwrap();
    for i in 0..4 {
        let r = odom
            .register_frame(&common::scan(&s, i, 40.0), None)
            .unwrap();
        assert!(r.sigma.is_finite(), "frame {i}: sigma {}", r.sigma);
    }
}
