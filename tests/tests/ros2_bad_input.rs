//! Bad clouds on the wire: each is skipped with a counted warning, the node goes on, and the
//! odometry is as if the bad cloud had never arrived (the poses after it are `kiss-odom run`'s
//! on the good clouds alone). A malformed IMU message is counted and warned about. And Ctrl-C
//! ends a node process cleanly with its summary.

use crate::ros2_common;

use kiss_odom::ros2::dds::{self, Writer};
use kiss_odom::ros2::imu::ImuCounts;
use kiss_odom::ros2::msg::{Field, Header, Imu, PointCloud2, Time, IMU_TYPE, POINTCLOUD2_TYPE};
use ros2_common::*;
use serde::Serialize;
use std::io::{BufRead, BufReader};
use std::time::Duration;

/// KITTI scan `k` of the shipped sample as a cloud (x, y, z FLOAT64, no time field).
fn good(k: usize) -> PointCloud2 {
    let bytes = std::fs::read(root().join(format!("{KITTI_DIR}/velodyne/{k:06}.bin"))).unwrap();
    let points: Vec<[f64; 3]> = bytes
        .chunks_exact(16)
        .map(|c| {
            let f =
                |i: usize| f64::from(f32::from_le_bytes(c[4 * i..4 * i + 4].try_into().unwrap()));
            [f(0), f(1), f(2)]
        })
        .collect();
    PointCloud2::xyzt(header(k as f64 * 0.1), &points, None)
}

fn header(seconds: f64) -> Header {
    Header {
        stamp: Time::from_seconds(seconds),
        frame_id: "velodyne".into(),
    }
}

/// A node on domain `k` and a cloud writer matched on both sides. Holds the test lock.
struct Rig {
    _lock: std::sync::MutexGuard<'static, ()>,
    dir: tempfile::TempDir,
    node: Node,
    _dp: dds::DomainParticipant,
    w: Writer<PointCloud2>,
}

fn rig(k: u16) -> Rig {
    let lock = serial();
    let dir = tempfile::tempdir().unwrap();
    let node = start_node(domain(k), dir.path(), Duration::ZERO);
    let dp = dds::participant(domain(k)).unwrap();
    let w: Writer<PointCloud2> =
        dds::writer(&dp, "/points", POINTCLOUD2_TYPE, &dds::sensor_qos()).unwrap();
    assert!(dds::wait_for_reader(&w, HANG, &|| false), "no node");
    node.wait_matched("/points", 1);
    Rig {
        _lock: lock,
        dir,
        node,
        _dp: dp,
        w,
    }
}

impl Rig {
    /// Waits until the node has printed `n` warnings: the skipped clouds' acknowledgements.
    fn warned(&self, n: usize) {
        let ok = wait_until(HANG, || self.node.warnings() >= n);
        assert!(
            ok,
            "the node printed {} warnings, not {n}",
            self.node.warnings()
        );
    }
}

/// Sends scan 0, then whatever `bad` sends (each bad cloud once the node warned about the one
/// before), then scan 1, each once the node is done with the one before (so nothing is
/// dropped, on any machine); returns what the node did.
fn around(k: u16, bad: impl FnOnce(&Rig)) -> Stopped {
    let r = rig(k);
    r.w.write(good(0), None).unwrap();
    assert!(wait_until(HANG, || r.node.registered() == 1));
    bad(&r);
    r.w.write(good(1), None).unwrap();
    let stopped = r.node.stop_after(2);
    println!("{}{}", stopped.out, stopped.err);
    let s = &stopped.summary;
    assert_eq!(s.dropped, 0);
    assert_eq!(s.registered, 2, "the node goes on after the bad cloud");
    let run = run_poses(
        &[&kitti(), "--format", "bin", "--frames", "0..2"],
        &r.dir.path().join("run"),
    );
    assert_eq!(
        stopped.poses, run,
        "the bad cloud left a trace in the odometry"
    );
    stopped
}

#[test]
fn cloud_without_xyz_fields_is_skipped_with_a_counted_warning() {
    let s = around(6, |r| {
        let mut c = good(2);
        for (f, name) in c.fields.iter_mut().zip(["a", "b", "c"]) {
            f.name = name.into();
        }
        r.w.write(c, None).unwrap();
        r.warned(1);
    });
    assert_eq!((s.summary.malformed, s.summary.warnings), (1, 1));
    assert!(s.err.contains("no field `x`"), "{}", s.err);
}

#[test]
fn cloud_whose_fields_do_not_fit_its_point_step_is_skipped_with_a_counted_warning() {
    let s = around(7, |r| {
        let mut c = good(2);
        c.point_step = 16; // x, y, z are 8 bytes each: z ends at 24
        c.row_step = 16 * c.width;
        r.w.write(c, None).unwrap();
        r.warned(1);
        let mut c = good(2);
        c.point_step = 48; // fits the fields, but the data holds half the points
        c.row_step = 48 * c.width;
        c.fields.push(Field {
            name: "pad".into(),
            offset: 24,
            datatype: 8,
            count: 1,
        });
        r.w.write(c, None).unwrap();
        r.warned(2);
    });
    assert_eq!((s.summary.malformed, s.summary.warnings), (2, 2));
    assert!(s.err.contains("does not fit in point_step 16"), "{}", s.err);
    assert!(s.err.contains("needs"), "{}", s.err);
}

#[test]
fn empty_cloud_is_skipped_with_a_counted_warning() {
    let s = around(8, |r| {
        r.w.write(PointCloud2::xyzt(header(0.15), &[], None), None)
            .unwrap();
        r.warned(1);
    });
    assert_eq!((s.summary.empty, s.summary.warnings), (1, 1));
    assert!(s.err.contains("empty cloud"), "{}", s.err);
}

#[test]
fn non_finite_points_are_skipped_and_counted_and_an_all_nan_cloud_is_skipped() {
    let s = around(9, |r| {
        let nan = [[f64::NAN, 1.0, 2.0], [3.0, f64::INFINITY, 0.0]];
        r.w.write(PointCloud2::xyzt(header(0.15), &nan, None), None)
            .unwrap();
        r.warned(1);
    });
    assert_eq!((s.summary.empty, s.summary.warnings), (1, 1));
    assert!(s.err.contains("no usable point"), "{}", s.err);

    // NaN points inside a usable cloud: the cloud is registered, the points skipped (the
    // core drops non-finite points before anything else, as `run` shows).
    let r = rig(9);
    let mut c = good(0);
    c.data.0[..8].copy_from_slice(&f64::NAN.to_le_bytes());
    c.data.0[32..40].copy_from_slice(&f64::NEG_INFINITY.to_le_bytes());
    r.w.write(c, None).unwrap();
    let stopped = r.node.stop_after(1);
    assert_eq!(
        (stopped.summary.registered, stopped.summary.warnings),
        (1, 1)
    );
    assert!(
        stopped.err.contains("2 non-finite points skipped"),
        "{}",
        stopped.err
    );
    assert!(stopped.out.contains("invalid_points"), "{}", stopped.out);
}

#[test]
fn message_cut_short_is_skipped_with_a_counted_warning() {
    /// The first members of a PointCloud2 and nothing after.
    #[derive(Debug, Serialize)]
    struct Cut {
        header: Header,
        height: u32,
    }
    let s = around(10, |r| {
        // Another participant: one participant cannot hold the topic with two types.
        let dp = dds::participant(domain(10)).unwrap();
        let w: Writer<Cut> =
            dds::writer(&dp, "/points", POINTCLOUD2_TYPE, &dds::sensor_qos()).unwrap();
        assert!(dds::wait_for_reader(&w, HANG, &|| false));
        r.node.wait_matched("/points", 2);
        let cut = Cut {
            header: header(0.15),
            height: 1,
        };
        w.write(cut, None).unwrap();
        r.warned(1);
    });
    assert_eq!((s.summary.malformed, s.summary.warnings), (1, 1));
    assert!(s.err.contains("message ends inside"), "{}", s.err);
}

#[test]
fn ctrl_c_ends_a_node_process_cleanly_with_its_summary() {
    let _lock = serial();
    let mut child = std::process::Command::new(cli())
        .args(["ros2", "--domain", &domain(11).to_string()])
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("start kiss-odom ros2");
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut first = String::new();
    out.read_line(&mut first).unwrap();
    assert!(first.starts_with("listening on /points"), "{first}");
    let kill = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let status = child.wait().unwrap();
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut out, &mut rest).unwrap();
    assert!(status.success(), "exit status {status}");
    assert!(
        rest.contains("summary: received 0, registered 0, dropped 0"),
        "{rest}"
    );
}

/// With the gyroscope prior on, an IMU message that is not a `sensor_msgs/Imu` is counted and
/// warned about, and the node goes on with the good samples.
#[test]
fn malformed_imu_message_is_counted_and_warned_and_the_node_goes_on() {
    let _lock = serial();
    let dir = tempfile::tempdir().unwrap();
    let d = domain(10);
    let node = start_node_imu(d, dir.path(), "/imu");
    let dp = dds::participant(d).unwrap();
    let w: Writer<PointCloud2> =
        dds::writer(&dp, "/points", POINTCLOUD2_TYPE, &dds::sensor_qos()).unwrap();
    let imu: Writer<Imu> = dds::writer(&dp, "/imu", IMU_TYPE, &dds::sensor_qos()).unwrap();
    // A header alone on the IMU topic, from a participant of its own.
    let other = dds::participant(d).unwrap();
    let bad: Writer<Header> = dds::writer(&other, "/imu", IMU_TYPE, &dds::sensor_qos()).unwrap();
    assert!(dds::wait_for_reader(&w, HANG, &|| false), "no node");
    assert!(dds::wait_for_reader(&imu, HANG, &|| false), "no IMU reader");
    assert!(dds::wait_for_reader(&bad, HANG, &|| false), "no IMU reader");
    node.wait_matched("/points", 1);
    node.wait_matched("/imu", 2);
    // The bad message first, then a good sample, then the cloud, each once the node took the
    // one before: the two writers' messages travel apart and could pass each other.
    let took = |n: u64| {
        let ok = wait_until(HANG, || node.watch.imu_messages() >= n);
        assert!(
            ok,
            "the node took {} IMU messages",
            node.watch.imu_messages()
        );
    };
    bad.write(header(0.0), None).unwrap();
    took(1);
    let sample = kiss_odom_io::imu::ImuSample {
        time_ns: 50_000_000,
        ..Default::default()
    };
    imu.write(Imu::of(&sample, "imu"), None).unwrap();
    took(2);
    w.write(good(0), None).unwrap();
    let stopped = node.stop_after(1);
    let s = &stopped.summary;
    println!("{}{}", stopped.out, stopped.err);
    assert_eq!(s.registered, 1, "the node goes on");
    assert_eq!(
        s.imu,
        Some(ImuCounts {
            received: 2,
            malformed: 1,
            dropped: 0
        })
    );
    assert_eq!(s.warnings, 1);
    assert!(
        stopped
            .err
            .contains("IMU message 1: skipped: message ends inside"),
        "{}",
        stopped.err
    );
    assert!(stopped.out.contains("imu received 2 (malformed 1)"));
}
