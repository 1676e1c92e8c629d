//! A simulated sequence as a ROS recording (`simulate --format bag|mcap`): every frame as a
//! `sensor_msgs/PointCloud2` on [`POINTS_TOPIC`] stamped at its sweep's end, and with
//! `--imu-rate` every IMU sample as a `sensor_msgs/Imu` on [`IMU_TOPIC`] stamped at its time,
//! in time order (a frame after the samples up to its end), received when stamped. A ROS 1 bag
//! ([`bag`]) carries ROS 1 messages, an MCAP file ROS 2's CDR ones ([`messages`]). The points
//! and their times are the frame files' numbers, and the stamps the nanoseconds `imu.csv`
//! writes, so `run` reads the same frames and samples from the recording as from the folder.

pub mod bag;
pub mod messages;

use crate::imu::ImuSample;
use crate::sensor::Frame;
use anyhow::{bail, Context, Result};
use messages::{Encoding, Stamp};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// The bag's file name in the output folder.
pub const BAG_NAME: &str = "points.bag";
/// The MCAP file's name in the output folder.
pub const MCAP_NAME: &str = "points.mcap";
/// The clouds' topic.
pub const POINTS_TOPIC: &str = "/points";
/// The IMU's topic.
pub const IMU_TOPIC: &str = "/imu";
/// The clouds' `frame_id`.
const LIDAR_FRAME: &str = "lidar";
/// The IMU samples' `frame_id`.
const IMU_FRAME: &str = "imu";

/// ROS 1 `sensor_msgs/PointCloud2`.
const CLOUD_CONN: bag::Connection = bag::Connection {
    topic: POINTS_TOPIC,
    tp: "sensor_msgs/PointCloud2",
    md5: "1158d486dd51d683ce2f1be655c3c181",
    definition: "std_msgs/Header header\nuint32 height\nuint32 width\nPointField[] fields\n\
        bool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n\
        ================================================================================\n\
        MSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n\
        ================================================================================\n\
        MSG: sensor_msgs/PointField\nuint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\n\
        uint8 UINT16=4\nuint8 INT32=5\nuint8 UINT32=6\nuint8 FLOAT32=7\nuint8 FLOAT64=8\n\
        string name\nuint32 offset\nuint8 datatype\nuint32 count\n",
};

/// ROS 1 `sensor_msgs/Imu`.
const IMU_CONN: bag::Connection = bag::Connection {
    topic: IMU_TOPIC,
    tp: "sensor_msgs/Imu",
    md5: "6a62c6daae103f4ff57a132d6f95cec2",
    definition: "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\n\
        float64[9] orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\n\
        float64[9] angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\n\
        float64[9] linear_acceleration_covariance\n\
        ================================================================================\n\
        MSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n\
        ================================================================================\n\
        MSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n\
        ================================================================================\n\
        MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n",
};

/// ROS 2 schema names.
const CLOUD_SCHEMA: &str = "sensor_msgs/msg/PointCloud2";
const IMU_SCHEMA: &str = "sensor_msgs/msg/Imu";

/// Which container.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Container {
    /// A ROS 1 bag.
    Bag,
    /// A ROS 2 MCAP file.
    Mcap,
}

enum Sink {
    Bag(bag::BagWriter),
    Mcap {
        writer: Box<mcap::Writer<BufWriter<File>>>,
        cloud: u16,
        imu: u16,
    },
}

/// A recording being written, frame by frame.
pub struct RosWriter {
    path: PathBuf,
    sink: Sink,
    /// The IMU's samples and how many are written.
    imu: Vec<ImuSample>,
    imu_next: usize,
}

impl RosWriter {
    /// Creates `path` as `container`, for frames and, if any, the IMU's `samples`.
    pub fn create(path: &Path, container: Container, imu: Vec<ImuSample>) -> Result<Self> {
        let sink = match container {
            Container::Bag => {
                let conns: &[bag::Connection] = if imu.is_empty() {
                    &[CLOUD_CONN]
                } else {
                    &[CLOUD_CONN, IMU_CONN]
                };
                Sink::Bag(bag::BagWriter::create(path, conns)?)
            }
            Container::Mcap => {
                let file =
                    File::create(path).with_context(|| format!("creating {}", path.display()))?;
                let mut writer = mcap::WriteOptions::new()
                    .compression(None)
                    .profile("ros2")
                    .create(BufWriter::new(file))
                    .with_context(|| format!("writing {}", path.display()))?;
                let mut channel = |topic: &str, schema: &str| -> Result<u16> {
                    let sid = writer.add_schema(schema, "ros2msg", b"")?;
                    Ok(writer.add_channel(sid, topic, "cdr", &BTreeMap::new())?)
                };
                let cloud = channel(POINTS_TOPIC, CLOUD_SCHEMA)?;
                let imu_channel = if imu.is_empty() {
                    0
                } else {
                    channel(IMU_TOPIC, IMU_SCHEMA)?
                };
                Sink::Mcap {
                    writer: Box::new(writer),
                    cloud,
                    imu: imu_channel,
                }
            }
        };
        Ok(Self {
            path: path.to_path_buf(),
            sink,
            imu,
            imu_next: 0,
        })
    }

    /// Writes the IMU samples up to `frame`'s end not written yet, then `frame`.
    pub fn write_frame(&mut self, frame: &Frame) -> Result<()> {
        let end = stamp(frame.end_time, "a sweep's end")?;
        let n = self.imu[self.imu_next..]
            .iter()
            .take_while(|s| Stamp::of(s.time).is_some_and(|t| t.nanos() <= end.nanos()))
            .count();
        self.write(self.imu_next..self.imu_next + n, Some((frame, end)))
    }

    /// Writes the samples after the last frame and closes the file.
    pub fn finish(mut self) -> Result<()> {
        self.write(self.imu_next..self.imu.len(), None)?;
        let path = &self.path;
        match self.sink {
            Sink::Bag(b) => b.finish(),
            Sink::Mcap { mut writer, .. } => writer
                .finish()
                .map(drop)
                .with_context(|| format!("writing {}", path.display())),
        }
    }

    /// Writes the samples `range`, then `frame` if given.
    fn write(
        &mut self,
        range: std::ops::Range<usize>,
        frame: Option<(&Frame, Stamp)>,
    ) -> Result<()> {
        let enc = match self.sink {
            Sink::Bag(_) => Encoding::Ros1,
            Sink::Mcap { .. } => Encoding::Cdr,
        };
        // (connection: 0 cloud, 1 IMU; sequence number; time; body)
        let mut msgs: Vec<(u32, u32, u64, Vec<u8>)> = Vec::with_capacity(range.len() + 1);
        for k in range.clone() {
            let s = &self.imu[k];
            let t = stamp(s.time, "an IMU sample")?;
            msgs.push((
                1,
                k as u32,
                t.nanos(),
                messages::imu(enc, k as u32, s, t, IMU_FRAME),
            ));
        }
        if let Some((frame, t)) = frame {
            let body = messages::point_cloud2(enc, frame, t, LIDAR_FRAME);
            msgs.push((0, frame.index as u32, t.nanos(), body));
        }
        self.imu_next = range.end;
        match &mut self.sink {
            Sink::Bag(b) => {
                let msgs: Vec<(u32, u64, Vec<u8>)> = msgs
                    .into_iter()
                    .map(|(c, _, t, body)| (c, t, body))
                    .collect();
                b.chunk(&msgs)
            }
            Sink::Mcap { writer, cloud, imu } => {
                for (c, sequence, t, body) in msgs {
                    let header = mcap::records::MessageHeader {
                        channel_id: if c == 0 { *cloud } else { *imu },
                        sequence,
                        log_time: t,
                        publish_time: t,
                    };
                    writer
                        .write_to_known_channel(&header, &body)
                        .with_context(|| format!("writing {}", self.path.display()))?;
                }
                Ok(())
            }
        }
    }
}

/// The stamp of `t` s; a recording cannot hold times before 1970.
fn stamp(t: f64, what: &str) -> Result<Stamp> {
    match Stamp::of(t) {
        Some(s) => Ok(s),
        None => bail!("{what} at {t} s cannot be a ROS stamp (0 to 2^32 s); use --start-time"),
    }
}
