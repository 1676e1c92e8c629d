//! A sensor's packets as its ROS driver records them (`simulate --messages packets`): the same
//! packets a pcap of the drive holds, stamped with the times it holds them at
//! ([`capture_ns`]), so that a reader decodes the same frames from either.
//!
//! - VLP-16, VLP-32C, HDL-64E S2 and S3, VLS-128: a `velodyne_msgs/VelodyneScan` a sweep on
//!   `/velodyne_packets`;
//! - the Hesai models (XT16, XT32, XT32M, Pandar40P, Pandar64, QT64, QT128, OT128, AT128): a
//!   `pandar_msgs/PandarScan` a sweep on `/pandar_packets` (nebula's);
//! - OS1-64: a `PacketMsg` a packet on `/ouster/lidar_packets` and `/ouster/imu_packets`, and
//!   the metadata JSON on `/ouster/metadata` first (ouster-ros');
//! - RS-Helios: a `robosense_msgs/RobosenseScan` a sweep on `/robosense_packets`, its DIFOP
//!   packet (with the model's name) on `/robosense_info_packets` first (nebula's; MCAP and db3
//!   only);
//! - Mid-360, Avia: a `nebula_msgs/NebulaPackets` a frame on `/nebula_packets`, the Mid-360's
//!   IMU packets among them in sending order (no ROS 1 type: MCAP and db3 only).
//!
//! A scan message is received when its last packet was.

use super::drivers::{self, Stamped};
use super::{Container, Outgoing, RosWriter, Topic};
use crate::capture::{capture_ns, clock_start, PacketSink};
use crate::packets::{Packet, PacketSensor};
use anyhow::{bail, Result};
use std::path::Path;

/// How the sensor's driver records its packets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Driver {
    Velodyne,
    Pandar,
    Ouster,
    Robosense,
    Nebula,
}

impl Driver {
    /// The driver that records `sensor`'s packets here, if one does.
    fn of(sensor: PacketSensor) -> Option<Self> {
        Some(match sensor {
            PacketSensor::Vlp16
            | PacketSensor::Vlp32c
            | PacketSensor::Vlp32ab
            | PacketSensor::Hdl64e
            | PacketSensor::Hdl64eS2
            | PacketSensor::Vls128 => Self::Velodyne,
            PacketSensor::Xt32
            | PacketSensor::Qt128
            | PacketSensor::Ot128
            | PacketSensor::Xt16
            | PacketSensor::Xt32m
            | PacketSensor::Pandar40p
            | PacketSensor::Pandar64
            | PacketSensor::Qt64
            | PacketSensor::At128 => Self::Pandar,
            PacketSensor::Os1 => Self::Ouster,
            PacketSensor::Helios => Self::Robosense,
            PacketSensor::Mid360 | PacketSensor::Avia => Self::Nebula,
            // nebula records the Helios' packets with its model's name; these are not written.
            PacketSensor::Rs16
            | PacketSensor::Rs32
            | PacketSensor::Bpearl
            | PacketSensor::Helios16p
            | PacketSensor::Ruby
            | PacketSensor::Airy
            | PacketSensor::M1
            | PacketSensor::E1r => return None,
        })
    }

    fn topics(self) -> &'static [Topic] {
        match self {
            Self::Velodyne => &[drivers::VELODYNE],
            Self::Pandar => &[drivers::PANDAR],
            Self::Ouster => &[
                drivers::OUSTER_LIDAR,
                drivers::OUSTER_IMU,
                drivers::OUSTER_META,
            ],
            Self::Robosense => &[drivers::ROBOSENSE, drivers::ROBOSENSE_INFO],
            Self::Nebula => &[drivers::NEBULA],
        }
    }
}

/// A recording of packets being written, sweep by sweep.
pub struct PacketBag {
    writer: RosWriter,
    driver: Driver,
    clock_start: f64,
    /// This sweep's packets: capture time (ns), payload.
    scan: Vec<(u64, Vec<u8>)>,
    /// This sweep's Ouster messages.
    messages: Vec<Outgoing>,
}

impl PacketBag {
    /// Creates `path` as `container` for `sensor`'s packets; `meta`, an Ouster's metadata JSON;
    /// `start_time` the sequence time of trajectory time 0.
    pub fn create(
        path: &Path,
        container: Container,
        sensor: PacketSensor,
        start_time: f64,
        meta: Option<String>,
    ) -> Result<Self> {
        let Some(driver) = Driver::of(sensor) else {
            bail!(
                "--messages packets: the {sensor:?}'s packets are not written as a driver's \
                 messages (of the Robosense models, nebula's RS-Helios only); write them as a \
                 pcap (--format pcap)"
            );
        };
        let mut writer = RosWriter::create(path, container, driver.topics(), Vec::new())?;
        let clock_start = clock_start(sensor, start_time);
        if let Some(json) = meta.filter(|_| driver == Driver::Ouster) {
            let body = drivers::text(writer.encoding(), &json);
            writer.write_after_imu(0, vec![(2, capture_ns(clock_start, 0.0), body)])?;
        }
        Ok(Self {
            writer,
            driver,
            clock_start,
            scan: Vec::new(),
            messages: Vec::new(),
        })
    }

    fn add(&mut self, packet: &Packet, topic: usize) {
        let ns = capture_ns(self.clock_start, packet.offset);
        match self.driver {
            Driver::Ouster => {
                let body = drivers::ouster_packet(self.writer.encoding(), &packet.payload);
                self.messages.push((topic, ns, body));
            }
            _ => self.scan.push((ns, packet.payload.clone())),
        }
    }
}

impl PacketSink for PacketBag {
    fn write(&mut self, packet: &Packet) -> Result<()> {
        self.add(packet, 0);
        Ok(())
    }

    fn write_imu(&mut self, packet: &Packet) -> Result<()> {
        self.add(packet, 1);
        Ok(())
    }

    /// A Robosense's DIFOP packet, as nebula records it with the model's name.
    fn write_device(&mut self, packet: &Packet) -> Result<()> {
        let ns = capture_ns(self.clock_start, packet.offset);
        let body = drivers::robosense_info(self.writer.encoding(), "Helios", (ns, &packet.payload));
        self.messages.push((1, ns, body));
        Ok(())
    }

    fn end_sweep(&mut self) -> Result<()> {
        let mut out = std::mem::take(&mut self.messages);
        if let Some(&(last, _)) = self.scan.last() {
            let packets: Vec<Stamped<'_>> = self.scan.iter().map(|(t, p)| (*t, &p[..])).collect();
            let enc = self.writer.encoding();
            let body = match self.driver {
                Driver::Velodyne => drivers::velodyne_scan(enc, &packets),
                Driver::Pandar => drivers::pandar_scan(enc, &packets),
                Driver::Robosense => drivers::robosense_scan(enc, &packets),
                _ => drivers::nebula_packets(enc, &packets),
            };
            out.push((0, last, body));
        }
        self.scan.clear();
        match out.last() {
            Some(&(_, last, _)) => self.writer.write_after_imu(last, out),
            None => Ok(()),
        }
    }

    fn finish(mut self: Box<Self>) -> Result<()> {
        self.end_sweep()?;
        self.writer.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_robosense_model_nebula_records_is_written_as_messages() {
        let dir = tempfile::tempdir().unwrap();
        for sensor in PacketSensor::ROBOSENSE {
            let path = dir.path().join(format!("{sensor:?}.mcap"));
            let made = PacketBag::create(&path, Container::Mcap, sensor, 0.0, None);
            match (sensor, made) {
                (PacketSensor::Helios, made) => assert!(made.is_ok(), "{sensor:?}"),
                (_, Ok(_)) => panic!("{sensor:?}: written as messages no driver records"),
                (_, Err(e)) => assert!(e.to_string().contains("--format pcap"), "{e}"),
            }
        }
    }
}
