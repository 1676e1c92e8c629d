//! Whole-pipeline properties of `Odometry`: it tracks, it is deterministic, and bad input is
//! skipped, counted and reported without disturbing the pose.

use crate::common;

use common::*;
use kiss_odom_core::{
    Capacities, Config, Exact, Flag, FrameError, Odometry, Pose, Quantized, StampProblem, Status,
};

const RANGE: f64 = 40.0;
const FRAMES: usize = 20;

fn scans() -> Vec<Vec<[f64; 3]>> {
    let s = street(7);
    (0..FRAMES).map(|i| scan(&s, i, RANGE)).collect()
}

#[test]
fn odometry_tracks_an_accelerating_sensor_within_a_centimetre() {
    // The map keeps one point per alpha-voxel, so source points rarely have their exact twin
    // in it: point-to-point ICP then lands within the sampling noise, a few millimetres.
    let poses = run::<f64, Exact>(Config::new(RANGE), caps(), &scans());
    let worst = (0..FRAMES)
        .map(|i| error_at(&poses[i], i))
        .fold(0.0, f64::max);
    println!("worst translation error over {FRAMES} frames: {worst:.2e} m (allowed 1e-2)");
    assert!(worst < 1e-2);
}

#[test]
fn two_runs_give_bitwise_equal_poses() {
    let s = scans();
    let a = run::<f64, Exact>(Config::new(RANGE), caps(), &s);
    let b = run::<f64, Exact>(Config::new(RANGE), caps(), &s);
    assert_eq!(a, b);
}

#[test]
fn non_finite_points_are_skipped_counted_and_change_nothing() {
    let clean = scans();
    let mut dirty = clean.clone();
    for (i, s) in dirty.iter_mut().enumerate() {
        s.insert(i % 5, [f64::NAN, 1.0, 2.0]);
        s.push([1.0, f64::INFINITY, 0.0]);
        s.push([f64::NEG_INFINITY, f64::NAN, f64::NAN]);
    }
    let want = run::<f64, Exact>(Config::new(RANGE), caps(), &clean);
    let caps = caps();
    let mut arena = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut odom =
        Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps, &mut arena[..]).unwrap();
    for (i, s) in dirty.iter().enumerate() {
        let r = odom.register_frame(s, None).unwrap();
        assert_eq!(r.dropped.non_finite, 3);
        assert!(r.status.contains(Flag::InvalidPoints));
        assert_eq!(r.pose, want[i], "frame {i}");
    }
}

#[test]
fn empty_and_out_of_range_scans_are_errors_that_leave_the_state_untouched() {
    let s = scans();
    let caps = caps();
    let mut arena = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut odom =
        Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps, &mut arena[..]).unwrap();
    for frame in &s[..5] {
        odom.register_frame(frame, None).unwrap();
    }
    let before = *odom.pose();
    let far = vec![[1e30, 0.0, 0.0], [0.0, 500.0, 0.0], [0.0, 0.0, 0.0]];
    for bad in [&vec![], &far] {
        assert_eq!(odom.register_frame(bad, None), Err(FrameError::EmptyScan));
        assert_eq!(*odom.pose(), before);
        assert_eq!(odom.frames(), 5);
    }
    // The run continues as if the bad scans had never arrived.
    let rest = run::<f64, Exact>(Config::new(RANGE), caps, &s);
    for (i, frame) in s.iter().enumerate().skip(5) {
        assert_eq!(odom.register_frame(frame, None).unwrap().pose, rest[i]);
    }
}

#[test]
fn skip_frame_advances_by_the_constant_velocity_model() {
    let s = scans();
    let caps = caps();
    let mut arena = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut odom =
        Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps, &mut arena[..]).unwrap();
    for frame in &s[..6] {
        odom.register_frame(frame, None).unwrap();
    }
    let predicted = *odom.pose() * *odom.last_delta();
    let skipped = odom.skip_frame();
    // Equal up to the quaternion renormalisation applied to every new pose.
    assert!(gap(&skipped, &predicted) < 1e-15);
    assert!(skipped.rotation.angle_to(&predicted.rotation) < 1e-15);
    // The next real scan registers from the prediction and lands on the truth again.
    let r = odom.register_frame(&s[7], None).unwrap();
    println!(
        "error after a skipped frame: {:.2e} m",
        error_at(&r.pose, 7)
    );
    assert!(error_at(&r.pose, 7) < 1e-2);
}

#[test]
fn scan_motion_is_the_model_a_scan_was_deskewed_with_not_the_one_it_produced() {
    let s = scans();
    let caps = caps();
    let mut arena = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut odom =
        Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps, &mut arena[..]).unwrap();
    assert_eq!(*odom.scan_motion(), Pose::identity());
    for frame in &s[..5] {
        let before = *odom.last_delta();
        odom.register_frame(frame, None).unwrap();
        assert_eq!(*odom.scan_motion(), before);
    }
    // The sensor accelerates: the model a scan started from is not the motion it found.
    assert!(gap(odom.scan_motion(), odom.last_delta()) > 1e-3);
    odom.reset();
    assert_eq!(*odom.scan_motion(), Pose::identity());
}

#[test]
fn unusable_timestamps_are_ignored_reported_and_do_not_poison_the_pose() {
    let s = scans();
    let want = run::<f64, Exact>(Config::new(RANGE), caps(), &s);
    let caps = caps();
    let mut arena = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut odom =
        Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps, &mut arena[..]).unwrap();
    for (i, frame) in s.iter().enumerate() {
        let n = frame.len();
        // Wrong lengths use rising stamps, so only the length can make them unusable.
        let rising = |m: usize| (0..m).map(|k| k as f64 * 1e-5).collect::<Vec<f64>>();
        let (stamps, problem) = match i % 4 {
            0 => (vec![5.0; n], StampProblem::Constant),
            1 => (
                (0..n)
                    .map(|k| if k == 3 { f64::NAN } else { k as f64 })
                    .collect(),
                StampProblem::NonFinite,
            ),
            2 => (rising(n + 2), StampProblem::Length), // too many
            _ => (rising(n / 2), StampProblem::Length), // too few
        };
        let r = odom.register_frame(frame, Some(&stamps)).unwrap();
        assert!(r.status.contains(Flag::TimestampsIgnored) && !r.deskewed);
        assert_eq!(r.stamp_problem, Some(problem), "frame {i}");
        assert_eq!(r.pose, want[i], "frame {i}");
    }
}

#[test]
fn tiny_scans_and_huge_coordinates_never_panic_and_keep_the_pose_finite() {
    let s = scans();
    let caps = caps();
    let mut arena = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut odom =
        Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps, &mut arena[..]).unwrap();
    for frame in &s[..4] {
        odom.register_frame(frame, None).unwrap();
    }
    let odd: [&[[f64; 3]]; 4] = [
        &[[3.0, 0.0, 0.0]],
        &[[3.0, 0.0, 0.0]; 50],
        &[[1e30, 1e30, 1e30], [4.0, 4.0, 0.0]],
        &[[0.0, 0.0, 0.0], [1e-300, 0.0, 0.0], [2.0, 1.0, 0.0]],
    ];
    for scan in odd {
        let r = odom.register_frame(scan, None).unwrap();
        let t = r.pose.translation.vector;
        assert!(
            t.iter().all(|v| v.is_finite()) && r.pose.rotation.coords.iter().all(|v| v.is_finite())
        );
    }
}

#[test]
fn full_buffers_drop_by_their_documented_rules_and_say_so() {
    let tiny = Capacities {
        scan_points: 5_000,
        merge_points: 1_500,
        source_points: 300,
        map_voxels: 900,
        map_points: 2_000,
        plane_terms: false,
    };
    let s = scans();
    let mut arena = vec![0u64; tiny.arena_words::<f64, Exact>()];
    let mut odom =
        Odometry::<f64, Exact, _>::new(Config::new(RANGE), tiny, &mut arena[..]).unwrap();
    let mut seen = Status::default();
    for frame in &s {
        let r = odom.register_frame(frame, None).unwrap();
        assert!(r.merge_points as usize <= tiny.merge_points);
        assert!(r.source_points as usize <= tiny.source_points);
        assert!(r.map_voxels as usize <= tiny.map_voxels);
        assert!(r.map_points as usize <= tiny.map_points);
        assert_eq!(
            r.dropped.truncated as usize,
            frame.len().saturating_sub(tiny.scan_points)
        );
        seen = r.status.flags().chain(seen.flags()).collect();
        assert!(r.pose.translation.vector.iter().all(|v| v.is_finite()));
    }
    assert!(seen.contains(Flag::Capacity) && seen.contains(Flag::ScanTruncated));
    let hw = odom.high_water();
    assert_eq!(hw.merge_points, tiny.merge_points);
    // Starved of points, the pose degrades; the report must have said why.
    let err = error_at(odom.pose(), FRAMES - 1);
    println!("error with tiny capacities: {err:.3} m (normal capacities: < 1e-2)");
}

#[test]
fn single_precision_tracks_within_a_centimetre() {
    let s: Vec<Vec<[f32; 3]>> = scans().iter().map(|s| narrow::<f32>(s)).collect();
    let poses = run::<f32, Exact>(Config::new(RANGE as f32), caps(), &s);
    let worst = (0..FRAMES)
        .map(|i| {
            let p = &poses[i];
            let t = p.translation.vector;
            let q = p.rotation.coords;
            let wide = Pose::from_parts(
                nalgebra::Translation3::new(t.x as f64, t.y as f64, t.z as f64),
                nalgebra::UnitQuaternion::new_normalize(nalgebra::Quaternion::new(
                    q.w as f64, q.x as f64, q.y as f64, q.z as f64,
                )),
            );
            error_at(&wide, i)
        })
        .fold(0.0, f64::max);
    println!("f32 worst translation error: {worst:.2e} m (allowed 2e-2)");
    assert!(worst < 2e-2);
}

#[test]
fn quantised_map_points_track_like_exact_ones() {
    let poses = run::<f64, Quantized>(Config::new(RANGE), caps(), &scans());
    let exact = run::<f64, Exact>(Config::new(RANGE), caps(), &scans());
    let worst = (0..FRAMES)
        .map(|i| error_at(&poses[i], i))
        .fold(0.0, f64::max);
    let apart = (0..FRAMES)
        .map(|i| gap(&poses[i], &exact[i]))
        .fold(0.0, f64::max);
    println!("quantised: worst error {worst:.2e} m, worst gap to exact storage {apart:.2e} m");
    assert!(worst < 1e-2 && apart < 1e-3);
}

#[test]
fn state_bytes_are_fixed_at_construction() {
    let caps = caps();
    let mut arena = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut odom =
        Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps, &mut arena[..]).unwrap();
    let before = odom.state_bytes();
    for frame in &scans() {
        odom.register_frame(frame, None).unwrap();
    }
    assert_eq!(odom.state_bytes(), before);
    assert!(before >= caps.arena_words::<f64, Exact>() * 8);
}

#[test]
fn a_short_arena_is_refused_not_overrun() {
    let caps = caps();
    let mut arena = vec![0u64; caps.arena_words::<f64, Exact>() - 1];
    let r = Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps, &mut arena[..]);
    assert_eq!(r.err(), Some(kiss_odom_core::ConfigError::ArenaTooSmall));
}

#[test]
fn a_scan_pushed_in_pieces_registers_to_the_same_bits_as_one_slice() {
    let s = scans();
    // Per-point times in an arbitrary unit and offset, so deskewing runs on every frame.
    let stamps: Vec<Vec<f64>> = s
        .iter()
        .map(|f| (0..f.len()).map(|k| 1e6 + k as f64 * 0.37).collect())
        .collect();
    let caps = caps();
    let mut a = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut b = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut whole = Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps, &mut a[..]).unwrap();
    let mut parts = Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps, &mut b[..]).unwrap();
    for (frame, t) in s.iter().zip(&stamps) {
        let want = whole.register_frame(frame, Some(t)).unwrap();
        let span = (t[0], t[t.len() - 1]);
        let mut input = parts.begin_frame(Some(span));
        for (pts, ts) in frame.chunks(1000).zip(t.chunks(1000)) {
            input.push(pts, Some(ts));
        }
        let got = input.finish().unwrap();
        assert!(got.deskewed && want.deskewed);
        assert_eq!(got.pose, want.pose);
        assert_eq!(
            (got.merge_points, got.map_points),
            (want.merge_points, want.map_points)
        );
    }
}

#[test]
fn an_unfinished_frame_leaves_the_odometry_untouched() {
    let s = scans();
    let caps = caps();
    let mut arena = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut odom =
        Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps, &mut arena[..]).unwrap();
    let want = run::<f64, Exact>(Config::new(RANGE), caps, &s);
    for (i, frame) in s.iter().enumerate() {
        // A partial scan pushed and then abandoned changes nothing.
        {
            let mut input = odom.begin_frame(None);
            input.push(&frame[..frame.len() / 3], None);
        }
        assert_eq!(odom.register_frame(frame, None).unwrap().pose, want[i]);
    }
}

#[test]
fn assigned_pose_and_velocity_steer_the_next_prediction_and_clear_map_reseeds() {
    let s = scans();
    let caps = caps();
    let mut arena = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut odom =
        Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps, &mut arena[..]).unwrap();
    for frame in &s[..4] {
        odom.register_frame(frame, None).unwrap();
    }
    let (pose, delta) = (*odom.last_pose(), *odom.last_delta());
    // Non-finite assignments are refused and change nothing.
    let mut bad = pose;
    bad.translation.vector.x = f64::NAN;
    assert!(!odom.set_last_pose(bad) && !odom.set_last_delta(bad));
    assert_eq!((*odom.last_pose(), *odom.last_delta()), (pose, delta));
    // A zero velocity makes the prediction the last pose: with the map cleared, the next scan
    // has nothing to register against and lands exactly there (kiss-icp's empty-map rule).
    assert!(odom.set_last_delta(Pose::identity()));
    odom.clear_map();
    assert!(odom.map().is_empty());
    let r = odom.register_frame(&s[4], None).unwrap();
    println!("pose after clear_map: {:?} (expected {:?})", r.pose, pose);
    assert_eq!(r.pose.translation, pose.translation);
    assert!(!odom.map().is_empty());
    // An assigned pose is the next prediction's base.
    let moved = Pose::translation(1.0, 2.0, 3.0);
    assert!(odom.set_last_pose(moved) && odom.set_last_delta(Pose::identity()));
    odom.clear_map();
    let r = odom.register_frame(&s[5], None).unwrap();
    assert_eq!(r.pose.translation, moved.translation);
}
