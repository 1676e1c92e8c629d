//! `kiss-odom ros2` on the wire: against an independent DDS stack (Cyclone DDS from Python),
//! fed by `--play`, paced by the node's odometry and at 10 and 50 Hz.
//!
//! Every pose the node publishes must be, as printed in a KITTI file, the pose `kiss-odom run`
//! writes for the same cloud when run on the sequence of clouds the node registered (a cloud
//! the node dropped under the latest-only rule is never registered, so `run` gets the
//! registered ones only). Nothing here depends on how fast the machine is: every publisher
//! starts once the node has matched it (a reader drops what an unmatched writer sends); a
//! publisher that must lose nothing waits for each cloud's odometry (`interop.py --ack`,
//! `--play --lockstep`), so one cloud at most is in flight; at a fixed rate the tests check the
//! latest-only rule and the poses of what was registered, never how many were, and count the
//! clouds lost on the way: sensor data is best effort with a history of 5, so a loaded machine
//! may lose some. The Cyclone test needs `KISS_ODOM_ROS2_PYTHON` (a Python with
//! `tests/ros2/requirements.txt`, which `.ci/run` makes) and prints SKIP without it.

use crate::ros2_common;

use kiss_odom::ros2::dds;
use kiss_odom::ros2::node::twist_of;
use kiss_odom::ros2::params::NodeParams;
use kiss_odom_drive::settings::Settings;
use kiss_odom_drive::Driver;
use kiss_odom_io::poses::{format_kitti, read_kitti};
use kiss_odom_io::ros::message::parse_cdr;
use kiss_odom_io::ros::pointcloud2::decode;
use kiss_odom_io::{open, Format, Item, OpenOptions};
use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion};
use ros2_common::*;
use serde_json::Value;
use std::io::Write;
use std::path::Path;
use std::process::Stdio;
use std::time::Duration;

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

/// The pose a message carries, every value as sent.
fn pose_of(position: &Value, orientation: &Value) -> Isometry3<f64> {
    let (p, q) = (floats(position), floats(orientation));
    Isometry3::from_parts(
        Translation3::new(p[0], p[1], p[2]),
        UnitQuaternion::new_unchecked(Quaternion::new(q[3], q[0], q[1], q[2])),
    )
}

fn stamp_of(v: &Value) -> f64 {
    let s = floats(v);
    s[0] + s[1] / 1e9
}

#[test]
fn cyclonedds_publisher_and_subscriber_get_runs_poses_bit_for_bit_with_twist_and_covariance() {
    let Some(py) = std::env::var_os("KISS_ODOM_ROS2_PYTHON") else {
        println!(
            "SKIP: KISS_ODOM_ROS2_PYTHON is not set (a Python with tests/ros2/requirements.txt)"
        );
        return;
    };
    let _lock = serial();
    let dir = tempfile::tempdir().unwrap();
    let d = domain(0);
    let node = start_node(d, dir.path(), Duration::ZERO);
    let json = dir.path().join("received.json");
    let mut cyclone = std::process::Command::new(&py)
        .arg(root().join("tests/ros2/interop.py"))
        .args(["--folder", &kitti()])
        .args(["--domain", &d.to_string(), "--ack", "--go-on-stdin"])
        .args(["--timeout", &HANG.as_secs().to_string()])
        .arg("--out")
        .arg(&json)
        .stdin(Stdio::piped())
        .spawn()
        .expect("start the Cyclone DDS side");
    // Its first cloud goes once the node has matched its cloud writer and its two readers.
    for topic in ["/points", "/kiss/odometry", "/tf"] {
        node.wait_matched(topic, 1);
    }
    let mut go = cyclone.stdin.take().unwrap();
    go.write_all(b"go\n").unwrap();
    drop(go);
    let status = kiss_odom_tests::wait_exit(&mut cyclone, "interop.py", 2 * HANG);
    let stopped = node.stop();
    println!("{}{}", stopped.out, stopped.err);
    assert!(status.success(), "interop.py failed");

    // The clouds went out as raw .bin scans: `run` reads the same floats as a generic folder.
    let expected = run_poses(&[&kitti(), "--format", "bin"], &dir.path().join("run"));
    let expected: Vec<&str> = expected.lines().collect();
    let got: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let odom = got["odometry"].as_array().unwrap();
    let tf = got["tf"].as_array().unwrap();
    assert_eq!(odom.len(), 10, "one odometry message per cloud");
    assert_eq!(tf.len(), 10, "one transform per cloud");
    assert_eq!(stopped.summary.registered, 10);
    assert_eq!(
        stopped.summary.dropped, 0,
        "paced by the odometry: no cloud dropped"
    );

    let mut worst_twist = 0.0f64;
    let mut previous: Option<(Isometry3<f64>, f64)> = None;
    for (k, m) in odom.iter().enumerate() {
        let pose = pose_of(&m["position"], &m["orientation"]);
        assert_eq!(
            format_kitti(&[pose]).trim_end(),
            expected[k],
            "frame {k}: published pose differs from run's"
        );
        assert_eq!(m["frame_id"], "odom_lidar");
        assert_eq!(m["child_frame_id"], "velodyne", "base = the cloud's frame");
        let t = &tf[k];
        assert_eq!(t["stamp"], m["stamp"]);
        assert_eq!(
            (&t["frame_id"], &t["child_frame_id"]),
            (&m["frame_id"], &m["child_frame_id"])
        );
        assert_eq!(
            pose_of(&t["translation"], &t["rotation"]),
            pose,
            "frame {k}: /tf"
        );

        // Documented: twist = last motion / time between stamps (0.1 s for the first cloud);
        // pose covariance diag(0.1 x 6); twist covariance the same over dt^2.
        let stamp = stamp_of(&m["stamp"]);
        let (delta, dt) = match previous {
            None => (Isometry3::identity(), 0.1),
            Some((p, s)) => (p.inverse() * pose, stamp - s),
        };
        previous = Some((pose, stamp));
        let want = twist_of(&delta, dt);
        let want = [
            want.linear.x,
            want.linear.y,
            want.linear.z,
            want.angular.x,
            want.angular.y,
            want.angular.z,
        ];
        let have: Vec<f64> = floats(&m["linear"])
            .into_iter()
            .chain(floats(&m["angular"]))
            .collect();
        for (a, b) in want.iter().zip(&have) {
            worst_twist = worst_twist.max((a - b).abs());
        }
        let (pc, tc) = (
            floats(&m["pose_covariance"]),
            floats(&m["twist_covariance"]),
        );
        for i in 0..36 {
            let diag = i % 7 == 0;
            assert_eq!(pc[i], if diag { 0.1 } else { 0.0 }, "pose covariance [{i}]");
            let tw = if diag { 0.1 / (dt * dt) } else { 0.0 };
            assert!(
                (tc[i] - tw).abs() <= 1e-9 * tw.max(1.0),
                "frame {k} twist covariance [{i}]: {} vs {tw}",
                tc[i]
            );
        }
    }
    println!("twist against the published poses: worst {worst_twist:.3e} (tolerance 1e-9)");
    assert!(worst_twist <= 1e-9);
}

/// Plays `file` into a node in this process with `--play` flags `args`; returns what the
/// node printed and what the player printed.
///
/// With `--lockstep` one cloud at most is in flight and every cloud published must be
/// received. At a fixed rate a cloud can be lost on the way, as sensor data may be (best
/// effort, a reader history of 5): the losses are counted and printed.
fn play_into_node(k: u16, file: &Path, args: &[&str], min_period: Duration) -> (Stopped, String) {
    let dir = tempfile::tempdir().unwrap();
    let d = domain(k);
    let node = start_node(d, dir.path(), min_period);
    let played = play(&node, file, d, args);
    let stamps = published_stamps(&played);
    let sent = stamps.len();
    let lockstep = args.contains(&"--lockstep");
    // Latest-only: the last cloud published is never replaced (nor pushed out of the reader's
    // history), so the node registers it unless it is lost on the wire; its frame line says
    // every cloud before has been taken or dropped. Only waiting tells a lost cloud: at a
    // fixed rate, one not registered by the deadline is counted with the other losses.
    let last = *stamps.last().expect("no cloud published");
    let done = wait_until(HANG, || node.has_registered(last));
    let stopped = node.stop();
    let s = &stopped.summary;
    println!("{}: {}", file.display(), s.line());
    assert!(
        s.received as usize <= sent,
        "received more than was published"
    );
    let lost = sent - s.received as usize;
    println!(
        "{}: {sent} clouds published, {} received, {lost} lost on the way",
        file.display(),
        s.received
    );
    if lockstep {
        assert!(done, "the last cloud (stamp {last}) was never registered");
        assert_eq!(lost, 0, "--lockstep: every cloud published was received");
    }
    assert_eq!(
        s.received,
        s.registered + s.dropped + s.malformed + s.empty,
        "every received cloud is registered, dropped or skipped"
    );
    (stopped, played)
}

/// The node's poses are `run`'s on exactly the clouds it registered: a folder of `data`'s
/// frames holding only those, renumbered in order (a gap in the numbers would be a lost frame
/// to `run`), with `data`'s `calib.txt` (the KITTI correction `--play` applied).
fn assert_runs_poses_on_what_was_registered(data: &Path, stopped: &Stopped) {
    let times: Vec<f64> = std::fs::read_to_string(data.join("times.txt"))
        .unwrap()
        .lines()
        .map(|l| l.trim().parse().unwrap())
        .collect();
    let root = tempfile::tempdir().unwrap();
    let subset = root.path().join("registered");
    let subs: Vec<&str> = ["velodyne", "timestamps"]
        .into_iter()
        .filter(|sub| data.join(sub).is_dir())
        .collect();
    for sub in &subs {
        std::fs::create_dir_all(subset.join(sub)).unwrap();
    }
    if data.join("calib.txt").is_file() {
        std::fs::copy(data.join("calib.txt"), subset.join("calib.txt")).unwrap();
    }
    let stamps = registered_stamps(&stopped.out);
    assert_eq!(stamps.len() as u64, stopped.summary.registered);
    for (j, st) in stamps.iter().enumerate() {
        let t: f64 = st.parse().unwrap();
        let i = times
            .iter()
            .position(|x| (x - t).abs() < 1e-6)
            .expect("stamp of a frame");
        for sub in &subs {
            let (from, to) = (format!("{sub}/{i:06}.bin"), format!("{sub}/{j:06}.bin"));
            std::fs::copy(data.join(from), subset.join(to)).unwrap();
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let expected = run_poses(&[&subset.to_string_lossy()], dir.path());
    assert_eq!(
        stopped.poses, expected,
        "poses differ from run on the registered clouds"
    );
}

#[test]
fn play_of_a_bag_and_an_mcap_feeds_a_node_that_publishes_runs_poses() {
    let _lock = serial();
    for (k, name) in [(1, "ouster.bag"), (2, "ouster.mcap")] {
        let file = root().join("fixtures/bags").join(name);
        let (stopped, _) = play_into_node(k, &file, &["--lockstep"], Duration::ZERO);
        let dir = tempfile::tempdir().unwrap();
        let expected = run_poses(&[&file.to_string_lossy()], dir.path());
        assert_eq!(stopped.summary.dropped, 0, "--lockstep: none dropped");
        assert_eq!(
            stopped.poses, expected,
            "{name}: node poses differ from run's"
        );
        assert!(
            stopped.out.contains("deskewed"),
            "{name}: per-point times reach the core"
        );
    }
}

/// A simulated drone run recorded as a bag with its IMU, played with `--lockstep` into a node
/// with the gyroscope prior on: every cloud is registered with the samples up to its sweep's
/// end, as `run --imu auto` hands them on, so the poses are run's bit for bit.
#[test]
fn a_bag_with_an_imu_feeds_the_gyroscope_prior_and_the_poses_are_runs_with_imu_auto() {
    let _lock = serial();
    let data = tempfile::tempdir().unwrap();
    let sim = data.path().join("drone");
    let argv = [
        "kiss-odom",
        "simulate",
        "--out",
        &sim.to_string_lossy(),
        "--profile",
        "drone",
        "--frames",
        "30",
        "--imu-rate",
        "200",
        "--format",
        "bag",
    ];
    let mut err = Vec::new();
    let code = kiss_odom::cli::main_with(argv.iter().map(Into::into).collect(), &mut err);
    assert_eq!(code, 0, "{}", String::from_utf8_lossy(&err));
    let bag = sim.join("points.bag");

    let dir = tempfile::tempdir().unwrap();
    let d = domain(7);
    let node = start_node_imu(d, dir.path(), "/imu");
    let played = play(&node, &bag, d, &["--lockstep", "--imu", "auto"]);
    let stamps = published_stamps(&played);
    assert_eq!(stamps.len(), 30, "{played}");
    assert!(played.contains("IMU samples on /imu"), "{played}");
    let last = *stamps.last().unwrap();
    let done = wait_until(HANG, || node.has_registered(last));
    let stopped = node.stop();
    let s = &stopped.summary;
    println!("{}", s.line());
    assert!(done, "the last cloud was never registered");
    assert_eq!((s.received, s.registered, s.dropped), (30, 30, 0));
    let imu = s.imu.expect("IMU counters with the prior on");
    assert_eq!((imu.malformed, imu.dropped), (0, 0), "{}", s.line());
    assert!(imu.received > 30 * 15, "{}", s.line());
    assert!(
        s.line().contains("imu received"),
        "the summary prints the IMU counts"
    );
    let run_dir = tempfile::tempdir().unwrap();
    let expected = run_poses(&[&bag.to_string_lossy(), "--imu", "auto"], run_dir.path());
    let without = run_poses(&[&bag.to_string_lossy()], &run_dir.path().join("off"));
    assert_ne!(expected, without, "the prior changes the poses");
    // Every pose but the last is run's bit for bit. `run` hands the last frame every sample
    // left, those after its sweep's end too (a recording's last frame takes the rest), and
    // the prior uses them; a live node cannot know a cloud is the last, so it takes those up
    // to the end only, as for every other cloud.
    let node: Vec<&str> = stopped.poses.lines().collect();
    let run: Vec<&str> = expected.lines().collect();
    assert_eq!(node.len(), run.len());
    assert_eq!(
        node[..node.len() - 1],
        run[..run.len() - 1],
        "node poses differ from run --imu auto's\n{}",
        stopped.err
    );
    let last = |p: &str| read_kitti_str(p).translation.vector;
    let gap = (last(node[node.len() - 1]) - last(run[run.len() - 1])).norm();
    println!("last pose against run's: {gap:.3e} m (tolerance 1e-2)");
    assert!(gap < 1e-2, "last pose {gap} m from run's");
}

/// The pose of one KITTI line.
fn read_kitti_str(line: &str) -> Isometry3<f64> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("pose.txt");
    std::fs::write(&path, format!("{line}\n")).unwrap();
    read_kitti(&path).unwrap()[0]
}

#[test]
fn paced_by_the_odometry_none_is_dropped_and_faster_the_older_clouds_are_dropped_and_counted() {
    let _lock = serial();
    let data = tempfile::tempdir().unwrap();
    let urban = data.path().join("urban");
    let mut err = Vec::new();
    let argv = [
        "kiss-odom",
        "simulate",
        "--out",
        &urban.to_string_lossy(),
        "--frames",
        "100",
    ];
    let code = kiss_odom::cli::main_with(argv.iter().map(Into::into).collect(), &mut err);
    assert_eq!(code, 0, "{}", String::from_utf8_lossy(&err));
    let kitti = root().join(KITTI_DIR);

    // Each cloud once the odometry of the one before came, as fast as the node goes: nothing
    // dropped, every pose is run's.
    for (k, path) in [(3, &kitti), (4, &urban)] {
        let paced = ["--lockstep", "--rate", "1000"];
        let (stopped, _) = play_into_node(k, path, &paced, Duration::ZERO);
        let s = &stopped.summary;
        assert_eq!(s.dropped, 0, "{}: dropped under --lockstep", path.display());
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(
            stopped.poses,
            run_poses(&[&path.to_string_lossy()], dir.path())
        );
    }

    // At the recorded 10 Hz, whatever the machine: the node takes what it can, latest only.
    let (stopped, _) = play_into_node(5, &kitti, &["--rate", "1"], Duration::ZERO);
    assert_runs_poses_on_what_was_registered(&kitti, &stopped);
    println!(
        "10 Hz: {} of {} clouds registered, {} dropped",
        stopped.summary.registered, stopped.summary.received, stopped.summary.dropped
    );

    // 50 Hz into a node that takes a cloud at most every 500 ms (`--min-period 0.5`, a slow
    // computer on any machine): clouds arrive while one waits (any player faster than 2 Hz)
    // and the older ones are replaced.
    let (stopped, _) = play_into_node(6, &urban, &["--rate", "5"], Duration::from_millis(500));
    let s = &stopped.summary;
    assert!(
        s.dropped > 0,
        "50 Hz into a node taking 2 a second should drop: {}",
        s.line()
    );
    assert_runs_poses_on_what_was_registered(&urban, &stopped);
    println!(
        "50 Hz: {} of {} clouds registered, {} dropped",
        s.registered, s.received, s.dropped
    );
}

#[test]
fn base_to_lidar_extrinsic_moves_the_poses_and_the_local_map_is_published_in_the_odom_frame() {
    let _lock = serial();
    let dir = tempfile::tempdir().unwrap();
    let d = domain(7);
    // LiDAR 1.5 m above the base and turned 90 degrees about z.
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let params = NodeParams {
        base_frame: "base_link".into(),
        base_to_lidar: Some([0.0, 0.0, 1.5, 0.0, 0.0, h, h]),
        publish_local_map: true,
        local_map_period: 0.0,
        ..NodeParams::default()
    };
    let e = params.extrinsic().unwrap();
    let node = start_node_with(d, dir.path(), Duration::ZERO, params);
    let dp = dds::participant(d).unwrap();
    let mut maps = dds::cloud_reader(&dp, "/kiss/local_map").unwrap();
    play(&node, &root().join(KITTI_DIR), d, &["--lockstep"]);
    let stopped = node.stop_after(10);
    assert_eq!(stopped.summary.registered, 10);

    // Base poses are E L E^-1 of run's LiDAR poses.
    let run_dir = dir.path().join("run");
    run_poses(&[&kitti()], &run_dir);
    let lidar = read_kitti(&run_dir.join("poses_kitti.txt")).unwrap();
    let node_file = dir.path().join("node_poses.txt");
    let base = read_kitti(&node_file).unwrap();
    let mut worst = 0.0f64;
    for (l, b) in lidar.iter().zip(&base) {
        let want = e * l * e.inverse();
        worst = worst.max((want.translation.vector - b.translation.vector).norm());
        worst = worst.max(want.rotation.angle_to(&b.rotation));
    }
    println!("base poses against E L E^-1: worst {worst:.3e} (tolerance 1e-9)");
    assert!(worst <= 1e-9);
    // The first base pose is the identity, and the base moves forward along the LiDAR's
    // driving direction turned by the mount: KITTI drives along the LiDAR's x.
    let last = base.last().unwrap().translation.vector;
    assert!(last.y > 4.0 && last.x.abs() < 0.5, "{last:?}");

    // The last map is the odometry's map after the last cloud, moved into the base's
    // odometry frame: the same points, in the same order, as an odometry built here holds.
    let mut last = None;
    while let Ok(Some(sample)) = maps.take_next_sample() {
        last = Some(sample.into_value());
    }
    let raw = last.expect("no local map received");
    let cloud = parse_cdr(&raw.0).unwrap();
    assert_eq!(cloud.frame_id, "odom_lidar");
    assert_eq!(
        cloud.stamp.to_string(),
        *registered_stamps(&stopped.out).last().unwrap()
    );
    let published = decode(&cloud).unwrap().points;
    let mut dataset = open(Path::new(&kitti()), Format::Auto, &OpenOptions::default()).unwrap();
    let mut driver = Driver::new(&Settings::default()).unwrap();
    while let Some(Item::Frame(f)) = dataset.frames.next_item().unwrap() {
        driver.register(&f).unwrap();
    }
    let expected = driver.map_points();
    let expected: Vec<[f64; 3]> = expected
        .iter()
        .map(|p| {
            let v = e * Point3::from(*p);
            [v.x, v.y, v.z]
        })
        .collect();
    assert_eq!(published.len(), expected.len());
    assert!(published == expected, "local map points differ");
}

/// A generated revisit recorded as a bag, played with `--lockstep` into a node localizing in a
/// map of the first drive (`map_file`, `initial_pose`): its poses, in the map frame, are `run
/// --map`'s bit for bit on the same bag, each cloud's line says its state, and the base's pose
/// in the map frame goes out on `map_pose_topic`.
#[test]
fn a_node_with_a_prior_map_publishes_runs_map_frame_poses() {
    let _lock = serial();
    let data = tempfile::tempdir().unwrap();
    let (a, b) = (data.path().join("a"), data.path().join("b"));
    let map = data.path().join("site.komap");
    let cli = |args: &[&str]| {
        let argv = ["kiss-odom"].iter().chain(args).map(Into::into).collect();
        let mut err = Vec::new();
        let code = kiss_odom::cli::main_with(argv, &mut err);
        assert_eq!(code, 0, "{args:?}: {}", String::from_utf8_lossy(&err));
    };
    let (a_s, b_s, map_s) = (
        a.to_string_lossy(),
        b.to_string_lossy(),
        map.to_string_lossy(),
    );
    cli(&["simulate", "--out", &a_s, "--frames", "30", "--seed", "5"]);
    let revisit = [
        "--frames",
        "30",
        "--seed",
        "5",
        "--revisit",
        "--format",
        "bag",
    ];
    cli(&[&["simulate", "--out", &b_s][..], &revisit].concat());
    let poses = a.join("poses.txt");
    cli(&[
        "map",
        "build",
        &a_s,
        "--poses",
        &poses.to_string_lossy(),
        "--out",
        &map_s,
    ]);
    let start = std::fs::read_to_string(b.join("initial_pose.txt")).unwrap();
    let start = start.trim();
    let bag = b.join("points.bag");

    let dir = tempfile::tempdir().unwrap();
    let d = domain(8);
    let params = NodeParams {
        map_file: map_s.to_string(),
        initial_pose: start.to_string(),
        ..NodeParams::default()
    };
    let node = start_node_with(d, dir.path(), Duration::ZERO, params);
    let dp = dds::participant(d).unwrap();
    let mut map_poses = dds::cloud_reader(&dp, "/kiss/map_pose").unwrap();
    play(&node, &bag, d, &["--lockstep"]);
    let stopped = node.stop_after(30);
    assert_eq!(stopped.summary.registered, 30, "{}", stopped.err);
    let run_dir = tempfile::tempdir().unwrap();
    let bag_s = bag.to_string_lossy();
    let expected = run_poses(
        &[&bag_s, "--map", &map_s, "--initial-pose", start],
        run_dir.path(),
    );
    assert_eq!(
        stopped.poses, expected,
        "node poses differ from run --map's"
    );
    let localized = stopped.out.matches(" map localized").count();
    println!("{localized} of 30 clouds localized");
    assert!(localized >= 25, "{}", stopped.out);
    let mut received = 0;
    while let Ok(Some(sample)) = map_poses.take_next_sample() {
        let bytes = sample.into_value().0;
        // The header's frame_id, a CDR string: its length with the zero, then "map\0".
        assert!(
            bytes.windows(8).any(|w| w == b"\x04\0\0\0map\0"),
            "frame_id map"
        );
        received += 1;
    }
    println!("{received} map poses received");
    assert!(received > 0, "no pose in the map frame published");
}
