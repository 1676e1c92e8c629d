use super::*;

/// A frame of 0.1 s turning by `icp`, the gyroscope measuring `gyro` (rad) with samples of
/// that mean rate and `peak` at most.
fn frame(gyro: Vector3<f64>, icp: Vector3<f64>, peak: f64) -> Measured {
    Measured {
        gyro,
        icp,
        dt: 0.1,
        rate: gyro / 0.1,
        peak_rate: peak.max(gyro.norm() / 0.1),
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
    check.judge(&meta(), &frame(turn(), turn(), 0.0), false);
    check
}

#[test]
fn the_first_measured_frame_is_judged_with_room_for_its_undeskewed_map() {
    // A dead gyroscope is within the first frame's room (ICP's whole rotation), not the next's.
    let mut check = ImuCheck::default();
    let dead = frame(Vector3::zeros(), turn(), 0.0);
    assert!(check.judge(&meta(), &dead, false).1 && !check.rejecting());
    assert!(!check.judge(&meta(), &dead, false).1 && check.rejecting());
    // Four times ICP's rotation is beyond it, and so is a frame the check refused.
    let mut check = ImuCheck::default();
    let twice = frame(turn() * 4.0, turn(), 0.0);
    assert!(!check.judge(&meta(), &twice, false).1 && check.rejecting());
    let mut check = ImuCheck::default();
    assert!(!check.judge(&meta(), &frame(turn(), turn(), 0.0), true).1);
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
    let mut frames: Vec<Measured> = turns.iter().map(|&t| frame(read(t), t, 0.0)).collect();
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
            frame(rocking[k] * 57.2958, icp, 0.0)
        })
        .collect();
    assert_eq!(cause(&late), Cause::Degrees, "{late:?}");
    // A spike: the rates are judged, not the rotation (which may agree).
    let mut frames = after(|g| g, r, false);
    frames[1].peak_rate = 1e6;
    assert_eq!(cause(&frames), Cause::Spike);
    // A gyroscope in deg/s on a fast turn is beyond full scale on every sample: not a spike.
    let fast = after(|g| g * 57.2958, r * 10.0, false);
    assert!(fast.iter().all(|m| m.peak_rate > FULL_SCALE));
    assert_eq!(cause(&fast), Cause::Degrees);
    // Rates in deg/s turn the gyroscope's integrated rotation past half a turn, which wraps:
    // the mean rate still names them.
    let mut wrapped = after(|g| g * 57.2958, r * 5.0, true);
    for m in &mut wrapped {
        m.gyro = UnitQuaternion::from_scaled_axis(m.gyro).scaled_axis();
    }
    assert!(wrapped[2].gyro.norm() < 0.5 * (wrapped[2].rate * 0.1).norm());
    assert_eq!(cause(&wrapped), Cause::Degrees);
    // Frames that barely turn tell nothing; no frame neither.
    assert_eq!(
        cause(&after(|g| g * 57.2958, r * 0.1, false)[..2]),
        Cause::Unknown
    );
    assert_eq!(cause(&[]), Cause::Unknown);
    // Every description names something.
    assert!(Cause::Degrees.describe().contains("57.3"));
}

#[test]
fn a_disagreement_rejects_warns_once_and_resumes_after_turning_frames_that_agree() {
    let mut check = started();
    let r = turn();
    let (off, ok) = check.judge(&meta(), &frame(Vector3::zeros(), r, 0.0), false);
    assert!(!ok && off > tolerance(&r, false));
    assert!(check.rejecting());
    // The cause comes from it and the frames after it, registered without the gyroscope.
    for _ in 0..CAUSE_FRAMES {
        assert!(check.warning(false).is_none());
        check.judge(&meta(), &frame(Vector3::zeros(), turn(), 0.0), false);
    }
    let w = check.warning(false).expect("a warning");
    assert!(w.contains("dead") && w.contains("7.bin"), "{w}");
    let still = Vector3::new(0.0, 0.0, 0.01);
    // Frames that barely turn tell nothing: still rejecting after many.
    for _ in 0..100 {
        check.judge(&meta(), &frame(still, still, 0.0), false);
    }
    assert!(check.rejecting());
    for k in 1..=RESUME_FRAMES {
        assert!(check.rejecting(), "resumed after {k} frames");
        check.judge(&meta(), &frame(r, r, 0.0), false);
    }
    assert!(!check.rejecting());
    // A second rejection does not warn again and needs twice the frames.
    check.judge(&meta(), &frame(r * 57.3, r, 0.0), false);
    assert!(check.rejecting() && check.warning(true).is_none());
    for _ in 0..RESUME_FRAMES {
        check.judge(&meta(), &frame(r, r, 0.0), false);
    }
    assert!(check.rejecting());
    for _ in 0..RESUME_FRAMES {
        check.judge(&meta(), &frame(r, r, 0.0), false);
    }
    assert!(!check.rejecting());
}

#[test]
fn a_non_finite_disagreement_is_a_disagreement() {
    let mut check = started();
    let (_, ok) = check.judge(
        &meta(),
        &frame(Vector3::new(f64::NAN, 0.0, 0.0), turn(), 0.0),
        false,
    );
    assert!(!ok && check.rejecting());
}

#[test]
fn a_frame_the_check_refused_disagrees_whatever_its_redone_registration_reads() {
    let mut check = started();
    let (_, ok) = check.judge(&meta(), &frame(turn(), turn(), 0.0), true);
    assert!(!ok && check.rejecting());
}

#[test]
fn a_rejection_in_the_last_frames_warns_at_the_end_with_what_they_tell() {
    let mut check = started();
    check.judge(&meta(), &frame(Vector3::zeros(), turn(), 0.0), false);
    check.judge(&meta(), &frame(Vector3::zeros(), turn(), 0.0), false);
    assert!(check.warning(false).is_none());
    let w = check.warning(true).expect("a warning at the end");
    assert!(w.contains("dead") && w.contains("7.bin"), "{w}");
    assert!(check.warning(true).is_none());
    // Without any frame after it: named from the rejected frame alone.
    let mut check = started();
    check.judge(&meta(), &frame(Vector3::zeros(), turn(), 0.0), false);
    let w = check.warning(true).expect("a warning at the end");
    assert!(w.contains("dead"), "{w}");
    // A frame too slight to tell anything: named as unknown, still said.
    let mut check = started();
    let slight = turn() * 0.1;
    check.judge(&meta(), &frame(slight * 3.0, slight, 0.0), true);
    let w = check.warning(true).expect("a warning at the end");
    assert!(w.contains("otherwise than ICP"), "{w}");
}

#[test]
fn a_corrupt_sample_is_named_from_the_frame_it_was_in() {
    let mut check = started();
    let r = turn();
    let mut spiked = frame(r, r, 1e6);
    spiked.rate = r / 0.1 + Vector3::new(1e6, 0.0, 0.0) / 20.0;
    // The check refused the frame (a sample beyond full scale is not handed over).
    let (_, ok) = check.judge(&meta(), &spiked, true);
    assert!(!ok);
    for _ in 0..CAUSE_FRAMES {
        check.judge(&meta(), &frame(r, r, 0.0), false);
    }
    let w = check.warning(false).expect("a warning");
    assert!(w.contains("corrupt sample"), "{w}");
}

#[test]
fn a_frame_with_a_corrupt_sample_warns_once_and_does_not_reject_the_gyroscope() {
    let r = turn();
    assert!(corrupt(1e6, &(r / 0.1 + Vector3::new(5e4, 0.0, 0.0))));
    // Rates in deg/s on a fast turn: all beyond full scale, none standing out.
    assert!(!corrupt(60.0, &Vector3::new(0.0, 0.0, 57.0)));
    assert!(!corrupt(30.0, &Vector3::zeros()));
    let mut check = started();
    check.corrupt_sample(&meta());
    assert!(!check.rejecting());
    let w = check.warning(false).expect("a warning");
    assert!(w.contains("corrupt sample") && w.contains("7.bin"), "{w}");
    check.corrupt_sample(&meta());
    assert!(check.warning(true).is_none(), "warned once");
    // A rejection after it still warns.
    check.judge(&meta(), &frame(Vector3::zeros(), r, 0.0), false);
    assert!(check.warning(true).is_some_and(|w| w.contains("dead")));
}
