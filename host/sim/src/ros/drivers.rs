//! The messages sensor drivers record, serialized from their definitions as
//! [`messages`](super::messages) serializes the points' (ROS 1 or CDR): the packet messages of
//! the Velodyne, Hesai and Ouster drivers and nebula's generic one, the `std_msgs/String`
//! ouster-ros records the sensor's metadata on, and Livox's `CustomMsg`.

use super::messages::{Encoding, Stamp};
use super::Topic;

/// A packet and the time its driver received it, ns.
pub type Stamped<'a> = (u64, &'a [u8]);

/// The bytes of a Velodyne packet in a `VelodynePacket`.
const VELODYNE_PACKET: usize = 1206;
/// The bytes of nebula's `PandarPacket.data`.
const PANDAR_PACKET: usize = 1500;

/// `std_msgs/Header` of `frame_id` stamped `ns`.
fn header(o: &mut super::messages::Out, ns: u64, frame_id: &str) {
    o.header(0, stamp(ns), frame_id);
}

fn stamp(ns: u64) -> Stamp {
    Stamp {
        sec: (ns / 1_000_000_000) as u32,
        nsec: (ns % 1_000_000_000) as u32,
    }
}

/// `time` / `builtin_interfaces/Time`.
fn time(o: &mut super::messages::Out, ns: u64) {
    let s = stamp(ns);
    o.u32(s.sec);
    o.u32(s.nsec);
}

/// `velodyne_msgs/VelodyneScan`: each packet a stamp and a `uint8[1206]`; the scan is stamped
/// with its last packet, as the ROS driver stamps it.
pub fn velodyne_scan(enc: Encoding, packets: &[Stamped<'_>]) -> Vec<u8> {
    let mut o = enc.out();
    header(&mut o, packets.last().map_or(0, |p| p.0), "velodyne");
    o.u32(packets.len() as u32);
    for (ns, data) in packets {
        time(&mut o, *ns);
        let mut fixed = data.to_vec();
        fixed.resize(VELODYNE_PACKET, 0);
        o.bytes.extend_from_slice(&fixed);
    }
    o.bytes
}

/// `pandar_msgs/PandarScan` as nebula defines it: each packet a stamp, a `uint8[1500]` and the
/// `size` of it used; stamped with its first packet.
pub fn pandar_scan(enc: Encoding, packets: &[Stamped<'_>]) -> Vec<u8> {
    let mut o = enc.out();
    header(&mut o, packets.first().map_or(0, |p| p.0), "hesai");
    o.u32(packets.len() as u32);
    for (ns, data) in packets {
        time(&mut o, *ns);
        let mut fixed = data.to_vec();
        fixed.resize(PANDAR_PACKET, 0);
        o.bytes.extend_from_slice(&fixed);
        o.u32(data.len() as u32);
    }
    o.bytes
}

/// `nebula_msgs/NebulaPackets` (ROS 2 only): each packet a stamp and a `uint8[]`.
pub fn nebula_packets(enc: Encoding, packets: &[Stamped<'_>]) -> Vec<u8> {
    let mut o = enc.out();
    header(&mut o, packets.first().map_or(0, |p| p.0), "lidar");
    o.u32(packets.len() as u32);
    for (ns, data) in packets {
        time(&mut o, *ns);
        o.bytes(data);
    }
    o.bytes
}

/// The bytes of nebula's `RobosensePacket.data`.
const ROBOSENSE_PACKET: usize = 1248;

/// `robosense_msgs/RobosenseScan` (nebula): each packet a stamp and a `uint8[1248]`; stamped
/// with its first packet.
pub fn robosense_scan(enc: Encoding, packets: &[Stamped<'_>]) -> Vec<u8> {
    let mut o = enc.out();
    header(&mut o, packets.first().map_or(0, |p| p.0), "robosense");
    o.u32(packets.len() as u32);
    for (ns, data) in packets {
        time(&mut o, *ns);
        let mut fixed = data.to_vec();
        fixed.resize(ROBOSENSE_PACKET, 0);
        o.bytes.extend_from_slice(&fixed);
    }
    o.bytes
}

/// `robosense_msgs/RobosenseInfoPacket` (nebula): the model's name and a DIFOP packet.
pub fn robosense_info(enc: Encoding, model: &str, (ns, data): Stamped<'_>) -> Vec<u8> {
    let mut o = enc.out();
    o.string(model);
    time(&mut o, ns);
    let mut fixed = data.to_vec();
    fixed.resize(ROBOSENSE_PACKET, 0);
    o.bytes.extend_from_slice(&fixed);
    o.bytes
}

/// Ouster's `PacketMsg`: one packet, no stamp.
pub fn ouster_packet(enc: Encoding, data: &[u8]) -> Vec<u8> {
    let mut o = enc.out();
    o.bytes(data);
    o.bytes
}

/// `std_msgs/String`.
pub fn text(enc: Encoding, s: &str) -> Vec<u8> {
    let mut o = enc.out();
    o.string(s);
    o.bytes
}

/// One point of a Livox `CustomMsg`: ns after the message's `timebase`, x y z (m),
/// reflectivity, tag, line.
pub type CustomPoint = (u32, [f32; 3], u8, u8, u8);

/// Livox's `CustomMsg` of `points` whose first is at `timebase` ns, stamped then.
pub fn custom_msg(enc: Encoding, timebase: u64, points: &[CustomPoint]) -> Vec<u8> {
    let mut o = enc.out();
    header(&mut o, timebase, "livox_frame");
    o.align(8);
    o.bytes.extend_from_slice(&timebase.to_le_bytes());
    o.u32(points.len() as u32); // point_num
    o.u8(0); // lidar_id
    o.bytes.extend_from_slice(&[0; 3]); // rsvd
    o.u32(points.len() as u32);
    for (offset, xyz, reflectivity, tag, line) in points {
        o.u32(*offset);
        for v in xyz {
            o.u32(v.to_bits());
        }
        o.u8(*reflectivity);
        o.u8(*tag);
        o.u8(*line);
    }
    o.bytes
}

/// `std_msgs/Header` as a ROS 1 definition quotes it.
macro_rules! header_def {
    () => {
        "================================================================================\n\
         MSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n"
    };
}

/// The topics the drivers record on, with their types.
pub const VELODYNE: Topic = Topic {
    name: "/velodyne_packets",
    ros1: "velodyne_msgs/VelodyneScan",
    ros2: "velodyne_msgs/msg/VelodyneScan",
    md5: "50804fc9533a0e579e6322c04ae70566",
    definition: concat!(
        "Header header\nVelodynePacket[] packets\n",
        header_def!(),
        "================================================================================\n\
         MSG: velodyne_msgs/VelodynePacket\ntime stamp\nuint8[1206] data\n"
    ),
};

/// nebula's Hesai packets.
pub const PANDAR: Topic = Topic {
    name: "/pandar_packets",
    ros1: "pandar_msgs/PandarScan",
    ros2: "pandar_msgs/msg/PandarScan",
    md5: "96facf9d6e028e0cacbe7058fbabc851",
    definition: concat!(
        "Header header\nPandarPacket[] packets\n",
        header_def!(),
        "================================================================================\n\
         MSG: pandar_msgs/PandarPacket\ntime stamp\nuint8[1500] data\nuint32 size\n"
    ),
};

/// nebula's packets of any sensor (ROS 2 only: no ROS 1 type).
pub const NEBULA: Topic = Topic {
    name: "/nebula_packets",
    ros1: "",
    ros2: "nebula_msgs/msg/NebulaPackets",
    md5: "",
    definition: "",
};

/// nebula's Robosense MSOP packets (ROS 2 only).
pub const ROBOSENSE: Topic = Topic {
    name: "/robosense_packets",
    ros1: "",
    ros2: "robosense_msgs/msg/RobosenseScan",
    md5: "",
    definition: "",
};

/// nebula's Robosense DIFOP packets (ROS 2 only).
pub const ROBOSENSE_INFO: Topic = Topic {
    name: "/robosense_info_packets",
    ros1: "",
    ros2: "robosense_msgs/msg/RobosenseInfoPacket",
    md5: "",
    definition: "",
};

/// ouster-ros's lidar packets.
pub const OUSTER_LIDAR: Topic = Topic {
    name: "/ouster/lidar_packets",
    ros1: "ouster_ros/PacketMsg",
    ros2: "ouster_sensor_msgs/msg/PacketMsg",
    md5: "4f7b5949e76f86d01e96b0e33ba9b5e3",
    definition: "uint8[] buf\n",
};

/// ouster-ros's IMU packets.
pub const OUSTER_IMU: Topic = Topic {
    name: "/ouster/imu_packets",
    ..OUSTER_LIDAR
};

/// ouster-ros's metadata JSON.
pub const OUSTER_META: Topic = Topic {
    name: "/ouster/metadata",
    ros1: "std_msgs/String",
    ros2: "std_msgs/msg/String",
    md5: "992ce8a1687cec8c8bd883ec73ca41d1",
    definition: "string data\n",
};

/// The Livox drivers' points (`livox_ros_driver` in ROS 1, `livox_ros_driver2` in ROS 2).
pub const LIVOX: Topic = Topic {
    name: "/livox/lidar",
    ros1: "livox_ros_driver/CustomMsg",
    ros2: "livox_ros_driver2/msg/CustomMsg",
    md5: "e4d6829bdfe657cb6c21a746c86b21a6",
    definition: concat!(
        "Header header\nuint64 timebase\nuint32 point_num\nuint8 lidar_id\nuint8[3] rsvd\n\
         CustomPoint[] points\n",
        header_def!(),
        "================================================================================\n\
         MSG: livox_ros_driver/CustomPoint\nuint32 offset_time\nfloat32 x\nfloat32 y\n\
         float32 z\nuint8 reflectivity\nuint8 tag\nuint8 line\n"
    ),
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_have_their_definitions_lengths() {
        let p = [7u8; 1080];
        let packets: [Stamped<'_>; 2] = [(1, &p), (2, &p)];
        // ROS 1: seq, stamp, "hesai", count, then (8 + 1500 + 4) a packet.
        assert_eq!(
            pandar_scan(Encoding::Ros1, &packets).len(),
            12 + 9 + 4 + 2 * 1512
        );
        // CDR: header, stamp, "hesai\0" (4 + 6), padding to 4, count, 1512 a packet.
        assert_eq!(
            pandar_scan(Encoding::Cdr, &packets).len(),
            4 + 8 + 10 + 2 + 4 + 2 * 1512
        );
        let points = [(0, [1.0, 2.0, 3.0], 4, 5, 6); 3];
        // CDR: header (8 + 4 + 12), padding to 8, timebase, point_num, id, rsvd, count, then
        // 19 bytes a point padded to 20 but the last.
        let m = custom_msg(Encoding::Cdr, 9, &points);
        assert_eq!(m.len(), 4 + 24 + 8 + 4 + 4 + 4 + 20 + 20 + 19);
        assert_eq!(
            custom_msg(Encoding::Ros1, 9, &points).len(),
            12 + 15 + 8 + 4 + 4 + 4 + 57
        );
    }
}
