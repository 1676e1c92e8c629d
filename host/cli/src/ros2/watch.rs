//! What a caller in the same process can see of a running node ([`super::node::run`]): how
//! many remote endpoints each of its readers and writers has matched, and how many IMU
//! messages it has taken.
//!
//! DDS matches the two ends of a topic separately, each once its own participant has processed
//! the other's announcement, so a publisher can see the node before the node sees it. A reader
//! drops what a writer it has not matched yet sends, and a writer sends nothing to a reader it
//! has not matched: a publisher that must lose nothing (a test above all) starts once the
//! node's side has matched it too.

use super::dds::{CloudReader, Writer};
use rustdds::{DataReaderStatus, DataWriterStatus, StatusEvented};
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// The node's matches and IMU messages so far, updated while it runs.
#[derive(Debug, Default)]
pub struct Watch {
    matched: Mutex<BTreeMap<String, usize>>,
    imu_messages: AtomicU64,
}

impl Watch {
    /// Remote endpoints matched on ROS 2 topic `topic`: the publishers of a topic the node
    /// reads, the subscribers of one it publishes.
    pub fn matched(&self, topic: &str) -> usize {
        let m = self.matched.lock().unwrap_or_else(|e| e.into_inner());
        m.get(topic).copied().unwrap_or(0)
    }

    /// IMU messages the node has taken from DDS (the summary's IMU `received`).
    pub fn imu_messages(&self) -> u64 {
        self.imu_messages.load(Ordering::SeqCst)
    }

    pub(super) fn took_imu_message(&self) {
        self.imu_messages.fetch_add(1, Ordering::SeqCst);
    }

    fn set(&self, topic: &str, n: i32) {
        let mut m = self.matched.lock().unwrap_or_else(|e| e.into_inner());
        m.insert(topic.to_string(), usize::try_from(n).unwrap_or(0));
    }

    /// Takes `r`'s status events: the publishers matched on its `topic`.
    pub(super) fn reader(&self, topic: &str, r: &CloudReader) {
        while let Some(status) = r.try_recv_status() {
            if let DataReaderStatus::SubscriptionMatched { current, .. } = status {
                self.set(topic, current.count());
            }
        }
    }

    /// Takes `w`'s status events: the subscribers matched on its `topic`.
    pub(super) fn writer<D: Serialize>(&self, topic: &str, w: &Writer<D>) {
        while let Some(status) = w.try_recv_status() {
            if let DataWriterStatus::PublicationMatched { current, .. } = status {
                self.set(topic, current.count());
            }
        }
    }
}
