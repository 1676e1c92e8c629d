//! Sensor recordings to sweeps: a pcap of Velodyne or Ouster packets, decoded by
//! `kiss-odom-sensors`, one [`Sweep`] at a time with per-point times and per-sweep packet
//! statistics.
//!
//! The sensor is told by the options or found in the capture: Velodyne data packets are 1206
//! bytes (the model is in each packet), Ouster packets need the sensor's metadata JSON
//! (`--meta`). Only one sender is decoded: the first whose packets decode on the port; other
//! senders on that port (a second sensor) are skipped and counted in the [`PcapReport`].
//! Damage confined to a packet is a counted skip in the sweep's statistics; a capture with no
//! decodable packet, or cut in the middle, is an error naming the file and the reason.

use super::pcap::{self, Capture, Datagram};
use super::{ouster_meta, velodyne_calib, Frame};
use anyhow::{anyhow, bail, Result};
use kiss_odom_sensors::velodyne::{self, Model};
use kiss_odom_sensors::{
    ouster, Chunk, Decode, PacketError, PointMeta, Pushed, SweepSink, SweepStart, SweepStats,
};
use std::collections::{BTreeMap, VecDeque};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};

/// Velodyne data port.
pub const VELODYNE_PORT: u16 = 2368;
/// Ouster lidar port (when the metadata does not say).
pub const OUSTER_PORT: u16 = 7502;

/// Which sensor a recording is from (`--sensor`).
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    clap::ValueEnum,
    serde::Serialize,
    serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum SensorKind {
    /// Ouster if metadata is given, otherwise Velodyne with the model from the packets.
    #[default]
    Auto,
    /// Velodyne VLP-16 / Puck.
    Vlp16,
    /// Velodyne VLP-16 Hi-Res.
    PuckHiRes,
    /// Velodyne VLP-32C.
    Vlp32c,
    /// Velodyne HDL-32E.
    Hdl32e,
    /// Ouster (needs the metadata JSON).
    Ouster,
}

/// How to read a recording.
#[derive(Clone, Debug, Default)]
pub struct SensorOptions {
    /// The sensor.
    pub sensor: SensorKind,
    /// UDP port (default: 2368 for Velodyne, the metadata's or 7502 for Ouster).
    pub port: Option<u16>,
    /// Ouster metadata JSON.
    pub meta: Option<PathBuf>,
    /// Velodyne calibration (XML or YAML).
    pub calibration: Option<PathBuf>,
    /// Velodyne cut angle, degrees (default: a full turn from wherever the last sweep ended).
    pub cut_angle_deg: Option<f64>,
}

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
}

/// What a frame decoded from sensor packets carries besides its points: the sweep's packet
/// statistics (for `frames.csv`), the sensor-clock instants of its first and last point (the
/// instants a pose can refer to, `--pose-time`) and when its last packet was captured.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SweepInfo {
    /// Packet statistics.
    pub stats: SweepStats,
    /// Sensor-clock time of the sweep's first point, s.
    pub start_s: f64,
    /// Sensor-clock time of the sweep's last point, s.
    pub end_s: f64,
    /// Capture (host) time of the last packet that gave the sweep points, ns since the Unix
    /// epoch.
    pub last_capture_ns: u64,
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
    /// Datagrams on other ports (skipped), by port.
    pub other_ports: BTreeMap<u16, u64>,
}

impl PcapReport {
    /// One line per thing a person should know: other senders, refused packets.
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
        w
    }
}

enum Decoder {
    Velodyne(Box<velodyne::Decoder>),
    Ouster(Box<ouster::Decoder>),
}

impl Decoder {
    /// Pushes the packet, and again if it began a new sweep ([`Pushed::Again`]; the second
    /// push never answers that).
    fn push(&mut self, bytes: &[u8], sink: &mut Collect) -> Result<(), PacketError> {
        let mut r = Ok(Pushed::Again);
        for _ in 0..2 {
            r = match self {
                Self::Velodyne(d) => d.push(bytes, sink),
                Self::Ouster(d) => d.push(bytes, sink),
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
            Self::Ouster(d) => d.finish(sink),
        }
    }
}

/// Gathers the decoder's chunks into whole sweeps.
#[derive(Default)]
struct Collect {
    current: Option<Sweep>,
    done: VecDeque<Sweep>,
    capture_ns: u64,
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
            s.points.extend_from_slice(c.xyz);
            s.times.extend_from_slice(c.times);
            s.meta.extend_from_slice(c.meta);
        }
    }
    fn end_sweep(&mut self, stats: &SweepStats) {
        if let Some(mut s) = self.current.take() {
            s.stats = *stats;
            self.done.push_back(s);
        }
    }
}

/// Where datagrams come from: a capture file, or a socket (`kiss-odom live`).
pub trait DatagramSource {
    /// The next datagram, `Ok(None)` at the end, or an error naming the source when nothing
    /// after it can be read.
    fn next_datagram(&mut self) -> Result<Option<Datagram>>;
}

impl DatagramSource for Capture {
    fn next_datagram(&mut self) -> Result<Option<Datagram>> {
        Capture::next_datagram(self)
    }
}

/// A recording being decoded, sweep by sweep.
pub struct PcapSweeps {
    path: PathBuf,
    capture: Box<dyn DatagramSource>,
    decoder: Decoder,
    sink: Collect,
    meta_path: Option<PathBuf>,
    report: PcapReport,
    finished: bool,
}

/// Ports and lengths of the first datagrams of a capture (up to any damage, which the
/// decoding pass reports).
fn survey(path: &Path) -> Result<BTreeMap<(u16, usize), u64>> {
    let mut seen = BTreeMap::new();
    for d in pcap::open(path)?.take(2000).map_while(Result::ok) {
        *seen.entry((d.port, d.payload.len())).or_insert(0) += 1;
    }
    Ok(seen)
}

fn describe(seen: &BTreeMap<(u16, usize), u64>) -> String {
    if seen.is_empty() {
        return "no UDP packets at all".into();
    }
    let list: Vec<_> = seen
        .iter()
        .map(|((p, l), n)| format!("{n} x {l} bytes on port {p}"))
        .collect();
    format!("UDP seen: {}", list.join(", "))
}

/// Opens a recording (see the module doc).
pub fn open(path: &Path, opts: &SensorOptions) -> Result<PcapSweeps> {
    decode(path, Box::new(pcap::open(path)?), opts)
}

/// Decodes the datagrams of `capture`, named `path` in messages; without `opts.port` a
/// Velodyne's port is found by reading the file at `path`.
pub fn decode(
    path: &Path,
    capture: Box<dyn DatagramSource>,
    opts: &SensorOptions,
) -> Result<PcapSweeps> {
    let ouster = opts.meta.is_some() || opts.sensor == SensorKind::Ouster;
    let (decoder, port, sensor) = if ouster {
        let Some(meta_path) = &opts.meta else {
            bail!(
                "{}: an Ouster recording needs the sensor's metadata JSON (--meta)",
                path.display()
            );
        };
        let meta = ouster_meta::read(meta_path)?;
        let dec = ouster::Decoder::new(&meta.info)
            .map_err(|e| anyhow!("{}: {e}", meta_path.display()))?;
        let port = opts.port.or(meta.udp_port_lidar).unwrap_or(OUSTER_PORT);
        let name = format!(
            "Ouster {} {} ({})",
            meta.prod_line, meta.serial, meta.firmware
        );
        (Decoder::Ouster(Box::new(dec)), port, name)
    } else {
        let model = match opts.sensor {
            SensorKind::Vlp16 => Some(Model::Vlp16),
            SensorKind::PuckHiRes => Some(Model::PuckHiRes),
            SensorKind::Vlp32c => Some(Model::Vlp32c),
            SensorKind::Hdl32e => Some(Model::Hdl32e),
            SensorKind::Auto | SensorKind::Ouster => None,
        };
        let port = match opts.port {
            Some(p) => p,
            None => {
                let seen = survey(path)?;
                let velodyne = seen
                    .keys()
                    .find(|(_, len)| *len == velodyne::wire::field::LEN);
                match velodyne {
                    Some(&(p, _)) => p,
                    None if seen.keys().any(|(p, _)| *p == OUSTER_PORT) => bail!(
                        "{}: packets on port {OUSTER_PORT} look like an Ouster's: give its \
                         metadata JSON (--meta)",
                        path.display()
                    ),
                    None => bail!(
                        "{}: no Velodyne data packets (1206 bytes); {}",
                        path.display(),
                        describe(&seen)
                    ),
                }
            }
        };
        let calibration = opts
            .calibration
            .as_deref()
            .map(velodyne_calib::read)
            .transpose()?;
        let config = velodyne::Config {
            model,
            calibration,
            cut_angle_deg: opts.cut_angle_deg,
        };
        let dec = velodyne::Decoder::new(config).map_err(|e| anyhow!("{}: {e}", path.display()))?;
        (
            Decoder::Velodyne(Box::new(dec)),
            port,
            "Velodyne".to_string(),
        )
    };
    Ok(PcapSweeps {
        path: path.to_path_buf(),
        capture,
        decoder,
        sink: Collect::default(),
        meta_path: opts.meta.clone(),
        report: PcapReport {
            sensor,
            port,
            ..PcapReport::default()
        },
        finished: false,
    })
}

impl PcapSweeps {
    /// What was read so far; complete once the iterator has ended.
    pub fn report(&self) -> &PcapReport {
        &self.report
    }

    /// Whether the source has ended and every sweep was taken: the report is complete.
    pub fn exhausted(&self) -> bool {
        self.finished && self.sink.done.is_empty()
    }

    fn feed(&mut self, d: pcap::Datagram) {
        let r = &mut self.report;
        if d.port != r.port {
            *r.other_ports.entry(d.port).or_insert(0) += 1;
            return;
        }
        if r.source.is_some_and(|s| s != d.source) {
            *r.other_sources.entry(d.source).or_insert(0) += 1;
            return;
        }
        r.on_port += 1;
        self.sink.capture_ns = d.time_ns;
        match self.decoder.push(&d.payload, &mut self.sink) {
            Ok(()) => {
                r.decoded += 1;
                if r.source.is_none() {
                    r.source = Some(d.source);
                    if let Decoder::Velodyne(v) = &self.decoder {
                        r.sensor = format!("Velodyne {:?}", v.model().unwrap_or(Model::Vlp16));
                    }
                }
            }
            Err(e) => *r.refused.entry(e.to_string()).or_insert(0) += 1,
        }
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
            return anyhow!(
                "{file}: no packets on port {} ({})",
                r.port,
                if ports.is_empty() {
                    "no UDP packets at all".to_string()
                } else {
                    format!("UDP seen: {}", ports.join(", "))
                }
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

impl Iterator for PcapSweeps {
    type Item = Result<Sweep>;

    fn next(&mut self) -> Option<Result<Sweep>> {
        loop {
            if let Some(s) = self.sink.done.pop_front() {
                return Some(Ok(s));
            }
            if self.finished {
                return None;
            }
            match self.capture.next_datagram() {
                Ok(Some(d)) => self.feed(d),
                Ok(None) => {
                    self.finished = true;
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
