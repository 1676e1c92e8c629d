//! The message types the ROS readers know, by the names both generations give them (ROS 1's
//! `pkg/Type`, ROS 2's `pkg/msg/Type`) and, in a ROS 1 bag, the MD5 sum of the definition
//! each layout was written from: a connection with a known name but another sum is another
//! layout, refused rather than misread.

use super::recording::Message;

/// A message type a reader decodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    /// `sensor_msgs/PointCloud2`: a frame.
    Cloud,
    /// `sensor_msgs/Imu`: IMU samples beside the frames.
    Imu,
    /// `velodyne_msgs/VelodyneScan`: Velodyne packets (ros-drivers' and nebula's driver).
    VelodyneScan,
    /// `pandar_msgs/PandarScan`: Hesai packets (nebula, Hesai's ROS drivers).
    PandarScan,
    /// `nebula_msgs/NebulaPackets`: any sensor's packets (nebula).
    NebulaPackets,
    /// `ouster_sensor_msgs/PacketMsg` (ROS 2) or `ouster_ros/PacketMsg` (ROS 1): one Ouster
    /// lidar or IMU packet.
    OusterPacket,
    /// `robosense_msgs/RobosenseScan` (nebula): Robosense MSOP packets.
    RobosenseScan,
    /// `robosense_msgs/RobosenseInfoPacket` (nebula): a Robosense DIFOP packet (the lasers'
    /// angles) and the model's name.
    RobosenseInfo,
    /// `livox_ros_driver/CustomMsg`, `livox_ros_driver2/CustomMsg`: Livox points with
    /// per-point times.
    LivoxCustom,
    /// `std_msgs/String`: where ouster-ros records the sensor's metadata JSON.
    Text,
}

/// Type names (ROS 1 spelling) of each kind.
const NAMES: [(&str, Kind); 15] = [
    ("sensor_msgs/PointCloud2", Kind::Cloud),
    ("sensor_msgs/Imu", Kind::Imu),
    ("velodyne_msgs/VelodyneScan", Kind::VelodyneScan),
    ("pandar_msgs/PandarScan", Kind::PandarScan),
    ("nebula_msgs/NebulaPackets", Kind::NebulaPackets),
    ("ouster_sensor_msgs/PacketMsg", Kind::OusterPacket),
    ("ouster_ros/PacketMsg", Kind::OusterPacket),
    ("ouster_msgs/PacketMsg", Kind::OusterPacket),
    ("robosense_msgs/RobosenseScan", Kind::RobosenseScan),
    ("robosense_msgs/RobosenseInfoPacket", Kind::RobosenseInfo),
    ("livox_ros_driver/CustomMsg", Kind::LivoxCustom),
    ("livox_ros_driver2/CustomMsg", Kind::LivoxCustom),
    ("livox_ros2_driver/CustomMsg", Kind::LivoxCustom),
    ("livox_interfaces/CustomMsg", Kind::LivoxCustom),
    ("std_msgs/String", Kind::Text),
];

/// ROS 1 MD5 sums of the layouts read, by kind (PandarScan: nebula's fixed 1,500-byte
/// packets, and Hesai's ROS 1 drivers' `uint8[]` ones).
const MD5: [(Kind, &str); 8] = [
    (Kind::Cloud, "1158d486dd51d683ce2f1be655c3c181"),
    (Kind::Imu, "6a62c6daae103f4ff57a132d6f95cec2"),
    (Kind::VelodyneScan, "50804fc9533a0e579e6322c04ae70566"),
    (Kind::PandarScan, "96facf9d6e028e0cacbe7058fbabc851"),
    (Kind::PandarScan, "70c3ed4f4ae9144323298b04cc2c760b"),
    (Kind::OusterPacket, "4f7b5949e76f86d01e96b0e33ba9b5e3"),
    (Kind::LivoxCustom, "e4d6829bdfe657cb6c21a746c86b21a6"),
    (Kind::Text, "992ce8a1687cec8c8bd883ec73ca41d1"),
];

impl Kind {
    /// The kind of type `name` in either spelling, `None` for a type not read.
    pub fn of(name: &str) -> Option<Self> {
        let ros1 = name.replacen("/msg/", "/", 1);
        NAMES.iter().find(|(n, _)| *n == ros1).map(|(_, k)| *k)
    }

    /// The kind of a ROS 1 connection (type and MD5 sum): `Err` names what it is when the
    /// type is known but the sum is not a layout read.
    pub fn of_ros1(name: &str, md5: &str) -> Option<Result<Self, String>> {
        let kind = Self::of(name)?;
        if MD5.iter().any(|(k, m)| *k == kind && *m == md5) {
            return Some(Ok(kind));
        }
        let known: Vec<&str> = MD5
            .iter()
            .filter(|(k, _)| *k == kind)
            .map(|(_, m)| *m)
            .collect();
        Some(Err(format!(
            "{name} with md5 {md5} (read: {})",
            if known.is_empty() {
                "none in ROS 1".to_string()
            } else {
                known.join(", ")
            }
        )))
    }

    /// The kind of message `m` (of a ROS 1 bag if `ros1`), or what it is when it is not one
    /// read (another type, a ROS 1 definition of another layout).
    pub fn of_message(ros1: bool, m: &Message<'_>) -> Result<Self, String> {
        let known = match (ros1, m.md5) {
            (true, Some(md5)) => Self::of_ros1(m.tp, md5),
            _ => Self::of(m.tp).map(Ok),
        };
        known.unwrap_or_else(|| Err(m.tp.to_string()))
    }

    /// Its type name as a ROS 1 bag (`pkg/Type`) or a ROS 2 recording (`pkg/msg/Type`) names
    /// it, as drivers most often publish it.
    pub fn type_name(self, ros1: bool) -> String {
        let name = NAMES
            .iter()
            .find(|(_, k)| *k == self)
            .map_or("", |(n, _)| *n);
        match name.split_once('/') {
            Some((pkg, tp)) if !ros1 => format!("{pkg}/msg/{tp}"),
            _ => name.to_string(),
        }
    }

    /// Whether its messages become frames (points, or packets decoded into sweeps).
    pub fn is_frames(self) -> bool {
        !matches!(self, Self::Imu | Self::Text | Self::RobosenseInfo)
    }

    /// Whether its messages carry sensor packets.
    pub fn is_packets(self) -> bool {
        matches!(
            self,
            Self::VelodyneScan
                | Self::PandarScan
                | Self::NebulaPackets
                | Self::OusterPacket
                | Self::RobosenseScan
                | Self::RobosenseInfo
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_spellings_name_a_kind_and_a_ros1_sum_must_be_a_layout_read() {
        assert_eq!(
            Kind::of("pandar_msgs/msg/PandarScan"),
            Some(Kind::PandarScan)
        );
        assert_eq!(Kind::of("ouster_ros/PacketMsg"), Some(Kind::OusterPacket));
        assert_eq!(Kind::of("sensor_msgs/msg/Image"), None);
        let ok = Kind::of_ros1(
            "velodyne_msgs/VelodyneScan",
            "50804fc9533a0e579e6322c04ae70566",
        );
        assert_eq!(ok, Some(Ok(Kind::VelodyneScan)));
        let e = Kind::of_ros1("velodyne_msgs/VelodyneScan", "0123")
            .unwrap()
            .unwrap_err();
        assert!(e.contains("md5 0123") && e.contains("50804fc9"), "{e}");
        assert!(Kind::of_ros1("std_msgs/Int8", "x").is_none());
    }
}
