//! ROS 1 bags (format 2.0) carrying `sensor_msgs/PointCloud2`.
//!
//! The container (records, chunks, compression, index) is read by [`bag_records`], in place, also
//! when the bag is cut short or was never closed; the message body, in the ROS 1 wire format,
//! is parsed by [`message`](super::message) into a
//! [`PointCloud2`](super::pointcloud2::PointCloud2) view and decoded by [`pointcloud2`].
//! Frames are the messages of one topic in receive-time order (as `rosbag play` plays them),
//! whatever order they were written in; a bag written out of order says so in a dataset
//! warning. A chunk is decompressed when the stream reaches it, so a bag never has to fit in
//! memory, and [`FrameSource::seek`] is cheap. With `--imu`, the messages of its
//! `sensor_msgs/Imu` topic (`imu_topic`) are read when it is opened.

use super::bag_records;
use super::bag_records::{Bag, MessageRef};
use super::message::parse_ros1;
use super::pointcloud2::{self, MessageAt};
use super::{imu_msg, imu_topic};
use crate::dataset::{Dataset, DatasetInfo, Format, FrameSource, Item, OpenOptions};
use crate::imu::{attach::WithImu, ImuSample};
use anyhow::{anyhow, bail, Result};
use std::collections::HashMap;
use std::path::Path;

/// Connection type of the messages this reader decodes.
pub const POINTCLOUD2_TYPE: &str = "sensor_msgs/PointCloud2";

/// MD5 of the `sensor_msgs/PointCloud2` definition; a connection with this type name but another
/// sum was recorded from a different definition and cannot be parsed with this layout.
pub const POINTCLOUD2_MD5: &str = "1158d486dd51d683ce2f1be655c3c181";

/// Opens a ROS 1 bag and streams the PointCloud2 messages of `opts.topic`, or of the only
/// PointCloud2 topic in the bag, in receive-time order.
pub fn open(path: &Path, opts: &OpenOptions) -> Result<Dataset> {
    let label = path.display().to_string();
    let limit = pointcloud2::record_limit(opts.scan_points);
    let mut bag = Bag::open(path, limit).map_err(|e| anyhow!("{label}: {e}"))?;
    if bag.connections.is_empty() {
        if let Some(d) = &bag.damage {
            bail!("{label}: damaged before its first message: {d}");
        }
    }
    let topics: Vec<(String, String)> = bag
        .connections
        .values()
        .map(|c| (c.topic.clone(), c.tp.clone()))
        .collect();
    let topic = pointcloud2::choose_topic(
        &label,
        &topics,
        |t| t == POINTCLOUD2_TYPE,
        pointcloud2::Wanted::cloud(POINTCLOUD2_TYPE),
        opts.topic.as_deref(),
    )
    .map_err(|e| match &bag.damage {
        Some(d) => anyhow!("{e}; the bag is damaged: {d}"),
        None => anyhow!(e),
    })?;
    let imu_topic = imu_topic::choose(
        &label,
        &topics,
        |t| t == imu_msg::ROS1_TYPE,
        imu_msg::ROS1_TYPE,
        &opts.imu,
    )
    .map_err(|e| anyhow!(e))?;
    let ours: HashMap<u32, ConnKind> = bag
        .connections
        .iter()
        .filter(|(_, c)| c.topic == topic)
        .map(|(&id, c)| (id, ConnKind::of(c)))
        .collect();
    let mut plan: Vec<MessageRef> = bag
        .messages
        .iter()
        .filter(|m| ours.contains_key(&m.conn))
        .copied()
        .collect();
    let mut warnings = Vec::new();
    if !bag.indexed {
        warnings.push(format!(
            "{label}: bag has no usable index (cut short or not closed); its chunks were found \
             by scanning"
        ));
    }
    if let Some(w) = pointcloud2::time_order(&label, &topic, &mut plan, |m| m.time) {
        warnings.push(w);
    }
    let imu = imu_topic.map(|t| read_imu(&mut bag, &label, &t, &mut warnings));
    let source = BagSource {
        bag,
        file: label,
        topic,
        ours,
        plan,
        next: 0,
        max_points: opts.scan_points,
        done: false,
    };
    let mut frames: Box<dyn FrameSource> = Box::new(source);
    if let Some(samples) = imu {
        frames = Box::new(WithImu::new(frames, samples));
    }
    Ok(Dataset {
        frames,
        info: DatasetInfo {
            format: Some(Format::Bag),
            warnings,
            ..DatasetInfo::default()
        },
    })
}

/// The samples of the `sensor_msgs/Imu` messages on `topic`, read in file order, in stamp
/// order; what went wrong goes to `warnings`.
fn read_imu(bag: &mut Bag, file: &str, topic: &str, warnings: &mut Vec<String>) -> Vec<ImuSample> {
    let usable: HashMap<u32, Option<String>> = bag
        .connections
        .iter()
        .filter(|(_, c)| c.topic == topic)
        .map(|(&id, c)| {
            let wrong = (c.tp != imu_msg::ROS1_TYPE || c.md5 != imu_msg::ROS1_MD5)
                .then(|| format!("{} with md5 {}", c.tp, c.md5));
            (id, wrong)
        })
        .collect();
    let mut refs: Vec<MessageRef> = bag
        .messages
        .iter()
        .filter(|m| usable.contains_key(&m.conn))
        .copied()
        .collect();
    refs.sort_by_key(|m| m.time);
    // Numbered in receive order, read chunk by chunk.
    let mut order: Vec<(usize, MessageRef)> = refs.into_iter().enumerate().collect();
    order.sort_by_key(|(_, m)| (m.chunk, m.offset));
    let mut collected = imu_topic::Collector::new(file, topic);
    for (index, m) in order {
        if let Some(Some(wrong)) = usable.get(&m.conn) {
            collected.refuse(index, wrong);
            continue;
        }
        match bag.message(m) {
            Ok(body) => collected.push(index, imu_msg::parse_ros1(body)),
            Err(e) => {
                collected.stop(index, &e);
                break;
            }
        }
    }
    collected.finish(warnings)
}

/// Whether messages of a connection on the chosen topic can be decoded.
#[derive(Clone, Debug)]
enum ConnKind {
    Cloud,
    /// Another type (or another definition) published on the same topic.
    Wrong(String),
}

impl ConnKind {
    fn of(c: &bag_records::Connection) -> Self {
        if c.tp != POINTCLOUD2_TYPE {
            ConnKind::Wrong(c.tp.clone())
        } else if c.md5 != POINTCLOUD2_MD5 {
            ConnKind::Wrong(format!(
                "{} with md5 {} (expected {POINTCLOUD2_MD5})",
                c.tp, c.md5
            ))
        } else {
            ConnKind::Cloud
        }
    }
}

/// The frames of one topic of an open bag.
struct BagSource {
    bag: Bag,
    file: String,
    topic: String,
    /// Connections on the chosen topic.
    ours: HashMap<u32, ConnKind>,
    /// The messages of `ours`, in receive-time order.
    plan: Vec<MessageRef>,
    next: usize,
    max_points: usize,
    done: bool,
}

impl FrameSource for BagSource {
    fn len_hint(&self) -> Option<usize> {
        Some(self.plan.len())
    }

    fn next_item(&mut self) -> Result<Option<Item>> {
        if self.done {
            return Ok(None);
        }
        let Some(&m) = self.plan.get(self.next) else {
            self.done = true;
            return match &self.bag.damage {
                Some(d) => bail!("{}: {d}", self.file),
                None => Ok(None),
            };
        };
        let index = self.next;
        self.next += 1;
        if let Some(ConnKind::Wrong(tp)) = self.ours.get(&m.conn) {
            self.done = true;
            bail!(
                "{}: message {index} on {} is {tp}, not {POINTCLOUD2_TYPE}",
                self.file,
                self.topic
            );
        }
        let at = MessageAt {
            index,
            file: &self.file,
            topic: &self.topic,
            received: m.time,
        };
        let body = match self.bag.message(m) {
            Ok(body) => body,
            Err(e) => {
                self.done = true;
                bail!("{}: {e}", self.file);
            }
        };
        Ok(Some(pointcloud2::message_item(
            at,
            parse_ros1(body),
            self.max_points,
        )))
    }

    fn seek(&mut self, index: usize) -> bool {
        self.next = index.min(self.plan.len());
        self.done = false;
        true
    }
}

#[cfg(test)]
mod tests;
