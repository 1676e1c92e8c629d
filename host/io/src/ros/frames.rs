//! What a ROS recording's messages become, the same for a ROS 1 bag, an MCAP file and a ROS 2
//! sqlite3 bag: the topic `--topic` names, or else the only `sensor_msgs/PointCloud2` topic, or
//! else the only topic of sensor packets or Livox points, gives the frames:
//!
//! - PointCloud2 messages are frames one for one ([`pointcloud2`], parsed by
//!   [`message`](super::message));
//! - packet messages (VelodyneScan, PandarScan, NebulaPackets, Ouster's PacketMsg) are
//!   decoded into sweeps as a pcap of the same packets is ([`packet_frames`](super::packet_frames));
//! - Livox `CustomMsg` messages are frames one or several at a time ([`livox`](super::livox)).
//!
//! With `--imu`, the samples of its `sensor_msgs/Imu` topic are read first, in one pass, and
//! handed on with the frames (`imu_topic`).

use super::imu_msg;
use super::imu_topic;
use super::kinds::Kind;
use super::message::{parse_cdr, parse_ros1};
use super::pointcloud2::{self, choose_topic, wanted_topics, MessageAt, Wanted};
use super::recording::{MessageStream, Recording};
use crate::dataset::{Dataset, DatasetInfo, FrameSource, Item, OpenOptions};
use crate::imu::{attach::WithImu, ImuSample};
use anyhow::{anyhow, bail, Result};
use std::ops::ControlFlow;

/// Opens the frames of `rec` that `opts` asks for (see the module doc).
pub fn open(mut rec: Box<dyn Recording>, opts: &OpenOptions) -> Result<Dataset> {
    let label = rec.label().to_string();
    let ros1 = rec.ros1();
    let topics = rec.topics();
    let (topic, kind) =
        choose(&label, ros1, &topics, opts.topic.as_deref()).map_err(|e| match rec.damage() {
            Some(d) => anyhow!("{e}; the file is damaged: {d}"),
            None => anyhow!(e),
        })?;
    let imu_type = Kind::Imu.type_name(ros1);
    let is_imu = |t: &str| Kind::of(t) == Some(Kind::Imu);
    let imu_topic =
        imu_topic::choose(&label, &topics, is_imu, &imu_type, &opts.imu).map_err(|e| anyhow!(e))?;
    let mut warnings = rec.take_warnings();
    let imu = imu_topic.map(|t| read_imu(rec.as_mut(), &t, &mut warnings));
    let format = rec.format();
    let mut frames: Box<dyn FrameSource> = match kind {
        Kind::Cloud => {
            let total = rec.count(&topic);
            let mut stream = rec.stream(std::slice::from_ref(&topic))?;
            warnings.extend(stream.take_warnings());
            Box::new(CloudFrames {
                stream,
                file: label,
                topic,
                ros1,
                total,
                index: 0,
                max_points: opts.scan_points,
                done: false,
            })
        }
        Kind::LivoxCustom => super::livox::open(rec, &topic, opts, &mut warnings)?,
        _ => super::packet_frames::open(rec, &topic, kind, opts, &mut warnings)?,
    };
    if let Some(samples) = imu {
        frames = Box::new(WithImu::new(frames, samples));
    }
    Ok(Dataset {
        frames,
        info: DatasetInfo {
            format: Some(format),
            warnings,
            ..DatasetInfo::default()
        },
    })
}

/// The frame topic and its kind (see the module doc); errors name the file and list the
/// candidates.
fn choose(
    file: &str,
    ros1: bool,
    topics: &[(String, String)],
    requested: Option<&str>,
) -> Result<(String, Kind), String> {
    let cloud_type = Kind::Cloud.type_name(ros1);
    let is_cloud = |t: &str| Kind::of(t) == Some(Kind::Cloud);
    let wanted = Wanted::cloud(&cloud_type);
    if let Some(t) = requested {
        let kind = topics
            .iter()
            .filter(|(name, _)| name == t)
            .find_map(|(_, tp)| Kind::of(tp).filter(|k| k.is_frames()));
        return match kind {
            Some(k) => Ok((t.to_string(), k)),
            None => choose_topic(file, topics, is_cloud, wanted, Some(t)).map(|t| (t, Kind::Cloud)),
        };
    }
    if !wanted_topics(topics, is_cloud).is_empty() {
        return choose_topic(file, topics, is_cloud, wanted, None).map(|t| (t, Kind::Cloud));
    }
    let mut sensors: Vec<(&str, &str, Kind)> = topics
        .iter()
        .filter_map(|(name, tp)| {
            let kind = Kind::of(tp).filter(|k| k.is_frames())?;
            let imu_packets = kind == Kind::OusterPacket && name.contains("imu");
            (!imu_packets).then_some((name.as_str(), tp.as_str(), kind))
        })
        .collect();
    sensors.sort_unstable_by_key(|s| s.0);
    sensors.dedup_by_key(|s| s.0);
    match sensors.as_slice() {
        [(name, _, kind)] => Ok((name.to_string(), *kind)),
        [] => {
            let mut all: Vec<String> = topics.iter().map(|(t, ty)| format!("{t} ({ty})")).collect();
            all.sort_unstable();
            all.dedup();
            Err(format!(
                "{file}: no {cloud_type} topic, nor sensor packets or Livox points (topics: {})",
                if all.is_empty() {
                    "none".to_string()
                } else {
                    all.join(", ")
                }
            ))
        }
        several => {
            let list: Vec<String> = several
                .iter()
                .map(|(n, t, _)| format!("{n} ({t})"))
                .collect();
            Err(format!(
                "{file}: several topics of sensor data ({}); choose one with --topic",
                list.join(", ")
            ))
        }
    }
}

/// The samples of the `sensor_msgs/Imu` messages on `topic`, in stamp order; what went wrong
/// goes to `warnings`.
fn read_imu(rec: &mut dyn Recording, topic: &str, warnings: &mut Vec<String>) -> Vec<ImuSample> {
    let (label, ros1) = (rec.label().to_string(), rec.ros1());
    let mut collected = imu_topic::Collector::new(&label, topic);
    let mut index = 0;
    let scanned = rec.scan(&[topic.to_string()], &mut |m| {
        match Kind::of_message(ros1, &m) {
            Ok(Kind::Imu) if ros1 => collected.push(index, imu_msg::parse_ros1(m.data)),
            Ok(Kind::Imu) => collected.push(index, imu_msg::parse_cdr(m.data)),
            Ok(_) => collected.refuse(index, &m.tp),
            Err(what) => collected.refuse(index, &what),
        }
        index += 1;
        ControlFlow::Continue(())
    });
    if let Err(e) = scanned {
        collected.stop(index, &e);
    }
    collected.finish(warnings)
}

/// The PointCloud2 messages of one topic as frames.
struct CloudFrames {
    stream: Box<dyn MessageStream>,
    file: String,
    topic: String,
    ros1: bool,
    total: Option<usize>,
    /// The next message's place in receive order: its frame's identity.
    index: usize,
    max_points: usize,
    done: bool,
}

impl FrameSource for CloudFrames {
    fn len_hint(&self) -> Option<usize> {
        self.stream.len_hint().or(self.total)
    }

    fn next_item(&mut self) -> Result<Option<Item>> {
        if self.done {
            return Ok(None);
        }
        let (file, topic, index) = (&self.file, &self.topic, self.index);
        let m = match self.stream.next_message() {
            Ok(Some(m)) => m,
            other => {
                self.done = true;
                return other.map(|_| None);
            }
        };
        let cloud_type = Kind::Cloud.type_name(self.ros1);
        match Kind::of_message(self.ros1, &m) {
            Ok(Kind::Cloud) => {}
            Ok(_) => {
                self.done = true;
                bail!(
                    "{file}: message {index} on {topic} is {}, not {cloud_type}",
                    m.tp
                );
            }
            Err(what) => {
                self.done = true;
                bail!("{file}: message {index} on {topic} is {what}, not {cloud_type}");
            }
        }
        let at = MessageAt {
            index,
            file,
            topic,
            received: m.time_ns,
        };
        let parsed = if self.ros1 {
            parse_ros1(m.data)
        } else {
            parse_cdr(m.data)
        };
        let mut item = pointcloud2::message_item(at, parsed, self.max_points);
        if let (Item::Frame(f), Some(w)) = (&mut item, m.warning) {
            f.warnings.push(w);
        }
        self.index += 1;
        Ok(Some(item))
    }

    fn seek(&mut self, index: usize) -> bool {
        if !self.stream.seek(index) {
            return false;
        }
        self.index = index;
        self.done = false;
        true
    }
}
