//! Per-stage micro-benchmarks of the core on real KITTI scans (kitti-mini sequence 05), so a
//! regression shows in the stage that caused it.
//!
//! The map is the one the odometry really built over frames 0-8; frame 9 is the scan under
//! test. Stages: preprocessing without and with deskewing (KITTI scans carry no timestamps, so
//! the deskew case stamps each point by its azimuth in 1024 columns, as a spinning sensor
//! would), the two voxel downsampling passes, the map update, the correspondence search (one
//! nearest-neighbour query per registration point), one ICP iteration (search, linear-system
//! build and solve: the linear system's cost is this minus the search), the full registration
//! and the whole frame.
//!
//! `cargo bench -p kiss-odom-drive --bench stages` (data: `KISS_ODOM_KITTI_MINI`).

mod common;

use criterion::{criterion_group, criterion_main, Criterion};
use kiss_odom_core::stages::{
    align_points_to_map, preprocess, scratch_words_for, voxel_downsample, work_words, IcpParams,
    LocalMap,
};
use kiss_odom_core::{Capacities, Config, Exact, Odometry, Point, Real, Sequential};
use std::hint::black_box;
use std::time::{Duration, Instant};

const SEQ: &str = "sequences/05";
const UNDER_TEST: usize = 9;

/// Arena words of a full-scale map.
type Map<'a> = LocalMap<f64, Exact, &'a mut [u64]>;

/// Words of a full-scale map.
fn map_words() -> usize {
    let caps = Capacities::FULL_SCALE;
    Map::words(caps.map_voxels, caps.map_points)
}

/// A full-scale map over `words`.
fn new_map(words: &mut [u64]) -> Map<'_> {
    let caps = Capacities::FULL_SCALE;
    LocalMap::new(1.0, 100.0, 20, caps.map_voxels, caps.map_points, words).unwrap()
}

/// Stamps by azimuth, 1024 columns over a 0.1 s sweep.
fn azimuth_stamps(points: &[[f64; 3]]) -> Vec<f64> {
    points
        .iter()
        .map(|p| {
            let a = (p[1].atan2(p[0]) + std::f64::consts::PI) / std::f64::consts::TAU;
            (a * 1024.0).floor().min(1023.0) * (0.1 / 1024.0)
        })
        .collect()
}

fn stages(c: &mut Criterion) {
    let Some(scans) = common::load(&common::kitti_mini().join(SEQ), UNDER_TEST + 1) else {
        return;
    };
    if scans.len() <= UNDER_TEST {
        eprintln!("skipping: fewer than {} frames", UNDER_TEST + 1);
        return;
    }
    let rec = common::record(&scans);
    let scan = &scans[UNDER_TEST].points;
    let cfg = Config::<f64>::new(100.0);
    let caps = Capacities::FULL_SCALE;
    let motion = rec.poses[UNDER_TEST - 1].inverse() * rec.poses[UNDER_TEST];

    let mut g = c.benchmark_group("stage");
    g.sample_size(20).measurement_time(Duration::from_secs(4));

    // Step 1: crop (and deskew).
    let mut pre_out = vec![[0.0f64; 3]; scan.len()];
    g.bench_function("crop", |b| {
        b.iter(|| preprocess(scan, None, &motion, 0.0, 100.0, true, &mut pre_out))
    });
    let stamps = azimuth_stamps(scan);
    g.bench_function("deskew_and_crop", |b| {
        b.iter(|| preprocess(scan, Some(&stamps), &motion, 0.0, 100.0, true, &mut pre_out))
    });
    let kept = preprocess(scan, None, &motion, 0.0, 100.0, true, &mut pre_out).kept;
    let cropped = &pre_out[..kept];

    // Step 2: the two downsampling passes.
    let mut merge = vec![[0.0f64; 3]; caps.merge_points];
    let mut scratch = vec![0u64; scratch_words_for(caps.merge_points)];
    g.bench_function("downsample_merge", |b| {
        b.iter(|| {
            voxel_downsample(
                cropped,
                cfg.voxel_size * cfg.alpha,
                &mut merge,
                &mut scratch,
            )
        })
    });
    let m = voxel_downsample(
        cropped,
        cfg.voxel_size * cfg.alpha,
        &mut merge,
        &mut scratch,
    )
    .unwrap()
    .kept;
    let mut source = vec![[0.0f64; 3]; caps.source_points];
    g.bench_function("downsample_source", |b| {
        b.iter(|| {
            voxel_downsample(
                &merge[..m],
                cfg.voxel_size * cfg.beta,
                &mut source,
                &mut scratch,
            )
        })
    });
    let s = voxel_downsample(
        &merge[..m],
        cfg.voxel_size * cfg.beta,
        &mut source,
        &mut scratch,
    )
    .unwrap()
    .kept;
    let source = &source[..s];

    // Step 3: map update of frame 9 into the map of frames 0-8 (rebuilt, untimed, each time).
    let mut map_arena = vec![0u64; map_words()];
    g.bench_function("map_update", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let mut map = new_map(&mut map_arena);
                for k in 0..UNDER_TEST {
                    map.update(&rec.merge[k], &rec.poses[k]);
                }
                let t0 = Instant::now();
                black_box(map.update(&rec.merge[UNDER_TEST], &rec.poses[UNDER_TEST]));
                total += t0.elapsed();
            }
            total
        })
    });

    // Steps 3-4 against the map of frames 0-8.
    let mut map = new_map(&mut map_arena);
    for k in 0..UNDER_TEST {
        map.update(&rec.merge[k], &rec.poses[k]);
    }
    let sigma = rec.sigmas[UNDER_TEST];
    let max_distance = cfg.max_correspondence_factor * sigma;
    let pose = rec.poses[UNDER_TEST];
    let queries: Vec<Point<f64>> = source.iter().map(|p| pose * Point::from(*p)).collect();
    g.bench_function("correspondence_search", |b| {
        b.iter(|| {
            let mut found = 0usize;
            for q in &queries {
                found += map.closest_neighbor(q, max_distance).is_some() as usize;
            }
            found
        })
    });
    let mut work = vec![0u64; work_words::<f64>(caps.source_points, false)];
    let one = IcpParams {
        convergence_criterion: 0.0,
        max_iterations: 1,
        budget: None,
        planes: false,
        prior: None,
        stop_on_cycle: false,
    };
    g.bench_function("icp_iteration", |b| {
        b.iter(|| {
            align_points_to_map(
                &Sequential,
                source,
                &mut work,
                &map.view(),
                &pose,
                max_distance,
                cfg.kernel_scale * sigma,
                &one,
            )
        })
    });
    let full = IcpParams {
        convergence_criterion: cfg.convergence_criterion,
        max_iterations: cfg.max_iterations,
        budget: None,
        planes: false,
        prior: None,
        stop_on_cycle: false,
    };
    let guess = rec.guesses[UNDER_TEST];
    g.bench_function("registration", |b| {
        b.iter(|| {
            align_points_to_map(
                &Sequential,
                source,
                &mut work,
                &map.view(),
                &guess,
                max_distance,
                cfg.kernel_scale * sigma,
                &full,
            )
        })
    });

    // The whole frame: frame 9 after frames 7 and 8 (registered untimed in each setup).
    whole_frame::<f64>(&mut g, "whole_frame_f64", &scans);
    whole_frame::<f32>(&mut g, "whole_frame_f32", &scans);
    g.finish();
}

fn whole_frame<T: Real>(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    scans: &[common::Scan],
) {
    let caps = Capacities::FULL_SCALE;
    let pts: Vec<Vec<[T; 3]>> = scans
        .iter()
        .map(|s| {
            s.points
                .iter()
                .map(|p| [T::of(p[0]), T::of(p[1]), T::of(p[2])])
                .collect()
        })
        .collect();
    let mut arena = vec![0u64; caps.arena_words::<T, Exact>()];
    g.bench_function(name, |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let mut odom =
                    Odometry::<T, Exact, _>::new(Config::new(T::of(100.0)), caps, &mut arena[..])
                        .unwrap();
                for p in &pts[UNDER_TEST - 2..UNDER_TEST] {
                    odom.register_frame(p, None).unwrap();
                }
                let t0 = Instant::now();
                black_box(odom.register_frame(&pts[UNDER_TEST], None).unwrap());
                total += t0.elapsed();
            }
            total
        })
    });
}

criterion_group!(benches, stages);
criterion_main!(benches);
