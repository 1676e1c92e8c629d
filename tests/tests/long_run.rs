//! A long run at the microcontroller budget: 10,000 simulated urban sweeps through the core at
//! `Capacities::SMALL` with the configuration that preset is sized for (f32, `Quantized` map
//! points, r_max 50 m, 1 m voxels; `core/src/config.rs`, `embedded/src/workload.rs`).
//!
//! Frames are ray cast in memory one at a time by `kiss_odom::simulate` and dropped after
//! registration; nothing is written to disk. What a long run must not do: panic, produce a
//! non-finite pose, grow its state, exceed a capacity, or slow down as the map ages. Those are
//! asserted; the rates of the first and last 1,000 frames and the drift against the
//! simulator's ground truth are printed. A frame's cost is the CPU time the registering thread
//! spent in the core, not the wall clock: `.ci/run` runs this beside other steps, and their
//! load must not read as a slowdown.
//!
//! Ignored by default (about 3 minutes in release on two cores while the core keeps its
//! speed; a slowdown makes it longer):
//! `cargo test --release -p kiss-odom-tests --test long_run -- --ignored --nocapture`.

use kiss_odom_core::{Capacities, Config, Flag, Odometry, Quantized};
use kiss_odom_sim::{Profile, SimParams, Simulation};
use std::time::Instant;

const FRAMES: usize = 10_000;
/// Frames per throughput window.
const WINDOW: usize = 1_000;
/// r_max of the `SMALL` profile (m).
const RANGE: f64 = 50.0;
/// Most memory the whole test may hold (bytes).
const MEMORY_LIMIT: u64 = 1 << 30;

/// CPU time this thread has used, s.
fn thread_cpu_s() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec that outlives the call, which only writes it.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    assert_eq!(rc, 0, "clock_gettime(CLOCK_THREAD_CPUTIME_ID)");
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

#[test]
fn thread_cpu_time_counts_work_and_not_sleep() {
    let t0 = thread_cpu_s();
    // The sleep is what is measured (its CPU cost), not a wait for anything.
    std::thread::sleep(std::time::Duration::from_millis(200));
    let slept = thread_cpu_s() - t0;
    let mut x = 0u64;
    let t1 = thread_cpu_s();
    while thread_cpu_s() - t1 < 0.05 {
        x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
    }
    let worked = thread_cpu_s() - t1;
    assert!(slept < 0.05, "200 ms of sleep cost {slept} s of CPU");
    assert!(worked >= 0.05, "{worked}");
}

/// Registered frames per second of core time over `secs`.
fn rate(secs: &[f64]) -> f64 {
    secs.len() as f64 / secs.iter().sum::<f64>()
}

#[test]
#[ignore = "10,000 frames: run by .ci/run in release"]
fn ten_thousand_urban_frames_at_small_capacities_stay_bounded_finite_and_fast() {
    // The default 64-beam sensor at half the columns (about 30k returns a sweep, like the
    // every-4th-point KITTI scans of the embedded runs) and the profile's range: ray casting
    // then costs about as much as registration, instead of three times as much.
    let mut params = SimParams::new(Profile::Urban, 0, FRAMES as u64);
    params.sensor.columns = 512;
    params.sensor.max_range = RANGE;
    let clock = Instant::now();
    let sim = Simulation::new(params).expect("valid simulation");
    println!(
        "scene and route for {FRAMES} frames built in {:.1} s",
        clock.elapsed().as_secs_f64()
    );

    let caps = Capacities::SMALL;
    let mut config = Config::new(RANGE as f32);
    config.voxel_size = 1.0;
    let mut arena = vec![0u64; caps.arena_words::<f32, Quantized>()];
    let arena_len = arena.len();
    let mut odom = Odometry::<f32, Quantized, _>::new(config, caps, &mut arena[..])
        .expect("SMALL fits its own arena");
    let state_bytes = odom.state_bytes();

    let mut core_secs = Vec::with_capacity(FRAMES);
    // Frames that hit the ICP iteration cap, per window: the usual reason for a slowdown.
    let mut capped = vec![0usize; FRAMES / WINDOW];
    let mut points: Vec<[f32; 3]> = Vec::new();
    let mut flags = [0usize; Flag::ALL.len()];
    let mut dropped_points = 0u64;
    let mut travelled = 0.0;
    let mut worst_step = (0.0f64, 0usize);
    let mut last_gt = sim.ground_truth(0);
    let mut last_est = *odom.pose();
    let mut input_points = 0u64;
    let clock = Instant::now();
    for k in 0..FRAMES {
        let frame = sim.frame(k as u64);
        points.clear();
        points.extend(frame.points.iter().map(|p| [p[0], p[1], p[2]]));
        input_points += points.len() as u64;

        let t0 = thread_cpu_s();
        let result = odom.register_frame(&points, Some(&frame.stamps));
        core_secs.push(thread_cpu_s() - t0);
        let r = result.unwrap_or_else(|e| panic!("frame {k}: {e:?}"));

        let p = r.pose;
        let finite = p.translation.vector.iter().all(|v| v.is_finite())
            && p.rotation.coords.iter().all(|v| v.is_finite());
        assert!(finite, "frame {k}: pose is not finite: {p:?}");
        assert!(
            !r.status.contains(Flag::ScanTruncated),
            "frame {k}: {} points do not fit {} scan points",
            points.len(),
            caps.scan_points
        );
        let hw = odom.high_water();
        assert!(
            hw.merge_points <= caps.merge_points
                && hw.source_points <= caps.source_points
                && hw.map_voxels <= caps.map_voxels
                && hw.map_point_slots <= caps.map_points,
            "frame {k}: high water {hw:?} past capacities {caps:?}"
        );
        assert!(
            r.merge_points as usize <= caps.merge_points
                && r.source_points as usize <= caps.source_points
                && r.map_voxels as usize <= caps.map_voxels
                && r.map_points as usize <= caps.map_points,
            "frame {k}: occupancy past capacities: {r:?}"
        );
        capped[k / WINDOW] += usize::from(r.status.contains(Flag::IterationCap));
        for (flag, n) in Flag::ALL.iter().zip(flags.iter_mut()) {
            *n += usize::from(r.status.contains(*flag));
        }
        let d = r.dropped;
        dropped_points += u64::from(d.merge_full + d.source_full + d.map_points_full);

        // Per-frame motion error against the ground truth.
        let gt = sim.ground_truth(k as u64);
        let true_step = last_gt.inverse() * gt;
        let est_step = last_est.inverse() * p;
        let est_t = est_step.translation.vector.map(f64::from);
        let step_err = (true_step.translation.vector - est_t).norm();
        if step_err > worst_step.0 {
            worst_step = (step_err, k);
        }
        travelled += true_step.translation.vector.norm();
        (last_gt, last_est) = (gt, p);

        if (k + 1) % WINDOW == 0 {
            let rss = kiss_odom::memory::peak_rss_bytes().unwrap_or(0);
            println!(
                "{:>6} frames: {:7.1} frames/s in the core over the last {WINDOW} \
                 ({:3} at the iteration cap), {:6.1} s elapsed, {:.0} m driven, \
                 {:.0} m from the start, peak RSS {:.0} MiB",
                k + 1,
                rate(&core_secs[k + 1 - WINDOW..]),
                capped[k / WINDOW],
                clock.elapsed().as_secs_f64(),
                travelled,
                gt.translation.vector.norm(),
                rss as f64 / f64::from(1 << 20)
            );
        }
    }

    // Final drift against ground truth (both in the frame of the first sweep's end).
    let est = odom.pose();
    let est_t = est.translation.vector.map(f64::from);
    let gt = sim.ground_truth(FRAMES as u64 - 1);
    let drift = (gt.translation.vector - est_t).norm();
    let first = rate(&core_secs[..WINDOW]);
    let last = rate(&core_secs[FRAMES - WINDOW..]);
    let flagged: Vec<String> = Flag::ALL
        .iter()
        .zip(flags)
        .filter(|(_, n)| *n > 0)
        .map(|(flag, n)| format!("{} {n}", flag.name()))
        .collect();
    println!(
        "{FRAMES} frames ({:.0} points each) in {:.1} s; core: first {WINDOW} {first:.1} \
         frames/s, last {WINDOW} {last:.1} frames/s (ratio {:.2}), overall {:.1} frames/s",
        input_points as f64 / FRAMES as f64,
        clock.elapsed().as_secs_f64(),
        last / first,
        rate(&core_secs)
    );
    println!(
        "final drift {drift:.2} m over {travelled:.0} m driven ({:.2} %), worst per-frame \
         motion error {:.3} m at frame {}",
        100.0 * drift / travelled,
        worst_step.0,
        worst_step.1
    );
    println!(
        "flags: {}; points/voxels dropped by capacity rules: {dropped_points}; high water {:?}",
        if flagged.is_empty() {
            "none".into()
        } else {
            flagged.join(", ")
        },
        odom.high_water()
    );

    assert_eq!(odom.state_bytes(), state_bytes, "state size changed");
    assert_eq!(odom.frames(), FRAMES as u64);
    let peak = kiss_odom::memory::peak_rss_bytes();
    println!(
        "state {state_bytes} bytes ({arena_len} arena words); peak RSS {:.0} MiB",
        peak.unwrap_or(0) as f64 / f64::from(1 << 20)
    );
    if let Some(peak) = peak {
        assert!(
            peak < MEMORY_LIMIT,
            "peak RSS {peak} bytes over {MEMORY_LIMIT}"
        );
    }
    assert!(
        last >= 0.5 * first,
        "throughput fell from {first:.1} to {last:.1} frames/s; frames at the ICP iteration \
         cap per {WINDOW}: {capped:?}"
    );
}
