use super::*;
use crate::config::{Capacities, Config};
use crate::geometry::Pose;
use crate::local_map::Exact;
use crate::registration::Sequential;
use crate::testutil::{yard, Rng};
use std::println;
use std::vec;
use std::vec::Vec;

type Odom = Odometry<f64, Exact, Vec<u64>>;

fn odometry() -> Odom {
    let caps = Capacities {
        scan_points: 4000,
        merge_points: 4000,
        source_points: 2000,
        map_voxels: 8192,
        map_points: 32768,
        plane_terms: false,
    };
    let words = vec![0u64; caps.arena_words::<f64, Exact>()];
    Odometry::new(Config::new(50.0), caps, words).unwrap()
}

/// Samples at `hz` over `[t0, t1]` of a body turning at `rate(t)` (LiDAR axes), seen by an
/// IMU turned by `r_li` and offset by `offset` s, plus `bias` (IMU axes).
fn samples(
    t0: f64,
    t1: f64,
    hz: f64,
    rate: impl Fn(f64) -> [f64; 3],
    r_li: UnitQuaternion<f64>,
    offset: f64,
    bias: [f64; 3],
) -> Vec<ImuSample<f64>> {
    let n = ((t1 - t0) * hz).round() as usize;
    (0..n)
        .map(|k| {
            let t = t0 + (k as f64 + 0.5) / hz;
            let w = r_li.inverse() * Vector3::from(rate(t)) + Vector3::from(bias);
            ImuSample {
                time: t + offset,
                gyro: w.into(),
                accel: [0.0; 3],
            }
        })
        .collect()
}

/// [`samples`] of an IMU with the LiDAR's axes and clock and no bias.
fn aligned(t0: f64, t1: f64, hz: f64, rate: impl Fn(f64) -> [f64; 3]) -> Vec<ImuSample<f64>> {
    samples(t0, t1, hz, rate, UnitQuaternion::identity(), 0.0, [0.0; 3])
}

#[test]
fn a_constant_rate_integrates_to_its_rotation_through_a_turned_mount_and_a_clock_offset() {
    let r_li = UnitQuaternion::from_euler_angles(0.3, -1.1, 2.0);
    let prior = GyroPrior::new(ImuConfig {
        lidar_from_imu: r_li,
        time_offset: 0.25,
        ..ImuConfig::new()
    });
    let w = [0.4, -1.5, 2.5];
    let s = samples(1.0, 1.1, 200.0, |_| w, r_li, 0.25, [0.0; 3]);
    let (q, _) = prior.rotation(&s, 1.0, 1.1).unwrap();
    let want = UnitQuaternion::from_scaled_axis(Vector3::from(w) * 0.1);
    let err = q.angle_to(&want);
    println!("constant rate: {err:.1e} rad off (tolerance 1e-12)");
    assert!(err < 1e-12);
}

#[test]
fn gaps_missing_or_disordered_samples_give_no_prior_and_leave_the_model() {
    let mut odom = odometry();
    let delta = Pose::new(Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.0, 0.0, 0.1));
    assert!(odom.set_last_delta(delta));
    // As stored (renormalised: under Miri, whose sin and cos are a few ulps off, that moves bits).
    let delta = *odom.last_delta();
    let mut prior = GyroPrior::new(ImuConfig::new());
    let good = aligned(0.0, 0.1, 100.0, |_| [0.0, 0.0, 1.0]);
    assert_eq!(prior.before_frame(&mut odom, &good, 0.0), Prior::First);
    assert_eq!(prior.before_frame(&mut odom, &[], 0.1), Prior::NoSamples);
    let mut holed = good.clone();
    holed.drain(2..8);
    assert_eq!(prior.before_frame(&mut odom, &holed, 0.2), Prior::Gap);
    // The samples end 60 ms before the sweep does.
    let early = aligned(0.2, 0.24, 100.0, |_| [0.0; 3]);
    assert_eq!(prior.before_frame(&mut odom, &early, 0.3), Prior::Gap);
    let mut swapped = aligned(0.3, 0.4, 100.0, |_| [0.0; 3]);
    swapped.swap(3, 4);
    assert_eq!(
        prior.before_frame(&mut odom, &swapped, 0.4),
        Prior::BadSamples
    );
    let mut nan = aligned(0.4, 0.5, 100.0, |_| [0.0; 3]);
    nan[5].gyro[1] = f64::NAN;
    assert_eq!(prior.before_frame(&mut odom, &nan, 0.5), Prior::BadSamples);
    assert_eq!(*odom.last_delta(), delta, "the model is untouched");
    // A good frame replaces the rotation only.
    let s = aligned(0.5, 0.6, 100.0, |_| [0.0, 0.0, 2.0]);
    assert_eq!(prior.before_frame(&mut odom, &s, 0.6), Prior::Used(10));
    assert_eq!(odom.last_delta().translation, delta.translation);
    assert!((odom.last_delta().rotation.angle() - 0.2).abs() < 1e-12);
}

#[test]
#[cfg_attr(
    miri,
    ignore = "over ten minutes of software floating point under Miri; no unsafe on this path"
)]
fn the_bias_estimate_converges_to_the_gyroscopes_bias() {
    let mut odom = odometry();
    let r_li = UnitQuaternion::from_euler_angles(0.0, 0.0, 1.0);
    let mut prior = GyroPrior::new(ImuConfig {
        lidar_from_imu: r_li,
        ..ImuConfig::new()
    });
    let bias = [0.01, -0.007, 0.004];
    let rate = |t: f64| [0.3 * t.sin(), 0.2, -0.5 * (2.0 * t).cos()];
    prior.before_frame(&mut odom, &[], 0.0);
    let mut residuals = Vec::new();
    for k in 1..=60 {
        let (t0, t1) = ((k - 1) as f64 * 0.1, k as f64 * 0.1);
        let s = samples(t0, t1, 400.0, rate, r_li, 0.0, bias);
        assert_eq!(prior.before_frame(&mut odom, &s, t1), Prior::Used(40));
        // ICP found the true rotation.
        let truth = GyroPrior::new(ImuConfig::new())
            .rotation(&aligned(t0, t1, 400.0, rate), t0, t1)
            .unwrap()
            .0;
        let mut d = *odom.last_delta();
        d.rotation = truth;
        odom.set_last_delta(d);
        residuals.push(prior.after_frame(&odom).unwrap());
    }
    // The disagreement starts at the bias and shrinks as the estimate learns it.
    let want = r_li * Vector3::from(bias);
    println!(
        "disagreement: {:.2e} rad/s on frame 1, {:.2e} on frame 60",
        residuals[0], residuals[59]
    );
    assert!((residuals[0] / want.norm() - 1.0).abs() < 0.02 && residuals[59] < 0.01 * residuals[0]);
    // Nothing pending: nothing learnt.
    assert_eq!(prior.after_frame(&odom), None);
    let err = (Vector3::from(prior.bias()) - want).norm();
    println!(
        "bias after 60 frames: {:?} (true {want:?}), {err:.1e} rad/s off",
        prior.bias()
    );
    assert!(err < 1e-4 * want.norm().max(1.0) + 2e-5);
    // Reset: no bias, no sweep before the next.
    prior.reset();
    assert_eq!(prior.bias(), [0.0; 3]);
    assert_eq!(
        prior.before_frame(&mut odom, &aligned(6.0, 6.1, 400.0, rate), 6.1),
        Prior::First
    );
}

/// The uneven turn below: yaw (rad) at `t` (s), and its rate.
fn uneven_yaw(t: f64) -> f64 {
    3.0 * t + 0.8 * (7.0 * t).sin()
}
fn uneven_rate(t: f64) -> [f64; 3] {
    [0.0, 0.0, 3.0 + 5.6 * (7.0 * t).cos()]
}

#[test]
fn the_sweep_rotation_follows_an_uneven_turn_point_by_point() {
    let (t0, t1) = (0.3, 0.4);
    let prior = GyroPrior::new(ImuConfig::new());
    let (_, sweep) = prior
        .rotation(&aligned(t0, t1, 400.0, uneven_rate), t0, t1)
        .unwrap();
    let yaw_to_end = |s: f64| uneven_yaw(t0 + s * (t1 - t0)) - uneven_yaw(t1);
    let (mut worst, mut constant) = (0.0f64, 0.0f64);
    for i in 0..=100 {
        let s = i as f64 / 100.0;
        let want = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw_to_end(s));
        worst = worst.max(sweep.at(s).angle_to(&want));
        // The constant rate the sweep's whole turn gives.
        constant = constant.max(((1.0 - s) * yaw_to_end(0.0) - yaw_to_end(s)).abs());
    }
    println!(
        "uneven turn: sweep rotation {worst:.1e} rad off at worst (tolerance 2e-3); a constant \
         rate {constant:.1e} rad"
    );
    assert!(worst < 2e-3 && constant > 20.0 * worst);
}

/// A sensor in the yard turning fast and unevenly (yaw rate 3 rad/s and more, changing within a
/// sweep), each point seen at its own time: the end poses' worst error with `prior`, if any.
fn turning_run(prior: Option<ImuConfig<f64>>) -> f64 {
    let mut scene = vec![[0.0; 3]; 4000];
    let n = yard(&mut scene);
    let (yaw, rate) = (uneven_yaw, uneven_rate);
    let at = |t: f64| {
        Pose::new(
            Vector3::new(0.5 * t, 0.2 * t, 0.0),
            Vector3::new(0.0, 0.0, yaw(t)),
        )
    };
    let mut odom = odometry();
    let with_prior = prior.is_some();
    let mut prior = GyroPrior::new(prior.unwrap_or_default());
    let mut rng = Rng(7);
    let mut worst: f64 = 0.0;
    for k in 0..25 {
        let (t0, t1) = (k as f64 * 0.1, (k + 1) as f64 * 0.1);
        let mut points = Vec::with_capacity(n);
        let mut stamps = Vec::with_capacity(n);
        for p in &scene[..n] {
            let t = t0 + 0.1 * rng.next();
            let local = at(t).inverse() * crate::geometry::Point::from(*p);
            points.push([local.x, local.y, local.z]);
            stamps.push(t);
        }
        if with_prior {
            let s = aligned(t0, t1, 400.0, rate);
            prior.before_frame(&mut odom, &s, t1);
        }
        let report = odom.register_frame(&points, Some(&stamps)).unwrap();
        prior.after_frame(&odom);
        let truth = at(0.1).inverse() * at(t1);
        worst = worst.max((report.pose.translation.vector - truth.translation.vector).norm());
    }
    worst
}

#[test]
#[cfg_attr(miri, ignore = "minutes per ICP run under Miri")]
fn a_fast_uneven_turn_is_tracked_with_the_prior_and_lost_without() {
    let mean_rate = ImuConfig {
        point_deskew: false,
        ..ImuConfig::new()
    };
    let (with, mean, without) = (
        turning_run(Some(ImuConfig::new())),
        turning_run(Some(mean_rate)),
        turning_run(None),
    );
    println!(
        "25 frames turning at 3 +- 5.6 rad/s: worst position error {with:.3} m with the prior, \
         {mean:.3} m deskewing at its mean rate, {without:.3} m without"
    );
    assert!(with < 0.25, "{with}");
    assert!(mean > 1.15 * with, "{mean} vs {with}");
    assert!(without > 4.0 * with, "{without} vs {with}");
}

/// A sensor in the yard on a small circle (so the kept translation errs by 0.2 m each frame)
/// while turning, with the gyroscope for `imu_frames` frames and then without: each frame's
/// `sigma`.
fn sigmas_through_a_dropout(imu_frames: usize) -> (Vec<f64>, Odom) {
    let mut scene = vec![[0.0; 3]; 4000];
    let n = yard(&mut scene);
    let w = 2.0 * core::f64::consts::PI;
    let at = |t: f64| {
        Pose::new(
            Vector3::new(0.5 * (w * t).sin(), 0.5 * (w * t).cos(), 0.0),
            Vector3::new(0.0, 0.0, 0.4 * t),
        )
    };
    let mut odom = odometry();
    let mut prior = GyroPrior::new(ImuConfig::new());
    let mut sigmas = Vec::new();
    for k in 0..imu_frames + 2 {
        let t1 = (k + 1) as f64 * 0.1;
        let points: Vec<[f64; 3]> = scene[..n]
            .iter()
            .map(|p| {
                let local = at(t1).inverse() * crate::geometry::Point::from(*p);
                [local.x, local.y, local.z]
            })
            .collect();
        let s = if k < imu_frames {
            aligned(t1 - 0.1, t1, 200.0, |_| [0.0, 0.0, 0.4])
        } else {
            Vec::new()
        };
        prior.before_frame(&mut odom, &s, t1);
        sigmas.push(odom.register_frame(&points, None).unwrap().sigma);
        prior.after_frame(&odom);
    }
    (sigmas, odom)
}

#[test]
#[cfg_attr(miri, ignore = "an ICP run per frame")]
fn after_the_imu_drops_out_the_constant_velocity_model_is_gated_by_its_own_threshold() {
    let tau_0 = Config::<f64>::new(50.0).initial_threshold;
    let (sigmas, mut odom) = sigmas_through_a_dropout(12);
    let (with, after) = (sigmas[11], sigmas[12]);
    println!("sigma {with:.3} on the last frame with the gyroscope, {after:.3} on the first without (tau_0 {tau_0})");
    // The measured predictions' errors were counted and brought their threshold down...
    assert!(with < 0.5 * tau_0, "{sigmas:?}");
    // ...and the constant-velocity model's, never used since the first frame, is still tau_0.
    assert_eq!(after, tau_0, "{sigmas:?}");
    // A measured prediction holds for one frame: a skipped frame or kiss-icp's assignable
    // `last_delta` goes back to the constant-velocity model's threshold.
    let (cv, delta) = (odom.sigma(), *odom.last_delta());
    assert!(odom.set_measured_delta(delta));
    // The measured predictions' threshold as the last of them left it.
    assert!(odom.sigma() <= with && cv > with, "{} {cv}", odom.sigma());
    odom.skip_frame();
    assert_eq!(odom.sigma(), cv);
    assert!(odom.set_measured_delta(delta) && odom.set_last_delta(delta));
    assert_eq!(odom.sigma(), cv);
}

#[test]
#[cfg_attr(miri, ignore = "an ICP run per frame")]
fn a_skipped_frame_advances_the_pose_by_the_model_and_is_counted() {
    let (_, mut odom) = sigmas_through_a_dropout(2);
    let (pose, delta, frames) = (*odom.last_pose(), *odom.last_delta(), odom.frames());
    assert!(delta.translation.vector.norm() > 0.05, "{delta:?}");
    let skipped = odom.skip_frame();
    let want = pose * delta;
    let off = (skipped.translation.vector - want.translation.vector).norm();
    assert!(
        off < 1e-12 && skipped.rotation.angle_to(&want.rotation) < 1e-12,
        "{off}"
    );
    assert_eq!(*odom.last_pose(), skipped);
    assert_eq!(odom.frames(), frames + 1);
}

#[test]
fn each_outcome_has_its_own_report_name() {
    let all = [
        Prior::Used(3),
        Prior::First,
        Prior::NoSamples,
        Prior::Gap,
        Prior::BadSamples,
    ];
    let names = all.map(Prior::name);
    assert_eq!(names, ["used", "first", "no_samples", "gap", "bad_samples"]);
}

#[test]
fn a_measured_frame_keeps_the_reference_prediction_and_teaches_the_bias_nothing() {
    let rate = |_| [0.0, 0.0, 2.0];
    let mut prior = GyroPrior::new(ImuConfig::new());
    let mut odom = odometry();
    let before = *odom.last_delta();
    assert_eq!(
        prior.measure_frame(&mut odom, &aligned(0.0, 0.1, 400.0, rate), 0.1),
        Prior::First
    );
    let p = prior.measure_frame(&mut odom, &aligned(0.1, 0.2, 400.0, rate), 0.2);
    assert_eq!(p, Prior::Used(40));
    // The motion model is untouched: the reference's prediction.
    assert_eq!(*odom.last_delta(), before);
    // The rotation is measured all the same: 2 rad/s over 0.1 s about z.
    let (q, dt) = prior.measured().unwrap();
    let err = (q.scaled_axis() - Vector3::new(0.0, 0.0, 0.2)).norm();
    println!("measured rotation {:?}, {err:.1e} rad off", q.scaled_axis());
    assert!(err < 1e-9 && (dt - 0.1).abs() < 1e-12);
    // ICP turned by nothing: a used prior would learn a bias of 0.2 rad/s, a measured one none.
    assert_eq!(prior.after_frame(&odom), None);
    assert_eq!(prior.bias(), [0.0; 3]);
    // And a frame the caller discards teaches nothing either.
    prior.before_frame(&mut odom, &aligned(0.2, 0.3, 400.0, rate), 0.3);
    assert!(prior.measured().is_some());
    prior.discard();
    assert_eq!(prior.after_frame(&odom), None);
    assert_eq!(prior.bias(), [0.0; 3]);
}

/// The yard seen from frame `k` of a drive of 0.3 m and 0.04 rad a frame.
fn yard_scan(k: usize) -> Vec<[f64; 3]> {
    let mut scene = vec![[0.0; 3]; 4000];
    let n = yard(&mut scene);
    let at = Pose::new(
        Vector3::new(0.3 * k as f64, 0.05 * k as f64, 0.0),
        Vector3::new(0.0, 0.0, 0.04 * k as f64),
    );
    scene[..n]
        .iter()
        .map(|p| {
            let local = at.inverse() * crate::geometry::Point::from(*p);
            [local.x, local.y, local.z]
        })
        .collect()
}

#[test]
#[cfg_attr(miri, ignore = "an ICP run per frame")]
fn a_refused_registration_is_the_fallbacks_and_an_accepted_one_the_predictions() {
    let (mut a, mut b) = (odometry(), odometry());
    for k in 0..3 {
        let scan = yard_scan(k);
        assert_eq!(a.register_frame(&scan, None), b.register_frame(&scan, None));
    }
    // A wrong measured motion: a quarter turn the wrong way.
    let wrong = Pose::new(Vector3::zeros(), Vector3::new(0.0, 0.0, -1.5));
    let scan = yard_scan(3);
    // Refused: registered again from the fallback, as `b` with that motion set: the same bits.
    let (fallback, before) = (*a.last_delta(), *a.last_pose());
    assert!(a.set_measured_delta(wrong));
    let mut seen = None;
    let (refused, accepted) = a
        .register_frame_checked(&Sequential, &scan, None, fallback, false, |m, judge| {
            assert!(judge.is_none());
            seen = Some(*m);
            false
        })
        .unwrap();
    assert!(!accepted);
    assert!(b.set_last_delta(fallback));
    let want = b.register_frame(&scan, None).unwrap();
    assert_eq!(refused, want);
    assert_eq!((a.map().points(), a.sigma()), (b.map().points(), b.sigma()));
    // `accept` saw the first registration's motion, which the wrong prediction led astray.
    let seen = seen.unwrap();
    let good = before.inverse() * want.pose;
    println!(
        "motion registered from the wrong prediction: {:.3} rad from the fallback's",
        seen.rotation.angle_to(&good.rotation)
    );
    assert!(seen.rotation.angle_to(&good.rotation) > 0.01);
    // Accepted: the frame is the prediction's, as `register_frame` gives it.
    let (mut c, mut d) = (odometry(), odometry());
    for k in 0..3 {
        let scan = yard_scan(k);
        c.register_frame(&scan, None).unwrap();
        d.register_frame(&scan, None).unwrap();
    }
    let fallback = *c.last_delta();
    assert!(c.set_measured_delta(wrong) && d.set_measured_delta(wrong));
    // Against the fallback's registration: `accept` gets it (the motion `b` registered), and
    // the prediction's registration, accepted, is the same bits as without it.
    let mut judged = None;
    let (kept, accepted) = c
        .register_frame_checked(&Sequential, &scan, None, fallback, true, |_, judge| {
            judged = judge.copied();
            true
        })
        .unwrap();
    assert!(accepted);
    assert_eq!(kept, d.register_frame(&scan, None).unwrap());
    assert_ne!(kept.pose, want.pose);
    let judged = judged.unwrap();
    assert!((judged.translation.vector - good.translation.vector).norm() < 1e-12);
    assert!(judged.rotation.angle_to(&good.rotation) < 1e-12);
    assert_eq!((c.map().points(), c.sigma()), (d.map().points(), d.sigma()));
}
