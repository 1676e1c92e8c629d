//! The DDS side shared by the node and the player: a participant that discovers peers over
//! loopback only, the QoS profiles ROS 2 uses, and typed readers and writers on ROS 2 topics.
//!
//! Discovery: many machines (containers, this one) have no multicast on loopback, and
//! multicast on a real interface would leave the machine. The participant is therefore
//! restricted to 127.0.0.1 and announces itself (SPDP) by unicast to the well-known ports of
//! participants 0.. on localhost; Cyclone DDS (and so `rmw_cyclonedds`) does the same with
//! `AllowMulticast=false` and a `127.0.0.1` peer, Fast DDS with a localhost initial peer.

use super::msg::{dds_topic, RawAdapter, RawCloud};
use anyhow::{anyhow, Result};
use rustdds::no_key::{DataReader, DataWriter};
use rustdds::policy::{Durability, History, Reliability};
use rustdds::serialization::{CDRDeserializerAdapter, CDRSerializerAdapter};
pub use rustdds::DomainParticipant;
use rustdds::{
    DataReaderStatus, DataWriterStatus, DomainParticipantBuilder, QosPolicies, QosPolicyBuilder,
    StatusEvented, TopicKind,
};
use serde::Serialize;
use std::net::{IpAddr, Ipv4Addr};
use std::time::{Duration, Instant};

/// A writer of `D` in CDR little endian, as `rmw` writes.
pub type Writer<D> = DataWriter<D, CDRSerializerAdapter<D>>;

/// A reader of `D` in CDR.
pub(crate) type Reader<D> = DataReader<D, CDRDeserializerAdapter<D>>;

/// A reader of serialized messages (clouds, IMU samples).
pub type CloudReader = DataReader<RawCloud, RawAdapter>;

/// The ROS domain: `ROS_DOMAIN_ID` if set and valid, else 0.
pub(crate) fn default_domain() -> u16 {
    std::env::var("ROS_DOMAIN_ID")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .filter(|d| *d <= 232)
        .unwrap_or(0)
}

/// A participant in `domain` that talks over loopback only (see the module doc).
pub fn participant(domain: u16) -> Result<DomainParticipant> {
    if domain > 232 {
        return Err(anyhow!("domain {domain}: ROS 2 domains are 0..=232"));
    }
    DomainParticipantBuilder::new(domain)
        .with_only_networks([IpAddr::V4(Ipv4Addr::LOCALHOST)])
        .same_host_loopback(true)
        .build()
        .map_err(|e| anyhow!("cannot start a DDS participant in domain {domain}: {e:?}"))
}

/// `rclcpp::SensorDataQoS`: best effort, keep last 5, volatile.
pub fn sensor_qos() -> QosPolicies {
    QosPolicyBuilder::new()
        .reliability(Reliability::BestEffort)
        .history(History::KeepLast { depth: 5 })
        .durability(Durability::Volatile)
        .build()
}

/// Reliable, keep last `depth`, volatile (`rclcpp::QoS(depth)`, what `/tf` and odometry use).
pub(crate) fn reliable_qos(depth: i32) -> QosPolicies {
    QosPolicyBuilder::new()
        .reliability(Reliability::Reliable {
            max_blocking_time: rustdds::Duration::from_millis(100),
        })
        .history(History::KeepLast { depth })
        .durability(Durability::Volatile)
        .build()
}

/// A writer of `D` on ROS 2 topic `name` with DDS type `type_name`.
pub fn writer<D: Serialize>(
    dp: &DomainParticipant,
    name: &str,
    type_name: &str,
    qos: &QosPolicies,
) -> Result<Writer<D>> {
    let topic = dp
        .create_topic(dds_topic(name), type_name.into(), qos, TopicKind::NoKey)
        .map_err(|e| anyhow!("topic {name}: {e:?}"))?;
    let publisher = dp
        .create_publisher(qos)
        .map_err(|e| anyhow!("publisher for {name}: {e:?}"))?;
    publisher
        .create_datawriter_no_key_cdr::<D>(&topic, Some(qos.clone()))
        .map_err(|e| anyhow!("writer on {name}: {e:?}"))
}

/// A reader of `D` (CDR) on ROS 2 topic `name` with DDS type `type_name`.
pub(crate) fn reader<D: serde::de::DeserializeOwned + 'static>(
    dp: &DomainParticipant,
    name: &str,
    type_name: &str,
    qos: &QosPolicies,
) -> Result<Reader<D>> {
    let topic = dp
        .create_topic(dds_topic(name), type_name.into(), qos, TopicKind::NoKey)
        .map_err(|e| anyhow!("topic {name}: {e:?}"))?;
    let subscriber = dp
        .create_subscriber(qos)
        .map_err(|e| anyhow!("subscriber for {name}: {e:?}"))?;
    subscriber
        .create_datareader_no_key_cdr::<D>(&topic, Some(qos.clone()))
        .map_err(|e| anyhow!("reader on {name}: {e:?}"))
}

/// Waits until `r` has a matched writer, `stop` says stop, or `timeout` passes; returns whether
/// a writer matched.
pub(crate) fn wait_for_writer<D: serde::de::DeserializeOwned + 'static>(
    r: &Reader<D>,
    timeout: Duration,
    stop: &dyn Fn() -> bool,
) -> bool {
    let start = Instant::now();
    while start.elapsed() < timeout && !stop() {
        while let Some(status) = r.try_recv_status() {
            if let DataReaderStatus::SubscriptionMatched { current, .. } = status {
                if current.count() > 0 {
                    return true;
                }
            }
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    false
}

/// A reader of `sensor_msgs/msg/PointCloud2` on ROS 2 topic `name`, sensor-data QoS.
pub fn cloud_reader(dp: &DomainParticipant, name: &str) -> Result<CloudReader> {
    raw_reader(dp, name, super::msg::POINTCLOUD2_TYPE, sensor_qos())
}

/// How many IMU messages the DDS reader keeps between two drains: a burst of 100 ms at 1 kHz.
/// Best effort and volatile as [`sensor_qos`], so it matches any sensor publisher; only the
/// local history is deeper, since IMU messages come many to a cloud.
pub(crate) const IMU_HISTORY: i32 = 100;

/// Sensor-data QoS with a history of [`IMU_HISTORY`]: the IMU reader's and the player's.
pub(crate) fn imu_qos() -> QosPolicies {
    QosPolicyBuilder::new()
        .reliability(Reliability::BestEffort)
        .history(History::KeepLast { depth: IMU_HISTORY })
        .durability(Durability::Volatile)
        .build()
}

/// A reader of serialized `sensor_msgs/msg/Imu` on ROS 2 topic `name`, [`imu_qos`].
pub(crate) fn imu_reader(dp: &DomainParticipant, name: &str) -> Result<CloudReader> {
    raw_reader(dp, name, super::msg::IMU_TYPE, imu_qos())
}

/// A reader of serialized messages of DDS type `type_name` on ROS 2 topic `name`.
fn raw_reader(
    dp: &DomainParticipant,
    name: &str,
    type_name: &str,
    qos: QosPolicies,
) -> Result<CloudReader> {
    let topic = dp
        .create_topic(dds_topic(name), type_name.into(), &qos, TopicKind::NoKey)
        .map_err(|e| anyhow!("topic {name}: {e:?}"))?;
    let subscriber = dp
        .create_subscriber(&qos)
        .map_err(|e| anyhow!("subscriber for {name}: {e:?}"))?;
    subscriber
        .create_datareader_no_key::<RawCloud, RawAdapter>(&topic, Some(qos))
        .map_err(|e| anyhow!("reader on {name}: {e:?}"))
}

/// Waits until `w` has a matched reader, `stop` says stop, or `timeout` passes; returns whether
/// a reader matched.
pub fn wait_for_reader<D: Serialize>(
    w: &Writer<D>,
    timeout: Duration,
    stop: &dyn Fn() -> bool,
) -> bool {
    let start = Instant::now();
    while start.elapsed() < timeout && !stop() {
        while let Some(status) = w.try_recv_status() {
            if let DataWriterStatus::PublicationMatched { current, .. } = status {
                if current.count() > 0 {
                    return true;
                }
            }
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    false
}
