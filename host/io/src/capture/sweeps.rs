//! Sensor recordings to sweeps: a pcap of Velodyne, Ouster, Hesai or Livox packets, decoded by
//! `kiss-odom-sensors`, one [`Sweep`] at a time with per-point times and per-sweep packet
//! statistics.
//!
//! The sensor is told by the options or found in the capture: Velodyne data packets are 1206
//! bytes on port 2368 unless `input.port` says otherwise (the model is in each packet's product
//! byte, or `--sensor`; a byte the packets' timing contradicts is a warning), Ouster packets
//! need the sensor's metadata JSON (`--calibration`), Hesai packets start `EE FF` and their
//! protocol version on port 2368 (the model found from it when no Velodyne packets are; the
//! 128-channel models need their angle correction file, `--calibration`), Livox SDK 1 packets
//! come to port 56001 (found there without `--sensor livox`), Livox SDK 2 (Mid-360)
//! packets to port 56301 (found there without `--sensor mid360`). IMU packets (Ouster's on
//! their own port, Livox SDK 1's on the data port, SDK 2's on their own) become the sweeps' IMU
//! samples, not points. Only one sender is decoded: the first whose
//! packets decode on the port; other senders on that port (a second sensor) are skipped,
//! counted as another sensor's in the sweep they arrive in and named in the [`PcapReport`].
//! Damage confined to a packet is a counted skip in the sweep's statistics; a capture with no
//! decodable packet, or cut in the middle, or Ouster packets that contradict the metadata
//! before the first sweep is complete, is an error naming the file and the reason. A sweep
//! keeps at most the points it is asked to ([`PcapSweeps::limit_points`]: the core's scan
//! capacity), however long the sensor takes to end it.

use super::identify;
use super::pcap::{self, Capture, Datagram, Record};
use crate::dataset::{Frame, SensorKind, SensorOptions, SweepInfo};
use crate::imu::ImuSample;
use anyhow::{anyhow, Result};
use kiss_odom_sensors::robosense;
use kiss_odom_sensors::velodyne::{self, Model};
use kiss_odom_sensors::{
    hesai, livox, ouster, Chunk, Decode, PacketError, PointMeta, Pushed, SweepSink, SweepStart,
    SweepStats,
};
use std::collections::{BTreeMap, VecDeque};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};

/// Velodyne data port (and Hesai's).
pub const VELODYNE_PORT: u16 = 2368;
/// Livox SDK 1 data port on the host.
pub const LIVOX_PORT: u16 = 56001;
/// Livox SDK 2 point data port on the host (the Mid-360's default).
pub const LIVOX2_PORT: u16 = 56301;
/// Ouster lidar port (when the metadata does not say).
pub const OUSTER_PORT: u16 = 7502;
/// Ouster IMU port (when the metadata does not say).
pub const OUSTER_IMU_PORT: u16 = 7503;

/// One decoded sweep.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sweep {
    /// Sensor-frame points, metres.
    pub points: Vec<[f64; 3]>,
    /// Per-point capture time, seconds since `stats.start_ns` (sensor clock).
    pub times: Vec<f64>,
    /// Ring, column, return and intensity of each point.
    pub meta: Vec<PointMeta>,
    /// Packet statistics.
    pub stats: SweepStats,
    /// Capture (host) time of the sweep's first packet, ns since the Unix epoch.
    pub capture_ns: u64,
    /// Capture (host) time of the last packet that gave the sweep points.
    pub last_capture_ns: u64,
    /// Points the sweep had beyond the most it keeps ([`PcapSweeps::limit_points`]): dropped.
    pub beyond_capacity: u64,
    /// IMU samples that arrived since the previous sweep ended, in arrival order.
    pub imu: Vec<ImuSample>,
}

impl Sweep {
    /// The sweep as a [`Frame`] for the odometry (times become the per-point stamps).
    pub fn into_frame(self, index: usize, name: String) -> Frame {
        let (lo, hi) = self
            .times
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &t| {
                (lo.min(t), hi.max(t))
            });
        let start = self.stats.start_ns as f64 * 1e-9;
        let sweep = SweepInfo {
            stats: self.stats,
            start_s: start + if lo.is_finite() { lo } else { 0.0 },
            end_s: start + if hi.is_finite() { hi } else { 0.0 },
            last_capture_ns: self.last_capture_ns,
        };
        Frame {
            index,
            name,
            points: self.points,
            stamps: Some(self.times),
            time: Some(self.capture_ns as f64 * 1e-9),
            warnings: Vec::new(),
            intensity: Some(self.meta.iter().map(|m| f32::from(m.intensity)).collect()),
            sweep: Some(sweep),
            end: None,
            imu: self.imu,
        }
    }
}

/// What the capture held besides the decoded sweeps.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PcapReport {
    /// The sensor decoded, e.g. `Velodyne VLP-16` or `Ouster OS-1-128 122201000998`.
    pub sensor: String,
    /// The port decoded.
    pub port: u16,
    /// The sender decoded.
    pub source: Option<SocketAddr>,
    /// Datagrams on the port from the decoded sender (or before one was chosen).
    pub on_port: u64,
    /// Packets decoded.
    pub decoded: u64,
    /// Packets refused, by reason.
    pub refused: BTreeMap<String, u64>,
    /// Datagrams on the port from other senders (skipped).
    pub other_sources: BTreeMap<SocketAddr, u64>,
    /// IMU packets (Livox: on the data port or, SDK 2, their own; Ouster: on the metadata's
    /// `udp_port_imu`, 7503 if unset), decoded into each sweep's [`Sweep::imu`].
    pub imu_packets: u64,
    /// Datagrams on other ports (skipped), by port.
    pub other_ports: BTreeMap<u16, u64>,
    /// Of those, datagrams of the sensor's data-packet length or of a sensor family's data
    /// packets ([`identify::family_of`]), by port: another sensor there?
    pub data_elsewhere: BTreeMap<u16, u64>,
    /// What else the capture, the metadata and the packets' timing showed (frames not read,
    /// fragments lost, a model the timing contradicts), one line each; complete at the end.
    pub notes: Vec<String>,
}

impl PcapReport {
    /// One line per thing a person should know: other senders, refused packets, packets of
    /// the sensor's length elsewhere, and the notes.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if !self.other_sources.is_empty() {
            let list: Vec<_> = self
                .other_sources
                .iter()
                .map(|(s, n)| format!("{s} ({n})"))
                .collect();
            w.push(format!(
                "packets from {} other sender(s) on port {} skipped (two sensors on one port?): {}",
                list.len(),
                self.port,
                list.join(", ")
            ));
        }
        for (reason, n) in &self.refused {
            w.push(format!("{n} packet(s) refused: {reason}"));
        }
        if self.decoded > 0 {
            for (port, n) in &self.data_elsewhere {
                w.push(format!(
                    "{n} sensor data packet(s) on port {port} not decoded (a second sensor? \
                     --set input.port={port} decodes them instead)"
                ));
            }
        }
        w.extend(self.notes.iter().cloned());
        w
    }
}

pub(super) enum Decoder {
    Velodyne(Box<velodyne::Decoder>),
    Robosense(Box<robosense::Decoder>),
    /// The RS-M1 or E1R: each return its direction.
    RobosenseSolid(Box<robosense::solid::Decoder>),
    Ouster(Box<ouster::Decoder>),
    Hesai(Box<hesai::Decoder>),
    /// The PandarAT128: its angles from the mirror-frame correction.
    HesaiAt128(Box<hesai::Decoder<hesai::MirrorAngles>>),
    Livox(Box<livox::Decoder>),
}

impl Decoder {
    /// Pushes the packet, and again if it began a new sweep ([`Pushed::Again`]; the second
    /// push never answers that).
    fn push(&mut self, bytes: &[u8], sink: &mut Collect) -> Result<(), PacketError> {
        let mut r = Ok(Pushed::Again);
        for _ in 0..2 {
            r = match self {
                Self::Velodyne(d) => d.push(bytes, sink),
                Self::Robosense(d) => d.push(bytes, sink),
                Self::RobosenseSolid(d) => d.push(bytes, sink),
                Self::Ouster(d) => d.push(bytes, sink),
                Self::Hesai(d) => d.push(bytes, sink),
                Self::HesaiAt128(d) => d.push(bytes, sink),
                Self::Livox(d) => d.push(bytes, sink),
            };
            if r != Ok(Pushed::Again) {
                break;
            }
        }
        r.map(|_| ())
    }
    fn finish(&mut self, sink: &mut Collect) {
        match self {
            Self::Velodyne(d) => d.finish(sink),
            Self::Robosense(d) => d.finish(sink),
            Self::RobosenseSolid(d) => d.finish(sink),
            Self::Ouster(d) => d.finish(sink),
            Self::Hesai(d) => d.finish(sink),
            Self::HesaiAt128(d) => d.finish(sink),
            Self::Livox(d) => d.finish(sink),
        }
    }
    fn between_sweeps(&self) -> SweepStats {
        match self {
            Self::Velodyne(d) => *d.between_sweeps(),
            Self::Robosense(d) => *d.between_sweeps(),
            Self::RobosenseSolid(d) => *d.between_sweeps(),
            Self::Ouster(d) => *d.between_sweeps(),
            Self::Hesai(d) => *d.between_sweeps(),
            Self::HesaiAt128(d) => *d.between_sweeps(),
            Self::Livox(d) => *d.between_sweeps(),
        }
    }
}

/// Packets refused here, before the decoder (damaged, other senders), that no sweep's
/// statistics hold yet: they go to the sweep that ends next.
#[derive(Clone, Copy, Debug, Default)]
struct Refused {
    bad: u32,
    other_sensor: u32,
}

impl Refused {
    fn add_to(self, s: &mut SweepStats) {
        s.bad_packets = s.bad_packets.saturating_add(self.bad);
        s.other_sensor = s.other_sensor.saturating_add(self.other_sensor);
    }
}

/// Gathers the decoder's chunks into whole sweeps of at most `capacity` points.
struct Collect {
    current: Option<Sweep>,
    done: VecDeque<Sweep>,
    capture_ns: u64,
    capacity: usize,
    refused: Refused,
    /// IMU samples since the last sweep ended: the next sweep's.
    imu: Vec<ImuSample>,
    /// Sweeps ended so far.
    ended: u64,
}

impl Default for Collect {
    fn default() -> Self {
        Self {
            current: None,
            done: VecDeque::new(),
            capture_ns: 0,
            capacity: usize::MAX,
            refused: Refused::default(),
            imu: Vec::new(),
            ended: 0,
        }
    }
}

impl SweepSink for Collect {
    fn begin_sweep(&mut self, _: &SweepStart) {
        self.current = Some(Sweep {
            capture_ns: self.capture_ns,
            ..Sweep::default()
        });
    }
    fn points(&mut self, c: Chunk<'_>) {
        if let Some(s) = &mut self.current {
            s.last_capture_ns = self.capture_ns;
            let n = c
                .xyz
                .len()
                .min(self.capacity.saturating_sub(s.points.len()));
            s.points.extend_from_slice(&c.xyz[..n]);
            s.times.extend_from_slice(&c.times[..n]);
            s.meta.extend_from_slice(&c.meta[..n]);
            s.beyond_capacity += (c.xyz.len() - n) as u64;
        }
    }
    fn end_sweep(&mut self, stats: &SweepStats) {
        if let Some(mut s) = self.current.take() {
            s.stats = *stats;
            std::mem::take(&mut self.refused).add_to(&mut s.stats);
            s.imu = std::mem::take(&mut self.imu);
            self.done.push_back(s);
            self.ended += 1;
        }
    }
}

/// Where datagrams come from: a capture file, or a socket (`kiss-odom live`).
pub trait DatagramSource {
    /// The next datagram, `Ok(None)` at the end, or an error naming the source when nothing
    /// after it can be read.
    fn next_datagram(&mut self) -> Result<Option<Datagram>>;
    /// The next datagram, whole or damaged ([`Record`]); a source that never holds damaged
    /// ones (a socket) need not say.
    fn next_record(&mut self) -> Result<Option<Record>> {
        Ok(self.next_datagram()?.map(Record::Datagram))
    }
    /// What the source could not hand on (frames not read, fragments lost), one line each.
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }
}

impl DatagramSource for Capture {
    fn next_datagram(&mut self) -> Result<Option<Datagram>> {
        Capture::next_datagram(self)
    }
    fn next_record(&mut self) -> Result<Option<Record>> {
        Capture::next_record(self)
    }
    fn warnings(&self) -> Vec<String> {
        self.counts().warnings()
    }
}

/// A recording being decoded, sweep by sweep.
pub struct PcapSweeps {
    path: PathBuf,
    capture: Box<dyn DatagramSource>,
    decoder: Decoder,
    sink: Collect,
    pub(super) meta_path: Option<PathBuf>,
    /// Whether `--sensor` named the Velodyne model.
    model_given: bool,
    /// The Ouster IMU port.
    pub(super) imu_port: Option<u16>,
    report: PcapReport,
    /// Ouster packets contradicting the metadata before the first sweep: the stream's end.
    fatal: Option<anyhow::Error>,
    finished: bool,
}

pub use super::choose::{decode, decode_beside, Beside, Survey};

/// Opens a recording (see the module doc).
pub fn open(path: &Path, opts: &SensorOptions) -> Result<PcapSweeps> {
    decode(path, Box::new(pcap::open(path)?), opts)
}

/// The `--sensor` value of a model.
fn sensor_flag(m: Model) -> &'static str {
    match m {
        Model::Vlp16 => "vlp16",
        Model::PuckHiRes => "puck-hi-res",
        Model::Vlp32c => "vlp32c",
        Model::Hdl32e => "hdl32e",
        Model::Vlp32ab => "vlp32ab",
        Model::Hdl64eS2 => "hdl64e-s2",
        Model::Hdl64eS3 => "hdl64e-s3",
        Model::Vls128 => "vls128",
    }
}

pub(super) fn sweeps(
    path: &Path,
    capture: Box<dyn DatagramSource>,
    decoder: Decoder,
    opts: &SensorOptions,
    (port, sensor, notes): (u16, String, Vec<String>),
) -> PcapSweeps {
    PcapSweeps {
        path: path.to_path_buf(),
        capture,
        decoder,
        sink: Collect::default(),
        meta_path: opts.meta.clone(),
        model_given: matches!(
            opts.sensor,
            SensorKind::Vlp16
                | SensorKind::PuckHiRes
                | SensorKind::Vlp32c
                | SensorKind::Hdl32e
                | SensorKind::Vlp32ab
                | SensorKind::Hdl64eS2
                | SensorKind::Hdl64eS3
                | SensorKind::Vls128
        ),
        imu_port: None,
        report: PcapReport {
            sensor,
            port,
            notes,
            ..PcapReport::default()
        },
        fatal: None,
        finished: false,
    }
}

impl PcapSweeps {
    /// What was read so far; complete once the iterator has ended.
    pub fn report(&self) -> &PcapReport {
        &self.report
    }

    /// Keeps at most `points` points of each sweep from now on; the rest are counted in
    /// [`Sweep::beyond_capacity`], so memory follows the capacity, not the recording.
    pub fn limit_points(&mut self, points: usize) {
        self.sink.capacity = points;
    }

    /// Whether the source has ended and every sweep was taken: the report is complete.
    pub fn exhausted(&self) -> bool {
        self.finished && self.sink.done.is_empty()
    }

    /// Packets refused or lost since the last sweep ended, which no sweep holds: once
    /// [`Self::exhausted`], what came after the last sweep.
    pub fn after_last_sweep(&self) -> SweepStats {
        let mut s = self.decoder.between_sweeps();
        self.sink.refused.add_to(&mut s);
        s
    }

    /// The sample of an IMU packet of the decoded sensor: Livox ones by their data type (SDK
    /// 1 sends them to the data port from another source port, SDK 2 to a port of their own),
    /// Ouster ones by their port (timed at the gyroscope's read).
    fn imu_sample(&self, port: u16, payload: &[u8]) -> Option<ImuSample> {
        // A Livox packet's data type byte first: the point packets, nearly all of them, are
        // checked once, by the decoder, not also here (a CRC over each SDK 2 packet).
        let data_type = |at: usize| payload.get(at).copied();
        let (time_ns, s) = match &self.decoder {
            Decoder::Livox(d) if d.model() == livox::Model::Mid360 => {
                if data_type(livox::sdk2::field::DATA_TYPE) != Some(livox::sdk2::IMU) {
                    return None;
                }
                let p = livox::sdk2::Packet::new_checked(payload).ok()?;
                (p.time_ns(), p.imu()?)
            }
            Decoder::Livox(_) => {
                if data_type(livox::sdk1::field::DATA_TYPE) != Some(livox::sdk1::IMU) {
                    return None;
                }
                let p = livox::sdk1::Packet::new_checked(payload).ok()?;
                (p.time_ns()?, p.imu()?)
            }
            Decoder::Ouster(_) if Some(port) == self.imu_port => {
                let p = ouster::ImuPacket::new_checked(payload).ok()?;
                let accel = ImuSample::from_g(p.gyro_ts(), [0.0; 3], p.accel_g());
                return Some(ImuSample {
                    gyro: p.gyro_deg_s().map(|w| f64::from(w).to_radians()),
                    ..accel
                });
            }
            _ => return None,
        };
        Some(ImuSample::from_g(time_ns, s.gyro, s.accel_g))
    }

    /// The length of the sensor's data packets.
    fn data_len(&self) -> usize {
        match &self.decoder {
            Decoder::Velodyne(_) => velodyne::wire::field::LEN,
            Decoder::Robosense(_) => robosense::wire::LEN,
            Decoder::RobosenseSolid(d) => d.model().packet_len(),
            Decoder::Ouster(d) => d.layout().packet_len(),
            Decoder::Hesai(d) if d.model() == hesai::Model::Xt32 => {
                hesai::wire::field::LEN_WITH_SEQUENCE
            }
            // The lengths the sensors send by default: QT128C2X 1127 bytes, 1.4 861 bytes.
            Decoder::Hesai(d) if d.model().fixed_format().is_some() => {
                d.model().fixed_format().map_or(0, |f| f.default_len())
            }
            Decoder::Hesai(d) if d.model() == hesai::Model::Qt128 => {
                hesai::wire128::packet_len(hesai::wire128::VERSION_QT, 0x1D)
            }
            Decoder::Hesai(_) => hesai::wire128::packet_len(hesai::wire128::VERSION_128, 0x07),
            Decoder::HesaiAt128(_) => hesai::wire_fixed::PANDARAT128.default_len(),
            // The SDKs' default data types: SDK 1's 2, SDK 2's 1 (96 points, the Mid-360's).
            Decoder::Livox(d) if d.model() == livox::Model::Mid360 => {
                livox::sdk2::packet_len(1, livox::sdk2::MID360_POINTS).unwrap_or(0)
            }
            Decoder::Livox(_) => livox::sdk1::packet_len(2).unwrap_or(0),
        }
    }

    fn feed(&mut self, record: Record) {
        let (time_ns, source, port) = match &record {
            Record::Datagram(d) => (d.time_ns, d.source, d.port),
            Record::Damaged {
                time_ns,
                source,
                port,
                ..
            } => (*time_ns, *source, *port),
        };
        let data_len = self.data_len();
        if let Record::Datagram(g) = &record {
            if let Some(sample) = self.imu_sample(port, &g.payload) {
                self.report.imu_packets += 1;
                self.sink.imu.push(sample);
                return;
            }
        }
        let r = &mut self.report;
        if port != r.port {
            *r.other_ports.entry(port).or_insert(0) += 1;
            // Another sensor's data packets: of this one's length, or of a family whose
            // packets name it (a second Livox unit sends to another port, in other lengths);
            // not a Robosense unit's device packets (DIFOP), of its data packets' length.
            let data = |d: &Datagram| {
                (d.payload.len() == data_len || identify::family_of(&d.payload).is_some())
                    && !d.payload.starts_with(&robosense::wire::DIFOP_ID)
            };
            if matches!(&record, Record::Datagram(d) if data(d)) {
                *r.data_elsewhere.entry(port).or_insert(0) += 1;
            }
            return;
        }
        if r.source.is_some_and(|s| s != source) {
            *r.other_sources.entry(source).or_insert(0) += 1;
            self.sink.refused.other_sensor = self.sink.refused.other_sensor.saturating_add(1);
            return;
        }
        r.on_port += 1;
        self.sink.capture_ns = time_ns;
        let d = match record {
            Record::Datagram(d) => d,
            Record::Damaged { damage, .. } => {
                *r.refused.entry(damage.to_string()).or_insert(0) += 1;
                self.sink.refused.bad = self.sink.refused.bad.saturating_add(1);
                return;
            }
        };
        match self.decoder.push(&d.payload, &mut self.sink) {
            Ok(()) => {
                r.decoded += 1;
                if r.source.is_none() {
                    r.source = Some(d.source);
                    if let Decoder::Velodyne(v) = &self.decoder {
                        let model = v.model().unwrap_or(Model::Vlp16);
                        r.sensor = format!("Velodyne {}", model.name());
                    }
                }
            }
            Err(e) => {
                *r.refused.entry(e.to_string()).or_insert(0) += 1;
                let contradiction =
                    matches!(e, PacketError::ColumnWindow | PacketError::ColumnRate);
                if contradiction && self.sink.ended == 0 && self.fatal.is_none() {
                    self.fatal = Some(self.contradicted(e));
                }
            }
        }
    }

    /// The error for Ouster packets that contradict the metadata.
    fn contradicted(&self, e: PacketError) -> anyhow::Error {
        let meta = self
            .meta_path
            .as_deref()
            .map_or_else(String::new, |m| format!(" {}", m.display()));
        anyhow!(
            "{}: packet {} on port {} contradicts the metadata{meta}: {e}; give the metadata \
             saved with this recording",
            self.path.display(),
            self.report.on_port,
            self.report.port
        )
    }

    /// What the capture and the packets' timing showed, for the report's notes.
    fn end_notes(&self) -> Vec<String> {
        let mut notes = self.capture.warnings();
        if let Decoder::Velodyne(v) = &self.decoder {
            notes.extend(timing_note(v, self.model_given));
        }
        notes
    }

    /// The reason nothing decoded, naming the file.
    fn nothing_decoded(&self) -> anyhow::Error {
        let r = &self.report;
        let file = self.path.display();
        if r.on_port == 0 {
            let ports: Vec<_> = r
                .other_ports
                .iter()
                .map(|(p, n)| format!("{n} on port {p}"))
                .collect();
            let seen = if ports.is_empty() {
                "no UDP packets at all".to_string()
            } else {
                format!("UDP seen: {}", ports.join(", "))
            };
            let elsewhere: Vec<_> = r
                .data_elsewhere
                .iter()
                .map(|(p, n)| format!("{n} on port {p} (--set input.port={p})"))
                .collect();
            let hint = if elsewhere.is_empty() {
                String::new()
            } else {
                format!(
                    "; packets of the sensor's data length ({} bytes): {}",
                    self.data_len(),
                    elsewhere.join(", ")
                )
            };
            let notes: String = r.notes.iter().map(|n| format!("; {n}")).collect();
            return anyhow!(
                "{file}: no packets on port {} ({seen}){hint}{notes}",
                r.port
            );
        }
        let (reason, _) = r
            .refused
            .iter()
            .max_by_key(|(_, n)| **n)
            .map(|(k, n)| (k.clone(), *n))
            .unwrap_or_default();
        let hint = match &self.meta_path {
            Some(m)
                if reason.contains("metadata")
                    || reason.contains("longer")
                    || reason.contains("shorter") =>
            {
                format!(" (is {} the metadata of this sensor?)", m.display())
            }
            _ => String::new(),
        };
        anyhow!(
            "{file}: {} packets on port {}, none decoded: {reason}{hint}",
            r.on_port,
            r.port
        )
    }
}

/// A warning when the packets' spacing contradicts the Velodyne model decoded (from the
/// product byte, or `--sensor`): which models send packets that far apart.
fn timing_note(v: &velodyne::Decoder, model_given: bool) -> Option<String> {
    let (model, nominal, step) = (v.model()?, v.packet_us()?, v.shortest_step_us()?);
    let spacing = f64::from(step);
    if spacing <= 1.5 * nominal && spacing >= nominal / 1.5 {
        return None;
    }
    let dual = (nominal - model.packet_us(true)).abs() < 1e-6;
    let fitting: Vec<Model> = Model::ALL
        .into_iter()
        .filter(|m| (m.packet_us(dual) - spacing).abs() <= 0.02 * spacing)
        .collect();
    let names: Vec<&str> = fitting.iter().map(|m| m.name()).collect();
    let flags: Vec<String> = fitting
        .iter()
        .map(|m| format!("--sensor {}", sensor_flag(*m)))
        .collect();
    let said = if model_given {
        "--sensor"
    } else {
        "the packets' product byte"
    };
    let (why, fix) = if fitting.is_empty() {
        (
            "packets are lost in between, or the model is wrong".to_string(),
            "--sensor with the unit's model".to_string(),
        )
    } else {
        (
            format!("as from a {}", names.join(" or ")),
            flags.join(" or "),
        )
    };
    Some(format!(
        "{said} says {name}, but they come {step} us apart at the closest, {why} ({name}: one \
         every {nominal:.0} us): decoded as {name}, losses counted from the packets' own \
         spacing; if the model is wrong, give {fix}",
        name = model.name()
    ))
}

impl Iterator for PcapSweeps {
    type Item = Result<Sweep>;

    fn next(&mut self) -> Option<Result<Sweep>> {
        loop {
            if let Some(e) = self.fatal.take() {
                self.finished = true;
                self.sink.done.clear();
                return Some(Err(e));
            }
            if let Some(s) = self.sink.done.pop_front() {
                return Some(Ok(s));
            }
            if self.finished {
                return None;
            }
            match self.capture.next_record() {
                Ok(Some(r)) => self.feed(r),
                Ok(None) => {
                    self.finished = true;
                    let notes = self.end_notes();
                    self.report.notes.extend(notes);
                    if self.report.decoded == 0 {
                        return Some(Err(self.nothing_decoded()));
                    }
                    self.decoder.finish(&mut self.sink);
                }
                Err(e) => {
                    self.finished = true;
                    self.sink.done.clear();
                    return Some(Err(e));
                }
            }
        }
    }
}

/// Every sweep of a recording and the report, or the first error (naming the file).
pub fn read_all(path: &Path, opts: &SensorOptions) -> Result<(Vec<Sweep>, PcapReport)> {
    let mut it = open(path, opts)?;
    let sweeps = it.by_ref().collect::<Result<Vec<_>>>()?;
    Ok((sweeps, it.report.clone()))
}
