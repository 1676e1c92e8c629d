//! The ROS 2 messages the node exchanges, laid out as their IDL so that the DDS layer's CDR
//! serializer writes what `rmw` implementations write.
//!
//! Outgoing messages (`nav_msgs/msg/Odometry`, `tf2_msgs/msg/TFMessage`,
//! `sensor_msgs/msg/PointCloud2`) are serde structs in IDL field order. Incoming clouds are kept
//! as raw CDR bytes ([`RawCloud`]), parsed by the MCAP reader's parser
//! ([`kiss_odom_io::ros::message::parse_cdr`]) and decoded by [`kiss_odom_io::ros::pointcloud2::decode`], the
//! code every other input format uses, so a malformed cloud is an error the node counts, not one
//! the DDS layer swallows.

use kiss_odom_io::ros::pointcloud2::FLOAT64;
use nalgebra::Isometry3;
use rustdds::no_key::{Decode, DefaultDecoder, DeserializerAdapter};
use rustdds::RepresentationIdentifier;
use serde::ser::SerializeTuple;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// DDS type name of `sensor_msgs/msg/PointCloud2` (ROS 2 naming: `pkg::msg::dds_::Name_`).
pub const POINTCLOUD2_TYPE: &str = "sensor_msgs::msg::dds_::PointCloud2_";
/// DDS type name of `nav_msgs/msg/Odometry`.
pub(crate) const ODOMETRY_TYPE: &str = "nav_msgs::msg::dds_::Odometry_";
/// DDS type name of `tf2_msgs/msg/TFMessage`.
pub(crate) const TFMESSAGE_TYPE: &str = "tf2_msgs::msg::dds_::TFMessage_";

/// DDS type name of `sensor_msgs/msg/Imu`.
pub const IMU_TYPE: &str = "sensor_msgs::msg::dds_::Imu_";

/// The DDS topic of ROS 2 topic `name`: `rt/` and the name without its leading slash.
pub(crate) fn dds_topic(name: &str) -> String {
    format!("rt/{}", name.trim_start_matches('/'))
}

/// `builtin_interfaces/msg/Time`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Time {
    /// Seconds.
    pub(crate) sec: i32,
    /// Nanoseconds, below 1e9.
    pub(crate) nanosec: u32,
}

impl Time {
    /// Seconds as f64, the way the readers compute a frame time.
    pub(crate) fn seconds(self) -> f64 {
        kiss_odom_io::ros::pointcloud2::Stamp {
            sec: i64::from(self.sec),
            nsec: self.nanosec,
        }
        .seconds()
    }

    /// The stamp nearest to `seconds` (saturating outside the i32 range).
    pub fn from_seconds(seconds: f64) -> Self {
        let whole = seconds.floor();
        let mut sec = whole.clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32;
        let mut nanosec = ((seconds - whole) * 1e9).round().clamp(0.0, 1e9) as u32;
        if nanosec >= 1_000_000_000 {
            sec = sec.saturating_add(1);
            nanosec = 0;
        }
        Self { sec, nanosec }
    }
}

/// `std_msgs/msg/Header`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// Acquisition time.
    pub stamp: Time,
    /// Coordinate frame.
    pub frame_id: String,
}

/// `geometry_msgs/msg/Vector3` (also `Point`, which has the same layout).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// `geometry_msgs/msg/Quaternion`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub(crate) w: f64,
}

/// `geometry_msgs/msg/Pose` (and `Transform`: translation then rotation, the same layout).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct Pose {
    /// Position.
    pub(crate) position: Vector3,
    /// Orientation.
    pub(crate) orientation: Quaternion,
}

impl Pose {
    /// The message of `p`, every value copied bit for bit.
    pub fn of(p: &Isometry3<f64>) -> Self {
        let t = p.translation.vector;
        let q = p.rotation.coords;
        Self {
            position: Vector3 {
                x: t.x,
                y: t.y,
                z: t.z,
            },
            orientation: Quaternion {
                x: q.x,
                y: q.y,
                z: q.z,
                w: q.w,
            },
        }
    }
}

/// A row-major 6x6 covariance (`double[36]`: a CDR array, no length prefix).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Covariance(pub [f64; 36]);

impl Covariance {
    /// The diagonal matrix with `linear` on x, y, z and `angular` on the three rotations.
    pub(crate) fn diagonal(linear: f64, angular: f64) -> Self {
        let mut c = [0.0; 36];
        for i in 0..3 {
            c[7 * i] = linear;
            c[7 * (i + 3)] = angular;
        }
        Self(c)
    }
}

impl Serialize for Covariance {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut t = s.serialize_tuple(36)?;
        for v in &self.0 {
            t.serialize_element(v)?;
        }
        t.end()
    }
}

impl<'de> Deserialize<'de> for Covariance {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = Covariance;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("36 doubles")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut a: A,
            ) -> Result<Covariance, A::Error> {
                let mut c = [0.0; 36];
                for (i, v) in c.iter_mut().enumerate() {
                    *v = a
                        .next_element()?
                        .ok_or_else(|| serde::de::Error::invalid_length(i, &self))?;
                }
                Ok(Covariance(c))
            }
        }
        d.deserialize_tuple(36, Visit)
    }
}

/// `geometry_msgs/msg/PoseWithCovariance`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct PoseWithCovariance {
    /// Pose.
    pub(crate) pose: Pose,
    /// Row-major over (x, y, z, rot x, rot y, rot z).
    pub(crate) covariance: Covariance,
}

/// `geometry_msgs/msg/Twist`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Twist {
    /// m/s.
    pub linear: Vector3,
    /// rad/s.
    pub angular: Vector3,
}

/// `geometry_msgs/msg/TwistWithCovariance`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct TwistWithCovariance {
    /// Twist.
    pub(crate) twist: Twist,
    /// Row-major over (vx, vy, vz, wx, wy, wz).
    pub(crate) covariance: Covariance,
}

/// `nav_msgs/msg/Odometry`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct Odometry {
    /// Stamp of the cloud and the odometry frame.
    pub(crate) header: Header,
    /// The moving frame (base).
    pub(crate) child_frame_id: String,
    /// Pose of the child frame in the header frame.
    pub(crate) pose: PoseWithCovariance,
    /// Velocity in the child frame.
    pub(crate) twist: TwistWithCovariance,
}

/// `geometry_msgs/msg/TransformStamped`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct TransformStamped {
    /// Stamp and parent frame.
    pub(crate) header: Header,
    /// Child frame.
    pub(crate) child_frame_id: String,
    /// Child frame in the parent frame (translation, rotation).
    pub(crate) transform: Pose,
}

/// `tf2_msgs/msg/TFMessage`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct TfMessage {
    /// Transforms.
    pub(crate) transforms: Vec<TransformStamped>,
}

/// `sensor_msgs/msg/PointField`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Field {
    /// Name.
    pub name: String,
    /// Byte offset in a point.
    pub offset: u32,
    /// Datatype code.
    pub datatype: u8,
    /// Values.
    pub count: u32,
}

/// `sequence<uint8>` written as one length and the bytes (not byte by byte).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bytes(pub Vec<u8>);

impl Serialize for Bytes {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_bytes(&self.0)
    }
}

/// `sensor_msgs/msg/PointCloud2` as published (by `--play` and the local map).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PointCloud2 {
    /// Stamp and frame.
    pub(crate) header: Header,
    /// Rows.
    pub(crate) height: u32,
    /// Points per row.
    pub width: u32,
    /// Layout.
    pub fields: Vec<Field>,
    /// Byte order of `data`.
    pub(crate) is_bigendian: bool,
    /// Bytes per point.
    pub point_step: u32,
    /// Bytes per row.
    pub row_step: u32,
    /// Points.
    pub data: Bytes,
    /// No invalid points.
    pub(crate) is_dense: bool,
}

impl PointCloud2 {
    /// An unorganized little-endian cloud of `points` with fields x, y, z and, when `stamps`
    /// is given, `t`, all FLOAT64 (24 or 32 bytes a point). Doubles keep every value exactly
    /// as read, so a node fed by `--play` registers the same numbers `kiss-odom run` does.
    pub fn xyzt(header: Header, points: &[[f64; 3]], stamps: Option<&[f64]>) -> Self {
        let step = if stamps.is_some() { 32 } else { 24 };
        let mut data = Vec::with_capacity(points.len() * step);
        for (i, p) in points.iter().enumerate() {
            for v in p {
                data.extend_from_slice(&v.to_le_bytes());
            }
            if let Some(s) = stamps {
                data.extend_from_slice(&s.get(i).copied().unwrap_or(f64::NAN).to_le_bytes());
            }
        }
        let f = |name: &str, offset| Field {
            name: name.into(),
            offset,
            datatype: FLOAT64,
            count: 1,
        };
        let mut fields = vec![f("x", 0), f("y", 8), f("z", 16)];
        if stamps.is_some() {
            fields.push(f("t", 24));
        }
        Self {
            header,
            height: 1,
            width: points.len() as u32,
            fields,
            is_bigendian: false,
            point_step: step as u32,
            row_step: (step * points.len()) as u32,
            data: Bytes(data),
            is_dense: points.iter().all(|p| p.iter().all(|v| v.is_finite())),
        }
    }
}

/// `sensor_msgs/msg/Imu`, as the player publishes a recording's samples: no orientation
/// (its covariance's first element -1, the message's convention for "not measured"), the
/// angular velocity and linear acceleration with unknown (zero) covariance. The node reads it
/// back with [`kiss_odom_io::ros::imu_msg::parse_cdr`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Imu {
    /// Stamp (the sample's time) and frame.
    pub(crate) header: Header,
    /// Orientation (identity, not measured).
    pub(crate) orientation: Quaternion,
    /// Its covariance, row-major 3x3.
    pub orientation_covariance: [f64; 9],
    /// rad/s.
    pub(crate) angular_velocity: Vector3,
    /// Its covariance.
    pub(crate) angular_velocity_covariance: [f64; 9],
    /// m/s^2.
    pub(crate) linear_acceleration: Vector3,
    /// Its covariance.
    pub(crate) linear_acceleration_covariance: [f64; 9],
}

impl Imu {
    /// The message of `s`, stamped with its time to the nanosecond.
    pub fn of(s: &kiss_odom_io::imu::ImuSample, frame_id: &str) -> Self {
        let v = |a: [f64; 3]| Vector3 {
            x: a[0],
            y: a[1],
            z: a[2],
        };
        let mut not_measured = [0.0; 9];
        not_measured[0] = -1.0;
        Self {
            header: Header {
                stamp: Time {
                    sec: i32::try_from(s.time_ns / 1_000_000_000).unwrap_or(i32::MAX),
                    nanosec: (s.time_ns % 1_000_000_000) as u32,
                },
                frame_id: frame_id.to_string(),
            },
            orientation: Quaternion {
                x: 0.0,
                y: 0.0,
                z: 0.0,
                w: 1.0,
            },
            orientation_covariance: not_measured,
            angular_velocity: v(s.gyro),
            angular_velocity_covariance: [0.0; 9],
            linear_acceleration: v(s.accel),
            linear_acceleration_covariance: [0.0; 9],
        }
    }
}

/// An incoming message as serialized: the 4-byte encapsulation header, then the CDR body.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RawCloud(pub Vec<u8>);

/// Hands the DDS layer's payload over untouched (see the module doc).
pub struct RawAdapter;

/// The decoder of [`RawAdapter`]: copies the bytes behind an encapsulation header.
#[derive(Clone, Copy)]
pub struct RawDecoder;

impl DeserializerAdapter<RawCloud> for RawAdapter {
    type Error = std::convert::Infallible;
    type Decoded = RawCloud;

    fn supported_encodings() -> &'static [RepresentationIdentifier] {
        &[
            RepresentationIdentifier::CDR_LE,
            RepresentationIdentifier::CDR_BE,
        ]
    }

    fn transform_decoded(decoded: RawCloud) -> RawCloud {
        decoded
    }
}

impl DefaultDecoder<RawCloud> for RawAdapter {
    type Decoder = RawDecoder;
    const DECODER: RawDecoder = RawDecoder;
}

impl Decode<'_, RawCloud> for RawDecoder {
    type Error = std::convert::Infallible;

    fn decode_bytes(
        self,
        bytes: &[u8],
        encoding: RepresentationIdentifier,
    ) -> Result<RawCloud, Self::Error> {
        // The DDS layer has already split off the encapsulation header; `parse_cdr` wants it.
        let little = encoding == RepresentationIdentifier::CDR_LE;
        let mut out = Vec::with_capacity(bytes.len() + 4);
        out.extend_from_slice(&[0, u8::from(little), 0, 0]);
        out.extend_from_slice(bytes);
        Ok(RawCloud(out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use kiss_odom_io::ros::pointcloud2::decode;

    #[test]
    fn topic_and_time_follow_ros2_conventions() {
        assert_eq!(dds_topic("/kiss/odometry"), "rt/kiss/odometry");
        assert_eq!(dds_topic("points"), "rt/points");
        let t = Time::from_seconds(1_700_000_000.25);
        assert_eq!((t.sec, t.nanosec), (1_700_000_000, 250_000_000));
        assert_eq!(Time::from_seconds(-0.5).nanosec, 500_000_000);
        assert_eq!(Time::from_seconds(f64::NAN).nanosec, 0);
    }

    #[test]
    fn published_clouds_parse_back_through_the_readers_decoder() {
        let pts = [[1.5, -2.0, 0.25], [f64::NAN, 3.0, 4.0]];
        let stamps = [0.125, 1e9 + 0.5];
        // Values f32 cannot hold survive the round trip.
        let pts = [[pts[0][0] + 1e-9, pts[0][1], pts[0][2]], pts[1]];
        let header = Header {
            stamp: Time::from_seconds(12.5),
            frame_id: "lidar".into(),
        };
        let msg = PointCloud2::xyzt(header, &pts, Some(&stamps));
        assert!(!msg.is_dense);
        let body = rustdds::serialization::to_vec::<_, byteorder::LittleEndian>(&msg).unwrap();
        let raw = RawDecoder
            .decode_bytes(&body, RepresentationIdentifier::CDR_LE)
            .unwrap();
        let cloud = kiss_odom_io::ros::message::parse_cdr(&raw.0).unwrap();
        assert_eq!(cloud.frame_id, "lidar");
        assert_eq!(cloud.stamp.seconds(), 12.5);
        let d = decode(&cloud).unwrap();
        assert_eq!(d.points[0], [1.5 + 1e-9, -2.0, 0.25]);
        assert!(d.points[1][0].is_nan());
        assert_eq!(d.stamps, Some(stamps.to_vec()));
    }

    #[test]
    fn published_imu_samples_parse_back_through_the_readers_decoder() {
        let sample = kiss_odom_io::imu::ImuSample {
            time_ns: 1_700_000_000_123_456_789,
            gyro: [0.1 + 1e-12, -0.2, 3.0],
            accel: [0.5, 9.81, -1e-9],
        };
        for frame_id in ["", "imu", "imu_link"] {
            let msg = Imu::of(&sample, frame_id);
            let body = rustdds::serialization::to_vec::<_, byteorder::LittleEndian>(&msg).unwrap();
            let raw = RawDecoder
                .decode_bytes(&body, RepresentationIdentifier::CDR_LE)
                .unwrap();
            assert_eq!(
                kiss_odom_io::ros::imu_msg::parse_cdr(&raw.0),
                Ok(sample),
                "{frame_id:?}"
            );
        }
    }

    #[test]
    fn covariance_is_a_fixed_array_of_36_doubles() {
        let c = Covariance::diagonal(0.1, 0.2);
        let body = rustdds::serialization::to_vec::<_, byteorder::LittleEndian>(&c).unwrap();
        assert_eq!(body.len(), 36 * 8, "no length prefix");
        assert_eq!(c.0[0], 0.1);
        assert_eq!(c.0[14], 0.1);
        assert_eq!(c.0[21], 0.2);
        assert_eq!(c.0[35], 0.2);
        assert_eq!(c.0.iter().filter(|v| **v != 0.0).count(), 6);
    }
}
