use super::*;

/// A frame of 0.1 s turning by `icp`, the gyroscope measuring `gyro` (rad) with samples of
/// that mean rate.
fn frame(gyro: Vector3<f64>, icp: Vector3<f64>) -> Measured {
    Measured {
        gyro,
        icp,
        dt: 0.1,
        rate: gyro / 0.1,
    }
}

fn meta() -> FrameMeta {
    FrameMeta {
        index: 7,
        source: "7.bin".into(),
        time: None,
    }
}

/// ICP's rotation over a turning frame: 0.08 rad, mostly about z.
fn turn() -> Vector3<f64> {
    Vector3::new(0.01, -0.02, 0.075)
}

/// A check past its first frame (an agreeing one).
fn started() -> ImuCheck {
    let mut check = ImuCheck::default();
    check.judge(&meta(), &frame(turn(), turn()), false);
    check
}

#[test]
fn the_first_measured_frame_is_judged_with_room_for_its_undeskewed_map() {
    // A dead gyroscope is within the first frame's room (ICP's whole rotation), not the next's.
    let mut check = ImuCheck::default();
    let dead = frame(Vector3::zeros(), turn());
    assert!(check.judge(&meta(), &dead, false).1 && !check.rejecting());
    assert!(!check.judge(&meta(), &dead, false).1 && check.rejecting());
    // Four times ICP's rotation is beyond it, and so is a frame the check refused.
    let mut check = ImuCheck::default();
    let twice = frame(turn() * 4.0, turn());
    assert!(!check.judge(&meta(), &twice, false).1 && check.rejecting());
    let mut check = ImuCheck::default();
    assert!(!check.judge(&meta(), &frame(turn(), turn()), true).1);
    let icp = turn();
    assert_eq!(tolerance(&icp, true), FIRST_FLOOR_RAD + icp.norm());
    assert_eq!(tolerance(&icp, false), FLOOR_RAD + SCALE * icp.norm());
}

#[test]
fn rates_beyond_full_scale_or_not_finite_are_not_plausible() {
    assert!(plausible(&[0.0, 0.0, 0.0]) && plausible(&[20.0, 20.0, 20.0]));
    assert!(plausible(&[FULL_SCALE, 0.0, 0.0]));
    assert!(!plausible(&[FULL_SCALE * 1.0001, 0.0, 0.0]));
    assert!(!plausible(&[1e6, 0.0, 0.0]) && !plausible(&[0.0, f64::NAN, 0.0]));
    assert!(!plausible(&[f64::INFINITY, 0.0, 0.0]));
}

#[test]
fn a_correct_gyroscope_with_bias_noise_and_scale_error_agrees() {
    let mut worst: f64 = 0.0;
    for icp in [
        Vector3::zeros(),
        turn(),
        turn() * 5.0,
        Vector3::new(0.3, 0.0, 0.0),
    ] {
        // A turn-on bias of 0.01 rad/s over 0.1 s, noise and ICP's own error of 0.003 rad,
        // a 3 % scale error.
        let gyro = icp * 1.03 + Vector3::new(0.001, -0.003, 0.002);
        let off = disagreement(&gyro, &icp);
        worst = worst.max(off / tolerance(&icp, false));
        assert!(
            agrees(&gyro, &icp, false),
            "{off} rad off on a turn of {}",
            icp.norm()
        );
    }
    println!("worst disagreement of a correct gyroscope: {worst:.3} of the tolerance");
}

/// Frames after a rejection, registered without the gyroscope: ICP turning by `r` and four
/// other turns, the gyroscope reading each as `read` does; when `lagging`, ICP's first two
/// rotations are short of the truth by half and a quarter (predicted from a frame that turned
/// less) and carry an error of 0.01 rad across.
fn after(
    read: impl Fn(Vector3<f64>) -> Vector3<f64>,
    r: Vector3<f64>,
    lagging: bool,
) -> Vec<Measured> {
    let turns = [
        r,
        Vector3::new(r.z, r.x, -r.y),
        Vector3::new(-r.y, r.z, r.x) * 1.5,
        Vector3::new(r.x, -r.z, r.y) * 0.7,
        Vector3::new(r.y, r.x, r.z) * 1.2,
    ];
    let mut frames: Vec<Measured> = turns.iter().map(|&t| frame(read(t), t)).collect();
    if lagging {
        let across = Vector3::new(0.01, -0.01, 0.0);
        frames[0].icp = frames[0].icp * 0.5 + across;
        frames[1].icp = frames[1].icp * 0.75 + across;
    }
    frames
}

#[test]
fn each_wrong_gyroscope_disagrees_and_is_named() {
    let r = turn();
    let flip = |axes: [f64; 3]| move |g: Vector3<f64>| g.component_mul(&Vector3::from(axes));
    for lagging in [false, true] {
        let cases: [(Vec<Measured>, Cause); 6] = [
            (after(|g| g * 57.2958, r, lagging), Cause::Degrees),
            (after(|_| Vector3::zeros(), r, lagging), Cause::Dead),
            (
                after(flip([1.0, 1.0, -1.0]), r, lagging),
                Cause::FlippedAxis(2),
            ),
            (
                after(flip([-1.0, 1.0, 1.0]), r, lagging),
                Cause::FlippedAxis(0),
            ),
            (
                after(flip([-1.0, -1.0, 1.0]), r, lagging),
                Cause::Rotated180(2),
            ),
            // Another recording's: no reading brings it to ICP's.
            (
                after(|g| Vector3::new(g.y, -g.z, g.x) * 2.0, r, lagging),
                Cause::Unknown,
            ),
        ];
        for (frames, want) in cases {
            let wrong = frames
                .iter()
                .filter(|m| !agrees(&m.gyro, &m.icp, false))
                .count();
            assert!(wrong >= 2, "{want:?}: {wrong} frames disagree");
            assert_eq!(cause(&frames), want, "lagging {lagging}: {frames:?}");
        }
    }
    // A rocking sensor whose ICP rotation about x runs a frame late (a generated drone flight
    // registered without the gyroscope): beside rates 57 times as large, x looks flipped, but
    // the size names deg/s.
    let rocking = [0.025, -0.03, 0.02, -0.035, 0.03, -0.02].map(|x| Vector3::new(x, -0.02, -0.06));
    let late: Vec<Measured> = (1..rocking.len())
        .map(|k| {
            let icp = Vector3::new(rocking[k - 1].x, rocking[k].y, rocking[k].z);
            frame(rocking[k] * 57.2958, icp)
        })
        .collect();
    assert_eq!(cause(&late), Cause::Degrees, "{late:?}");
    // A gyroscope in deg/s on a fast turn, beyond full scale on every sample.
    let fast = after(|g| g * 57.2958, r * 10.0, false);
    assert!(fast.iter().all(|m| m.rate.norm() > FULL_SCALE));
    assert_eq!(cause(&fast), Cause::Degrees);
    // Rates in deg/s turn the gyroscope's integrated rotation past half a turn, which wraps:
    // the mean rate still names them.
    let mut wrapped = after(|g| g * 57.2958, r * 5.0, true);
    for m in &mut wrapped {
        m.gyro = UnitQuaternion::from_scaled_axis(m.gyro).scaled_axis();
    }
    assert!(wrapped[2].gyro.norm() < 0.5 * (wrapped[2].rate * 0.1).norm());
    assert_eq!(cause(&wrapped), Cause::Degrees);
    // Rates of 1e30 rad/s (or 1e3 times ICP's): beyond any gyroscope, and not deg/s.
    for read in [|_: Vector3<f64>| Vector3::repeat(1e30), |g| g * 1e3] {
        let huge = after(read, r, true);
        assert_eq!(cause(&huge), Cause::BeyondRange, "{huge:?}");
    }
    // Deg/s on a slow turn stays below full scale: not beyond range.
    assert_ne!(cause(&after(|g| g * 57.2958, r, true)), Cause::BeyondRange);
    // Frames that barely turn tell nothing; no frame neither.
    assert_eq!(
        cause(&after(|g| g * 57.2958, r * 0.1, false)[..2]),
        Cause::Unknown
    );
    assert_eq!(cause(&[]), Cause::Unknown);
    // Every description names something.
    assert!(Cause::Degrees.describe().contains("57.3"));
    assert!(Cause::BeyondRange.describe().contains("beyond 35 rad/s"));
}

#[test]
fn a_disagreement_rejects_warns_once_and_resumes_after_turning_frames_that_agree() {
    let mut check = started();
    let r = turn();
    let (off, ok) = check.judge(&meta(), &frame(Vector3::zeros(), r), false);
    assert!(!ok && off > tolerance(&r, false));
    assert!(check.rejecting());
    // The cause comes from it and the frames after it, registered without the gyroscope.
    for _ in 0..CAUSE_FRAMES {
        assert!(check.warning(false).is_none());
        check.judge(&meta(), &frame(Vector3::zeros(), turn()), false);
    }
    let w = check.warning(false).expect("a warning");
    assert!(w.contains("dead") && w.contains("7.bin"), "{w}");
    let still = Vector3::new(0.0, 0.0, 0.01);
    // Frames that barely turn tell nothing: still rejecting after many.
    for _ in 0..100 {
        check.judge(&meta(), &frame(still, still), false);
    }
    assert!(check.rejecting());
    for k in 1..=RESUME_FRAMES {
        assert!(check.rejecting(), "resumed after {k} frames");
        check.judge(&meta(), &frame(r, r), false);
    }
    assert!(!check.rejecting());
    // A second rejection does not warn again and needs twice the frames.
    check.judge(&meta(), &frame(r * 57.3, r), false);
    assert!(check.rejecting() && check.warning(true).is_none());
    for _ in 0..RESUME_FRAMES {
        check.judge(&meta(), &frame(r, r), false);
    }
    assert!(check.rejecting());
    for _ in 0..RESUME_FRAMES {
        check.judge(&meta(), &frame(r, r), false);
    }
    assert!(!check.rejecting());
}

#[test]
fn a_non_finite_disagreement_is_a_disagreement() {
    let mut check = started();
    let (_, ok) = check.judge(
        &meta(),
        &frame(Vector3::new(f64::NAN, 0.0, 0.0), turn()),
        false,
    );
    assert!(!ok && check.rejecting());
}

#[test]
fn a_frame_the_check_refused_disagrees_whatever_its_redone_registration_reads() {
    let mut check = started();
    let (_, ok) = check.judge(&meta(), &frame(turn(), turn()), true);
    assert!(!ok && check.rejecting());
}

#[test]
fn a_rejection_in_the_last_frames_warns_at_the_end_with_what_they_tell() {
    let mut check = started();
    check.judge(&meta(), &frame(Vector3::zeros(), turn()), false);
    check.judge(&meta(), &frame(Vector3::zeros(), turn()), false);
    assert!(check.warning(false).is_none());
    let w = check.warning(true).expect("a warning at the end");
    assert!(w.contains("dead") && w.contains("7.bin"), "{w}");
    assert!(check.warning(true).is_none());
    // Without any frame after it: named from the rejected frame alone.
    let mut check = started();
    check.judge(&meta(), &frame(Vector3::zeros(), turn()), false);
    let w = check.warning(true).expect("a warning at the end");
    assert!(w.contains("dead"), "{w}");
    // A frame too slight to tell anything: named as unknown, still said.
    let mut check = started();
    let slight = turn() * 0.1;
    check.judge(&meta(), &frame(slight * 3.0, slight), true);
    let w = check.warning(true).expect("a warning at the end");
    assert!(w.contains("otherwise than ICP"), "{w}");
}

#[test]
fn a_corrupt_sample_is_told_from_rates_in_degrees_and_warned_once() {
    let sample = |z: f64| ImuSample {
        time: 0.0,
        gyro: [0.1, 0.0, z],
        accel: [0.0, 0.0, 9.8],
    };
    let mut samples: std::vec::Vec<_> = (0..20).map(|_| sample(0.8)).collect();
    assert!(!corrupt_samples(&samples));
    samples[7] = sample(1e6);
    assert!(corrupt_samples(&samples));
    // Rates in deg/s on a fast turn: all beyond full scale, none standing out.
    let degrees: std::vec::Vec<_> = (0..20).map(|k| sample(57.0 + k as f64)).collect();
    assert!(!corrupt_samples(&degrees));
    assert!(!corrupt_samples(&[]));
    let mut check = started();
    check.corrupt_sample(&meta());
    assert!(!check.rejecting());
    let w = check.warning(false).expect("a warning");
    assert!(w.contains("corrupt sample") && w.contains("7.bin"), "{w}");
    check.corrupt_sample(&meta());
    assert!(check.warning(true).is_none(), "warned once");
    // A rejection after it still warns.
    check.judge(&meta(), &frame(Vector3::zeros(), turn()), false);
    assert!(check.warning(true).is_some_and(|w| w.contains("dead")));
}
