//! ROS 1 bags (format 2.0) as a [`Recording`]: `sensor_msgs/PointCloud2`, sensor packets,
//! Livox points and IMU samples, read by [`frames`].
//!
//! The container (records, chunks, compression, index) is read by [`bag_records`](super::bag_records), in place,
//! also when the bag is cut short or was never closed; the message bodies are in the ROS 1 wire
//! format. A topic's messages are streamed in receive-time order (as `rosbag play` plays
//! them), whatever order they were written in; a bag written out of order says so in a
//! dataset warning. A chunk is decompressed when the stream reaches it, so a bag never has to
//! fit in memory, and seeking is cheap.

use super::bag_records::{Bag, MessageRef};
use super::frames;
use super::pointcloud2;
use super::recording::{Message, MessageStream, Recording};
use crate::dataset::{Dataset, Format, OpenOptions};
use anyhow::{anyhow, bail, Result};
use std::collections::HashMap;
use std::ops::ControlFlow;
use std::path::Path;

/// Connection type of the messages this reader decodes.
pub const POINTCLOUD2_TYPE: &str = "sensor_msgs/PointCloud2";

/// MD5 of the `sensor_msgs/PointCloud2` definition; a connection with this type name but another
/// sum was recorded from a different definition and cannot be parsed with this layout.
pub const POINTCLOUD2_MD5: &str = "1158d486dd51d683ce2f1be655c3c181";

/// Opens a ROS 1 bag and streams the frames of `opts.topic`, or of the only PointCloud2 topic
/// (else the only topic of sensor packets or Livox points), in receive-time order.
pub fn open(path: &Path, opts: &OpenOptions) -> Result<Dataset> {
    let bag = BagRecording::open(path, pointcloud2::record_limit(opts.scan_points))?;
    frames::open(Box::new(bag), opts)
}

/// A connection on a topic asked for: the topic's place in the list, its type and MD5 sum.
type Conn = (usize, String, String);

/// A ROS 1 bag opened for reading.
pub struct BagRecording {
    bag: Bag,
    label: String,
    warnings: Vec<String>,
}

impl BagRecording {
    /// Opens the bag at `path`; chunks larger than `limit` bytes are refused.
    pub fn open(path: &Path, limit: u64) -> Result<Self> {
        let label = path.display().to_string();
        let bag = Bag::open(path, limit).map_err(|e| anyhow!("{label}: {e}"))?;
        if bag.connections.is_empty() {
            if let Some(d) = &bag.damage {
                bail!("{label}: damaged before its first message: {d}");
            }
        }
        let mut warnings = Vec::new();
        if !bag.indexed {
            warnings.push(format!(
                "{label}: bag has no usable index (cut short or not closed); its chunks were \
                 found by scanning"
            ));
        }
        Ok(Self {
            bag,
            label,
            warnings,
        })
    }

    /// Connection ids on `topics`: the topic's place in the list, the type and its MD5 sum.
    fn ours(&self, topics: &[String]) -> HashMap<u32, Conn> {
        self.bag
            .connections
            .iter()
            .filter_map(|(&id, c)| {
                let topic = topics.iter().position(|t| *t == c.topic)?;
                Some((id, (topic, c.tp.clone(), c.md5.clone())))
            })
            .collect()
    }
}

impl Recording for BagRecording {
    fn label(&self) -> &str {
        &self.label
    }

    fn format(&self) -> Format {
        Format::Bag
    }

    fn ros1(&self) -> bool {
        true
    }

    fn topics(&self) -> Vec<(String, String)> {
        let mut out: Vec<(String, String)> = (self.bag.connections.values())
            .map(|c| (c.topic.clone(), c.tp.clone()))
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    fn count(&self, topic: &str) -> Option<usize> {
        let ours = self.ours(&[topic.to_string()]);
        Some(
            self.bag
                .messages
                .iter()
                .filter(|m| ours.contains_key(&m.conn))
                .count(),
        )
    }

    fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }

    fn damage(&self) -> Option<String> {
        self.bag.damage.clone()
    }

    fn scan(
        &mut self,
        topics: &[String],
        f: &mut dyn FnMut(Message<'_>) -> ControlFlow<()>,
    ) -> Result<()> {
        let ours = self.ours(topics);
        let refs: Vec<MessageRef> = (self.bag.messages.iter())
            .filter(|m| ours.contains_key(&m.conn))
            .copied()
            .collect();
        for m in refs {
            let (topic, tp, md5) = &ours[&m.conn];
            let body = self
                .bag
                .message(m)
                .map_err(|e| anyhow!("{}: {e}", self.label))?;
            let message = Message {
                topic: *topic,
                time_ns: m.time,
                data: body,
                tp,
                md5: Some(md5),
                warning: None,
            };
            if f(message).is_break() {
                return Ok(());
            }
        }
        match &self.bag.damage {
            Some(d) => bail!("{}: {d}", self.label),
            None => Ok(()),
        }
    }

    fn stream(self: Box<Self>, topics: &[String]) -> Result<Box<dyn MessageStream>> {
        let ours = self.ours(topics);
        let mut plan: Vec<MessageRef> = (self.bag.messages.iter())
            .filter(|m| ours.contains_key(&m.conn))
            .copied()
            .collect();
        let names = topics.join(", ");
        let order = pointcloud2::time_order(&self.label, &names, &mut plan, |m| m.time);
        Ok(Box::new(BagStream {
            bag: self.bag,
            file: self.label,
            ours,
            plan,
            next: 0,
            warnings: order.into_iter().collect(),
        }))
    }
}

/// The messages of some topics of an open bag, in receive-time order.
struct BagStream {
    bag: Bag,
    file: String,
    /// Connections on the topics asked for.
    ours: HashMap<u32, Conn>,
    plan: Vec<MessageRef>,
    next: usize,
    warnings: Vec<String>,
}

impl MessageStream for BagStream {
    fn len_hint(&self) -> Option<usize> {
        Some(self.plan.len())
    }

    fn next_message(&mut self) -> Result<Option<Message<'_>>> {
        let Some(&m) = self.plan.get(self.next) else {
            return match &self.bag.damage {
                Some(d) => bail!("{}: {d}", self.file),
                None => Ok(None),
            };
        };
        self.next += 1;
        let (topic, tp, md5) = &self.ours[&m.conn];
        let body = match self.bag.message(m) {
            Ok(body) => body,
            Err(e) => bail!("{}: {e}", self.file),
        };
        Ok(Some(Message {
            topic: *topic,
            time_ns: m.time,
            data: body,
            tp,
            md5: Some(md5),
            warning: None,
        }))
    }

    fn seek(&mut self, k: usize) -> bool {
        self.next = k.min(self.plan.len());
        true
    }

    fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }
}

#[cfg(test)]
mod tests;
