//! Tests of `packet_frames` (decoding itself: the workspace tests, on simulated packets).

use super::*;
use crate::ros::test_messages::{nebula_packets, ouster_packet, text, write_db3};
use crate::Format;

const PACKET: &str = "ouster_sensor_msgs/msg/PacketMsg";
const STRING: &str = "std_msgs/msg/String";

fn ouster_bag(dir: &Path, metadata: Option<&str>) -> std::path::PathBuf {
    let path = dir.join("o.db3");
    let mut topics = vec![
        ("/ouster/lidar_packets", PACKET),
        ("/ouster/imu_packets", PACKET),
    ];
    let mut msgs = vec![
        (0, 10, ouster_packet(false, &[0; 64])),
        (1, 11, ouster_packet(false, &[0; 48])),
    ];
    if let Some(json) = metadata {
        topics.push(("/ouster/metadata", STRING));
        msgs.push((2, 5, text(false, json)));
    }
    write_db3(&path, &topics, &msgs);
    path
}

#[test]
fn ouster_packets_need_the_metadata_their_bag_carries_or_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let open = |p: &Path| crate::open(p, Format::Auto, &OpenOptions::default());
    // The IMU packets' topic is not a candidate for frames: the lidar one is chosen alone.
    let e = format!("{:#}", open(&ouster_bag(dir.path(), None)).err().unwrap());
    assert!(
        e.contains("Ouster packets on /ouster/lidar_packets") && e.contains("--calibration"),
        "{e}"
    );
    let e = format!(
        "{:#}",
        open(&ouster_bag(dir.path(), Some("{not json")))
            .err()
            .unwrap()
    );
    assert!(e.contains("o.db3:/ouster/metadata"), "{e}");
}

#[test]
fn nebula_packets_go_to_the_port_their_sensor_sends_them_to() {
    let d = Datagrams::new(
        false,
        &[Kind::NebulaPackets],
        Ports {
            lidar: None,
            imu: None,
        },
    );
    assert_eq!(d.port(0, &[0xEE, 0xFF, 6, 1]), VELODYNE_PORT);
    assert_eq!(d.port(0, &[0; 1206]), VELODYNE_PORT);
    let given = Datagrams::new(
        false,
        &[Kind::NebulaPackets],
        Ports {
            lidar: Some(2369),
            imu: None,
        },
    );
    assert_eq!(given.port(0, &[0xEE, 0xFF, 6, 1]), 2369);
    // A message that is not NebulaPackets is counted and named once.
    let mut d = Datagrams::new(
        false,
        &[Kind::NebulaPackets],
        Ports {
            lidar: None,
            imu: None,
        },
    );
    d.add(
        0,
        5,
        Ok(Kind::NebulaPackets),
        &nebula_packets(5, &[(5, vec![1; 10])]),
    );
    d.add(0, 6, Ok(Kind::NebulaPackets), &[0, 1, 0, 0, 9]);
    assert_eq!(d.queue.len(), 1);
    let w = d.warnings();
    assert!(
        w[0].contains("1 of 2 packet message(s)") && w[0].contains("message 1"),
        "{w:?}"
    );
}
