use super::*;

/// A frame of 0.1 s turning by `icp`, the gyroscope measuring `gyro` (rad) with samples of
/// that mean rate and `peak` at most.
fn frame(gyro: Vector3<f64>, icp: Vector3<f64>, peak: f64) -> Measured {
    Measured {
        gyro,
        icp,
        dt: 0.1,
        mean_rate: gyro.norm() / 0.1,
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
    check.judge(&meta(), &frame(turn(), turn(), 0.0));
    check
}

#[test]
fn the_first_measured_frame_is_not_judged_the_second_is() {
    let mut check = ImuCheck::default();
    let dead = frame(Vector3::zeros(), turn(), 0.0);
    assert!(check.judge(&meta(), &dead).1 && !check.rejecting());
    assert!(!check.judge(&meta(), &dead).1 && check.rejecting());
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
        worst = worst.max(off / tolerance(&icp));
        assert!(
            agrees(&gyro, &icp),
            "{off} rad off on a turn of {}",
            icp.norm()
        );
    }
    println!("worst disagreement of a correct gyroscope: {worst:.3} of the tolerance");
}

#[test]
fn each_wrong_gyroscope_disagrees_and_is_named() {
    let r = turn();
    let cases = [
        (frame(r * 57.2958, r, 0.0), Cause::Degrees),
        (frame(r, r, 1e6), Cause::Spike),
        (frame(Vector3::zeros(), r, 0.0), Cause::Dead),
        (
            frame(Vector3::new(r.x, r.y, -r.z), r, 0.0),
            Cause::FlippedAxis(2),
        ),
        (
            frame(Vector3::new(-r.x, -r.y, r.z), r * 3.0, 0.0),
            Cause::Unknown,
        ),
    ];
    for (m, want) in cases {
        assert_eq!(cause(&m), want, "{m:?}");
    }
    // 180 degrees about z flips x and y: seen on a frame that turns about x and y.
    let r = Vector3::new(0.06, -0.05, 0.01);
    let m = frame(Vector3::new(-r.x, -r.y, r.z), r, 0.0);
    assert!(!agrees(&m.gyro, &m.icp));
    assert_eq!(cause(&m), Cause::Rotated180(2));
    // A spike at the frame's end: agreeing rotation is not what is judged, the rates are.
    let m = frame(Vector3::new(2.0, 0.0, 0.0), r, 1e6);
    assert!(!agrees(&m.gyro, &m.icp));
    assert_eq!(cause(&m), Cause::Spike);
    // Every description names something.
    assert!(Cause::Degrees.describe().contains("57.3"));
}

#[test]
fn a_disagreement_rejects_warns_once_and_resumes_after_turning_frames_that_agree() {
    let mut check = started();
    let r = turn();
    let (off, ok) = check.judge(&meta(), &frame(Vector3::zeros(), r, 0.0));
    assert!(!ok && off > tolerance(&r));
    assert!(check.rejecting());
    // The cause comes from the next frame, registered without the gyroscope.
    assert!(check.warning().is_none());
    let still = Vector3::new(0.0, 0.0, 0.01);
    check.judge(&meta(), &frame(Vector3::zeros(), turn(), 0.0));
    let w = check.warning().expect("a warning");
    assert!(w.contains("dead") && w.contains("7.bin"), "{w}");
    // Frames that barely turn tell nothing: still rejecting after many.
    for _ in 0..100 {
        check.judge(&meta(), &frame(still, still, 0.0));
    }
    assert!(check.rejecting());
    for k in 1..=RESUME_FRAMES {
        assert!(check.rejecting(), "resumed after {k} frames");
        check.judge(&meta(), &frame(r, r, 0.0));
    }
    assert!(!check.rejecting());
    // A second rejection does not warn again and needs twice the frames.
    check.judge(&meta(), &frame(r * 57.3, r, 0.0));
    assert!(check.rejecting() && check.warning().is_none());
    for _ in 0..RESUME_FRAMES {
        check.judge(&meta(), &frame(r, r, 0.0));
    }
    assert!(check.rejecting());
    for _ in 0..RESUME_FRAMES {
        check.judge(&meta(), &frame(r, r, 0.0));
    }
    assert!(!check.rejecting());
}

#[test]
fn a_non_finite_disagreement_is_a_disagreement() {
    let mut check = started();
    let (_, ok) = check.judge(
        &meta(),
        &frame(Vector3::new(f64::NAN, 0.0, 0.0), turn(), 0.0),
    );
    assert!(!ok && check.rejecting());
}
