//! Sensor packets recorded in a ROS recording, decoded as a pcap of the same packets is: the
//! packet messages ([`packets`]) become the UDP datagrams a capture of the
//! sensor would hold, on the ports the sensor sends to, timed by the driver's stamps (the
//! message's receive time where a packet has none), and go through the same decoders, sweep
//! assembly and options (`--sensor`, `--calibration`, `input.cut_angle`) as a pcap ([`sweeps`],
//! [`SweepFrames`]), so a bag of packets and a pcap of the same packets give the same frames.
//!
//! An Ouster's IMU packets come from the topic beside its lidar packets' (`.../imu_packets`),
//! its metadata from the `std_msgs/String` topic ouster-ros records it on (`.../metadata`)
//! unless `--calibration` gives a file. A Robosense's DIFOP packets (the lasers' angles) and its
//! model's name come from nebula's `.../robosense_info_packets` beside its MSOP packets, unless
//! `--calibration` and `--sensor` say. `NebulaPackets` carry any sensor's packets: each goes to
//! the port its sensor sends that packet to (a Livox Mid-360's IMU packets to their own). A
//! message that does not parse is skipped, counted and named in one warning when the stream
//! ends.

use super::kinds::Kind;
use super::packets::{self, Packet};
use super::recording::{MessageStream, Recording};
use crate::capture::frames::SweepFrames;
use crate::capture::ouster_meta;
use crate::capture::pcap::{Datagram, Record};
use crate::capture::robosense_calib::{DIFOP_PORT, MSOP_PORT};
use crate::capture::sweeps::{self, Beside, DatagramSource, Survey, LIVOX2_PORT, LIVOX_PORT};
use crate::capture::sweeps::{OUSTER_IMU_PORT, OUSTER_PORT, VELODYNE_PORT};
use crate::dataset::{FrameSource, OpenOptions, SensorKind};
use anyhow::{anyhow, bail, Result};
use kiss_odom_sensors::livox;
use std::collections::VecDeque;
use std::net::{Ipv4Addr, SocketAddr};
use std::ops::ControlFlow;
use std::path::Path;

/// The Mid-360's IMU port on the host (Livox's default).
pub const LIVOX2_IMU_PORT: u16 = 56401;

/// Opens the packets on `topic` (of `kind`) of `rec` as frames.
pub fn open(
    mut rec: Box<dyn Recording>,
    topic: &str,
    kind: Kind,
    opts: &OpenOptions,
    warnings: &mut Vec<String>,
) -> Result<Box<dyn FrameSource>> {
    let label = rec.label().to_string();
    let ros1 = rec.ros1();
    let all = rec.topics();
    let mut topics = vec![topic.to_string()];
    let mut kinds = vec![kind];
    let mut beside = Beside::default();
    let mut sensor = opts.sensor.clone();
    let mut ports = Ports {
        lidar: opts.sensor.port,
        imu: None,
    };
    if kind == Kind::OusterPacket {
        if let Some(imu) = sibling(&all, topic, "imu_packets", Kind::OusterPacket) {
            topics.push(imu);
            kinds.push(Kind::OusterPacket);
        }
        if opts.sensor.meta.is_none() {
            let meta = sibling(&all, topic, "metadata", Kind::Text).or_else(|| only_metadata(&all));
            let Some(meta) = meta else {
                bail!(
                    "{label}: Ouster packets on {topic} and no metadata topic beside them: give \
                     the sensor's metadata JSON (--calibration)"
                );
            };
            let (parsed, where_) = read_metadata(rec.as_mut(), &meta)?;
            ports.lidar = ports.lidar.or(parsed.udp_port_lidar);
            ports.imu = parsed.udp_port_imu;
            beside.ouster_meta = Some((parsed, where_));
        } else if let Some(file) = &opts.sensor.meta {
            let parsed = ouster_meta::read(file)?;
            ports.lidar = ports.lidar.or(parsed.udp_port_lidar);
            ports.imu = parsed.udp_port_imu;
        }
    }
    if kind == Kind::RobosenseScan {
        let info = sibling(&all, topic, "robosense_info_packets", Kind::RobosenseInfo);
        if let Some(info) = info {
            let (model, difop, where_) = read_robosense_info(rec.as_mut(), &info)?;
            if sensor.sensor == SensorKind::Auto {
                sensor.sensor = robosense_kind(&model).ok_or_else(|| {
                    anyhow!("{where_}: lidar_model {model:?} is not a model read: name it with --sensor")
                })?;
            }
            beside.device = Some((difop, where_));
            topics.push(info);
            kinds.push(Kind::RobosenseInfo);
        } else if sensor.sensor == SensorKind::Auto {
            bail!(
                "{label}: Robosense packets on {topic} and no robosense_info_packets topic beside \
                 them: name the model with --sensor (and its angle.csv with --calibration)"
            );
        }
    }
    // The first packets tell the sensor, as a pcap's do; damage is the stream's to report.
    let mut survey = Survey::default();
    let mut first = Datagrams::new(ros1, &kinds, ports);
    let _ = rec.scan(&topics, &mut |m| {
        first.add(m.topic, m.time_ns, Kind::of_message(ros1, &m), m.data);
        while let Some(d) = first.queue.pop_front() {
            if !survey.add(&Record::Datagram(d)) {
                return ControlFlow::Break(());
            }
        }
        ControlFlow::Continue(())
    });
    beside.survey = Some(survey);
    let mut stream = rec.stream(&topics)?;
    warnings.extend(stream.take_warnings());
    let source = Datagrams::new(ros1, &kinds, ports).over(stream);
    let decoded = sweeps::decode_beside(Path::new(&label), Box::new(source), &sensor, beside)?;
    Ok(Box::new(SweepFrames::new(
        decoded,
        &label,
        opts.scan_points,
    )))
}

/// The topic of `kind` named as `topic` with its last part `last` (`/ouster/lidar_packets`
/// gives `/ouster/imu_packets`, `/ouster/metadata`).
fn sibling(all: &[(String, String)], topic: &str, last: &str, kind: Kind) -> Option<String> {
    let (ns, _) = topic.rsplit_once('/')?;
    let name = format!("{ns}/{last}");
    all.iter()
        .find(|(t, tp)| *t == name && Kind::of(tp) == Some(kind))
        .map(|(t, _)| t.clone())
}

/// The only `std_msgs/String` topic named `.../metadata`.
fn only_metadata(all: &[(String, String)]) -> Option<String> {
    let mut found = all
        .iter()
        .filter(|(t, tp)| t.ends_with("metadata") && Kind::of(tp) == Some(Kind::Text));
    match (found.next(), found.next()) {
        (Some((t, _)), None) => Some(t.clone()),
        _ => None,
    }
}

/// The Ouster metadata JSON of the first message on `topic`, and where it came from.
fn read_metadata(
    rec: &mut dyn Recording,
    topic: &str,
) -> Result<(ouster_meta::OusterMeta, String)> {
    let (label, ros1) = (rec.label().to_string(), rec.ros1());
    let mut text: Option<Result<String, String>> = None;
    rec.scan(&[topic.to_string()], &mut |m| {
        text = Some(super::serial::Reader::of(ros1, m.data).and_then(|mut r| {
            let s = r.string("data")?;
            r.finish().map(|()| s)
        }));
        ControlFlow::Break(())
    })?;
    let where_ = format!("{label}:{topic}");
    match text {
        None => bail!("{where_}: no message: give the sensor's metadata JSON (--calibration)"),
        Some(Err(e)) => bail!("{where_}: not a std_msgs/String: {e}"),
        Some(Ok(json)) => Ok((
            ouster_meta::parse(&json).map_err(|e| anyhow!("{where_}: {e:#}"))?,
            where_,
        )),
    }
}

/// The first message on `topic` (nebula's `RobosenseInfoPacket`): the model's name, its DIFOP
/// packet, and where it came from.
fn read_robosense_info(rec: &mut dyn Recording, topic: &str) -> Result<(String, Vec<u8>, String)> {
    let (label, ros1) = (rec.label().to_string(), rec.ros1());
    let mut info = None;
    rec.scan(&[topic.to_string()], &mut |m| {
        info = Some(packets::robosense_info(ros1, m.data).map(|(n, p)| (n, p.data.to_vec())));
        ControlFlow::Break(())
    })?;
    let where_ = format!("{label}:{topic}");
    match info {
        None => bail!("{where_}: no message: give the unit's angle.csv with --calibration"),
        Some(Err(e)) => bail!("{where_}: not a RobosenseInfoPacket: {e}"),
        Some(Ok((model, difop))) => Ok((model, difop, where_)),
    }
}

/// The `--sensor` of a Robosense model as nebula names it.
fn robosense_kind(model: &str) -> Option<SensorKind> {
    let model = model.to_ascii_lowercase();
    Some(match model.as_str() {
        "helios" => SensorKind::Helios,
        m if m.starts_with("bpearl") => SensorKind::Bpearl,
        _ => return None,
    })
}

/// Where the sensor sends its packets; `None` for its usual port.
#[derive(Clone, Copy, Debug)]
struct Ports {
    lidar: Option<u16>,
    imu: Option<u16>,
}

/// Packet messages as the datagrams a capture would hold.
struct Datagrams {
    ros1: bool,
    /// What each topic carries, by its place in the stream's list.
    kinds: Vec<Kind>,
    ports: Ports,
    stream: Option<Box<dyn MessageStream>>,
    queue: VecDeque<Datagram>,
    /// Messages read, and those that could not be, with the first reason.
    messages: usize,
    refused: usize,
    first_refused: Option<String>,
}

impl Datagrams {
    fn new(ros1: bool, kinds: &[Kind], ports: Ports) -> Self {
        Self {
            ros1,
            kinds: kinds.to_vec(),
            ports,
            stream: None,
            queue: VecDeque::new(),
            messages: 0,
            refused: 0,
            first_refused: None,
        }
    }

    fn over(mut self, stream: Box<dyn MessageStream>) -> Self {
        self.stream = Some(stream);
        self
    }

    /// Queues the datagrams of message `data` of the `topic`-th topic (0: the lidar packets,
    /// 1: an Ouster's IMU packets or a Robosense's DIFOP packets), received at `time_ns`.
    fn add(&mut self, topic: usize, time_ns: u64, kind: Result<Kind, String>, data: &[u8]) {
        let index = self.messages;
        self.messages += 1;
        let expected = self.kinds.get(topic).copied().unwrap_or(Kind::Text);
        let wanted = expected.type_name(self.ros1);
        let parsed = match kind {
            Ok(k) if k == expected => packets::packets(k, self.ros1, data),
            Ok(k) => Err(format!("{}, not {wanted}", k.type_name(self.ros1))),
            Err(what) => Err(format!("{what}, not {wanted}")),
        };
        let list = match parsed {
            Ok(list) => list,
            Err(e) => {
                self.refused += 1;
                self.first_refused
                    .get_or_insert_with(|| format!("message {index}: {e}"));
                return;
            }
        };
        for Packet { stamp_ns, data } in list {
            let port = self.port(topic, data);
            self.queue.push_back(Datagram {
                time_ns: stamp_ns.unwrap_or(time_ns),
                source: SocketAddr::from((Ipv4Addr::UNSPECIFIED, port)),
                port,
                payload: data.to_vec(),
            });
        }
    }

    /// The port the sensor sends this packet to.
    fn port(&self, topic: usize, data: &[u8]) -> u16 {
        let lidar = self.ports.lidar;
        match self.kinds.get(topic).copied().unwrap_or(Kind::Text) {
            Kind::OusterPacket if topic == 1 => self.ports.imu.unwrap_or(OUSTER_IMU_PORT),
            Kind::OusterPacket => lidar.unwrap_or(OUSTER_PORT),
            Kind::RobosenseInfo => DIFOP_PORT,
            Kind::RobosenseScan => lidar.unwrap_or(MSOP_PORT),
            Kind::NebulaPackets => {
                if livox::sdk1::Packet::new_checked(data).is_ok() {
                    lidar.unwrap_or(LIVOX_PORT)
                } else if let Ok(p) = livox::sdk2::Packet::new_checked(data) {
                    match p.imu() {
                        Some(_) => LIVOX2_IMU_PORT,
                        None => lidar.unwrap_or(LIVOX2_PORT),
                    }
                } else {
                    lidar.unwrap_or(VELODYNE_PORT)
                }
            }
            _ => lidar.unwrap_or(VELODYNE_PORT),
        }
    }
}

impl DatagramSource for Datagrams {
    fn next_datagram(&mut self) -> Result<Option<Datagram>> {
        loop {
            if let Some(d) = self.queue.pop_front() {
                return Ok(Some(d));
            }
            // Out of `self` while its message is borrowed, so that `add` can queue it.
            let Some(mut stream) = self.stream.take() else {
                return Ok(None);
            };
            let read = match stream.next_message() {
                Ok(Some(m)) => {
                    let kind = Kind::of_message(self.ros1, &m);
                    self.add(m.topic, m.time_ns, kind, m.data);
                    Ok(true)
                }
                Ok(None) => Ok(false),
                Err(e) => Err(e),
            };
            self.stream = Some(stream);
            if !read? {
                return Ok(None);
            }
        }
    }

    fn warnings(&self) -> Vec<String> {
        match &self.first_refused {
            Some(first) => vec![format!(
                "{} of {} packet message(s) could not be read and were left out (first: {first})",
                self.refused, self.messages
            )],
            None => Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests;
