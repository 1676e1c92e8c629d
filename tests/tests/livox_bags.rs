//! Livox `CustomMsg` recordings with the IMU beside them (`simulate --messages livox
//! --imu-rate`, from a Mid-360 and an Avia drive): each point's time (`timebase +
//! offset_time`) and each IMU sample are the simulator's, and `run` with the gyroscope prior
//! gives the same poses as on the same drive in the generic layout with its `imu.csv`. A driver
//! publishing several messages a frame is read back frame for frame with `--frame-period`.

use kiss_odom_io::{Format, Frame, ImuInput, Item, OpenOptions, SensorOptions};
use kiss_odom_sim::{Lidar, Messages, PacketSensor, Profile, Request, SimParams};
use kiss_odom_tests::run;
use std::path::Path;

/// Every frame of `path`; a skipped frame or an error fails the test.
fn frames(path: &Path, imu: ImuInput, frame_period_s: Option<f64>) -> Vec<Frame> {
    let opts = OpenOptions {
        imu,
        sensor: SensorOptions {
            frame_period_s,
            ..SensorOptions::default()
        },
        ..OpenOptions::default()
    };
    let mut ds = kiss_odom_io::open(path, Format::Auto, &opts).unwrap();
    assert!(ds.info.warnings.is_empty(), "{:?}", ds.info.warnings);
    std::iter::from_fn(|| ds.frames.next_item().unwrap())
        .map(|item| match item {
            Item::Frame(f) => f,
            Item::Skipped { reason, .. } => panic!("{reason}"),
        })
        .collect()
}

/// The worst disagreement of `bag`'s frames with the simulator's own (`folder`): per-point
/// times (the bag's seconds after its first point against the folder's sequence times, which
/// the recording keeps to the nanosecond) and the sweeps' ends; points and IMU samples must be
/// equal.
fn worst_time(folder: &[Frame], bag: &[Frame]) -> f64 {
    assert_eq!(folder.len(), bag.len());
    let mut worst = 0f64;
    for (f, b) in folder.iter().zip(bag) {
        assert_eq!(f.points, b.points, "frame {}", f.index);
        assert_eq!(f.imu, b.imu, "frame {}: IMU samples", f.index);
        let (fs, bs) = (f.stamps.as_ref().unwrap(), b.stamps.as_ref().unwrap());
        for (t, s) in fs.iter().zip(bs) {
            worst = worst.max(((t - fs[0]) - s).abs());
        }
        worst = worst.max((f.sweep_end().unwrap() - b.sweep_end().unwrap()).abs());
    }
    worst
}

#[test]
fn a_custom_msg_recording_gives_the_simulators_times_imu_samples_and_poses() {
    let tmp = tempfile::tempdir().unwrap();
    for (sensor, format, bag) in [("mid360", "db3", "points"), ("avia", "bag", "points.bag")] {
        let dir = tmp.path().join(sensor);
        kiss_odom_tests::simulate(
            &dir,
            &[
                "--sensor",
                sensor,
                "--format",
                format,
                "--messages",
                "livox",
                "--imu-rate",
                "200",
                "--rate-hz",
                "20",
                "--frames",
                "6",
                "--profile",
                "handheld",
                "--seed",
                "8",
            ],
        );
        // The folder's imu.csv, and the recording's sensor_msgs/Imu topic.
        let folder = frames(&dir, ImuInput::Builtin, None);
        let recorded = frames(&dir.join(bag), ImuInput::Auto, None);
        let worst = worst_time(&folder, &recorded);
        let samples: usize = recorded.iter().map(|f| f.imu.len()).sum();
        println!(
            "{sensor} {format}: {} frames, {samples} IMU samples equal; point times and sweep \
             ends within {worst:.1e} s of the simulator's, tolerance 1e-9 s (nanoseconds)",
            recorded.len()
        );
        assert!(worst <= 1e-9 && samples >= 6 * 10);
        // The gyroscope prior on either gives the same poses.
        let a = run(
            &dir,
            &tmp.path().join(format!("{sensor}-folder")),
            &["--imu", "auto"],
        );
        let b = run(
            &dir.join(bag),
            &tmp.path().join(format!("{sensor}-bag")),
            &["--imu", "auto"],
        );
        let (a, b) = (
            a.ok().lines("poses_kitti.txt"),
            b.ok().lines("poses_kitti.txt"),
        );
        assert_eq!(a.len(), 6);
        let values =
            |l: &String| -> Vec<f64> { l.split_whitespace().map(|v| v.parse().unwrap()).collect() };
        let worst_pose = a
            .iter()
            .zip(&b)
            .flat_map(|(x, y)| values(x).into_iter().zip(values(y)))
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        // Times kept to the nanosecond move a deskewed point by nanometres.
        println!(
            "{sensor}: poses with the IMU prior within {worst_pose:.1e} of the folder's, \
             tolerance 1e-6"
        );
        assert!(worst_pose <= 1e-6);
    }
}

#[test]
fn messages_published_faster_than_the_frames_merge_back_with_a_frame_period() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("sim");
    let request = Request {
        params: SimParams {
            sensor: Lidar {
                rate_hz: 20.0,
                ..Lidar::DEFAULT
            },
            ..SimParams::new(Profile::Handheld, 9, 4)
        },
        sensor: Some(PacketSensor::Mid360),
        format: kiss_odom_sim::Format::Db3,
        messages: Messages::Livox,
        messages_per_frame: 5,
        imu: None,
        layout: kiss_odom_sim::Layout::Generic,
        overwrite: false,
    };
    kiss_odom_sim::write(&request, &dir, &|| false, &mut |_| {}).unwrap();
    let folder = frames(&dir, ImuInput::Builtin, None);
    let each = frames(&dir.join("points"), ImuInput::Builtin, None);
    let merged = frames(&dir.join("points"), ImuInput::Builtin, Some(0.05));
    println!(
        "{} frames of 5 messages each: {} messages read alone, {} frames merged",
        folder.len(),
        each.len(),
        merged.len()
    );
    assert_eq!(each.len(), 5 * folder.len());
    let worst = worst_time(&folder, &merged);
    println!(
        "merged frames' point times within {worst:.1e} s of the simulator's, tolerance 1e-9 s"
    );
    assert!(worst <= 1e-9);
}

#[test]
fn several_messages_a_frame_are_refused_for_anything_but_livox_messages() {
    let tmp = tempfile::tempdir().unwrap();
    for (messages, per_frame, refused) in [
        (Messages::Points, 3, true),
        (Messages::Packets, 3, true),
        (Messages::Livox, 0, true),
        (Messages::Livox, 3, false),
    ] {
        let request = Request {
            params: SimParams::new(Profile::Handheld, 9, 1),
            sensor: Some(PacketSensor::Mid360),
            format: kiss_odom_sim::Format::Mcap,
            messages,
            messages_per_frame: per_frame,
            imu: None,
            layout: kiss_odom_sim::Layout::Generic,
            overwrite: true,
        };
        let out = kiss_odom_sim::write(&request, &tmp.path().join("sim"), &|| false, &mut |_| {});
        let said = out.as_ref().err().map(|e| format!("{e:#}"));
        println!("{messages:?}, {per_frame} a frame: {said:?}");
        assert_eq!(said.is_some(), refused);
        if let Some(e) = said {
            assert!(e.contains("--messages-per-frame"), "{e}");
        }
    }
}
