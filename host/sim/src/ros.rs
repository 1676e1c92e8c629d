//! A simulated sequence as a ROS recording (`simulate --format bag|mcap|db3`): a ROS 1 bag
//! ([`bag`]) of ROS 1 messages, or a ROS 2 MCAP file or sqlite3 bag ([`db3`]) of CDR ones, of
//! what `--messages` asks for:
//!
//! - `points`: every frame as a `sensor_msgs/PointCloud2` on [`POINTS_TOPIC`] stamped at its
//!   sweep's end ([`messages`]); the points and their times are the frame files' numbers;
//! - `packets`: the sensor's packets as its ROS driver records them ([`packet_bag`],
//!   [`drivers`]), at the times a pcap of them holds;
//! - `livox`: a Livox sensor's frames as the Livox driver's `CustomMsg` ([`livox`]).
//!
//! With `--imu-rate`, every IMU sample goes on [`IMU_TOPIC`] as a `sensor_msgs/Imu` stamped at
//! its time (a sensor that sends IMU packets sends them as packets instead), in time order: a
//! frame after the samples up to its end, received when stamped, with the nanoseconds
//! `imu.csv` writes, so `run` reads the same frames and samples from the recording as from the
//! folder.

pub mod bag;
pub mod db3;
pub mod drivers;
pub mod livox;
pub mod messages;
pub mod packet_bag;

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
/// The sqlite3 bag's folder name in the output folder.
pub const DB3_NAME: &str = "points";
/// The clouds' topic.
pub const POINTS_TOPIC: &str = "/points";
/// The IMU's topic.
pub const IMU_TOPIC: &str = "/imu";
/// The clouds' `frame_id`.
const LIDAR_FRAME: &str = "lidar";
/// The IMU samples' `frame_id`.
const IMU_FRAME: &str = "imu";

/// A topic: its name, its type in either generation, and (ROS 1) its definition and MD5.
#[derive(Clone, Copy, Debug)]
pub struct Topic {
    /// The topic.
    pub name: &'static str,
    /// The ROS 1 type, e.g. `sensor_msgs/Imu`; empty if the type has none.
    pub ros1: &'static str,
    /// The ROS 2 type, e.g. `sensor_msgs/msg/Imu`.
    pub ros2: &'static str,
    /// The ROS 1 definition's MD5 sum.
    pub md5: &'static str,
    /// The ROS 1 definition.
    pub definition: &'static str,
}

/// `sensor_msgs/PointCloud2` on [`POINTS_TOPIC`].
pub const CLOUD: Topic = Topic {
    name: POINTS_TOPIC,
    ros1: "sensor_msgs/PointCloud2",
    ros2: "sensor_msgs/msg/PointCloud2",
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

/// `sensor_msgs/Imu` on [`IMU_TOPIC`].
pub const IMU: Topic = Topic {
    name: IMU_TOPIC,
    ros1: "sensor_msgs/Imu",
    ros2: "sensor_msgs/msg/Imu",
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

/// Which container.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Container {
    /// A ROS 1 bag.
    Bag,
    /// A ROS 2 MCAP file.
    Mcap,
    /// A ROS 2 bag in sqlite3 storage (a folder).
    Db3,
}

impl Container {
    /// How its messages are serialized.
    pub fn encoding(self) -> Encoding {
        match self {
            Self::Bag => Encoding::Ros1,
            Self::Mcap | Self::Db3 => Encoding::Cdr,
        }
    }
}

/// A message to write: its topic (place in the recording's list), receive time (ns), body.
pub type Outgoing = (usize, u64, Vec<u8>);

enum Sink {
    Bag(bag::BagWriter),
    Mcap {
        writer: Box<mcap::Writer<BufWriter<File>>>,
        /// Channel ids and messages written on each.
        channels: Vec<(u16, u32)>,
    },
    Db3(db3::Db3Writer),
}

impl Sink {
    fn create(path: &Path, container: Container, topics: &[Topic]) -> Result<Self> {
        Ok(match container {
            Container::Bag => {
                let conns: Vec<bag::Connection> = (topics.iter())
                    .map(|t| bag::Connection {
                        topic: t.name,
                        tp: t.ros1,
                        md5: t.md5,
                        definition: t.definition,
                    })
                    .collect();
                Self::Bag(bag::BagWriter::create(path, &conns)?)
            }
            Container::Mcap => {
                let file =
                    File::create(path).with_context(|| format!("creating {}", path.display()))?;
                let mut writer = mcap::WriteOptions::new()
                    .compression(None)
                    .profile("ros2")
                    .create(BufWriter::new(file))
                    .with_context(|| format!("writing {}", path.display()))?;
                let mut channels = Vec::new();
                for t in topics {
                    let sid = writer.add_schema(t.ros2, "ros2msg", b"")?;
                    channels.push((writer.add_channel(sid, t.name, "cdr", &BTreeMap::new())?, 0));
                }
                Self::Mcap {
                    writer: Box::new(writer),
                    channels,
                }
            }
            Container::Db3 => Self::Db3(db3::Db3Writer::create(path, topics)?),
        })
    }

    /// Writes `msgs` (in time order; a bag's chunk).
    fn write(&mut self, path: &Path, msgs: Vec<Outgoing>) -> Result<()> {
        match self {
            Self::Bag(b) => {
                let msgs: Vec<(u32, u64, Vec<u8>)> =
                    msgs.into_iter().map(|(c, t, m)| (c as u32, t, m)).collect();
                b.chunk(&msgs)
            }
            Self::Mcap { writer, channels } => {
                for (c, t, body) in msgs {
                    let (channel_id, sequence) = &mut channels[c];
                    let header = mcap::records::MessageHeader {
                        channel_id: *channel_id,
                        sequence: *sequence,
                        log_time: t,
                        publish_time: t,
                    };
                    *sequence += 1;
                    writer
                        .write_to_known_channel(&header, &body)
                        .with_context(|| format!("writing {}", path.display()))?;
                }
                Ok(())
            }
            Self::Db3(d) => msgs.into_iter().try_for_each(|(c, t, m)| d.write(c, t, &m)),
        }
    }

    fn finish(self, path: &Path) -> Result<()> {
        match self {
            Self::Bag(b) => b.finish(),
            Self::Mcap { mut writer, .. } => writer
                .finish()
                .map(drop)
                .with_context(|| format!("writing {}", path.display())),
            Self::Db3(d) => d.finish(),
        }
    }
}

/// A recording being written, frame by frame.
pub struct RosWriter {
    path: PathBuf,
    sink: Sink,
    encoding: Encoding,
    /// The IMU's samples, the first not written yet, and their topic.
    imu: Vec<ImuSample>,
    imu_next: usize,
    imu_topic: usize,
}

impl RosWriter {
    /// Creates `path` as `container` for messages on `topics` and, if any, the IMU's
    /// `samples` (on [`IMU_TOPIC`], after `topics`).
    pub fn create(
        path: &Path,
        container: Container,
        topics: &[Topic],
        imu: Vec<ImuSample>,
    ) -> Result<Self> {
        let mut all = topics.to_vec();
        if !imu.is_empty() {
            all.push(IMU);
        }
        if container == Container::Bag {
            if let Some(t) = all.iter().find(|t| t.ros1.is_empty()) {
                bail!(
                    "{} has no ROS 1 type: write it to an MCAP file or a db3 bag",
                    t.ros2
                );
            }
        }
        Ok(Self {
            path: path.to_path_buf(),
            sink: Sink::create(path, container, &all)?,
            encoding: container.encoding(),
            imu,
            imu_next: 0,
            imu_topic: topics.len(),
        })
    }

    /// How its messages are serialized.
    pub fn encoding(&self) -> Encoding {
        self.encoding
    }

    /// Writes `frame` as a `sensor_msgs/PointCloud2` on the first topic, after the IMU samples
    /// up to its end not written yet.
    pub fn write_frame(&mut self, frame: &Frame) -> Result<()> {
        let end = stamp(frame.end_time, "a sweep's end")?;
        let body = messages::point_cloud2(self.encoding, frame, end, LIDAR_FRAME);
        self.write_after_imu(end.nanos(), vec![(0, end.nanos(), body)])
    }

    /// Writes the IMU samples up to `ns` not written yet, then `msgs` (in time order).
    pub fn write_after_imu(&mut self, ns: u64, msgs: Vec<Outgoing>) -> Result<()> {
        let n = self.imu[self.imu_next..]
            .iter()
            .take_while(|s| Stamp::of(s.time).is_some_and(|t| t.nanos() <= ns))
            .count();
        self.write(self.imu_next..self.imu_next + n, msgs)
    }

    /// Writes the samples after the last frame and closes the file.
    pub fn finish(mut self) -> Result<()> {
        self.write(self.imu_next..self.imu.len(), Vec::new())?;
        self.sink.finish(&self.path)
    }

    /// Writes the samples `range`, then `msgs`.
    fn write(&mut self, range: std::ops::Range<usize>, msgs: Vec<Outgoing>) -> Result<()> {
        let mut all: Vec<Outgoing> = Vec::with_capacity(range.len() + msgs.len());
        for k in range.clone() {
            let s = &self.imu[k];
            let t = stamp(s.time, "an IMU sample")?;
            let body = messages::imu(self.encoding, k as u32, s, t, IMU_FRAME);
            all.push((self.imu_topic, t.nanos(), body));
        }
        all.extend(msgs);
        self.imu_next = range.end;
        self.sink.write(&self.path, all)
    }
}

/// The stamp of `t` s; a recording cannot hold times before 1970.
fn stamp(t: f64, what: &str) -> Result<Stamp> {
    match Stamp::of(t) {
        Some(s) => Ok(s),
        None => bail!("{what} at {t} s cannot be a ROS stamp (0 to 2^32 s); use --start-time"),
    }
}
