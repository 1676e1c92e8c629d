//! Which decoder a recording gets: the one `--sensor` names, or the family its packets show
//! (a survey of the capture's first datagrams: Velodyne data packets by their length, Hesai by
//! their header on port 2368, Livox by their ports and lengths), with the files the model
//! needs (Ouster metadata, calibrations, angle correction files) read and checked first.

use super::identify::{family_of, Family};
use super::pcap::{self, Datagram, Record};
use super::sweeps::{
    sweeps, DatagramSource, Decoder, PcapSweeps, LIVOX2_PORT, LIVOX_PORT, OUSTER_IMU_PORT,
    OUSTER_PORT, VELODYNE_PORT,
};
use super::{hesai_at128, hesai_calib, ouster_meta, robosense_calib, velodyne_calib};
use crate::dataset::{SensorKind, SensorOptions};
use anyhow::{anyhow, bail, Result};
use kiss_odom_sensors::robosense;
use kiss_odom_sensors::velodyne::{self, Model};
use kiss_odom_sensors::{hesai, livox, ouster};
use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::path::{Path, PathBuf};

/// The first datagrams of a capture (up to any damage, which the decoding pass reports):
/// whole ones by port and length, the ports of damaged ones, and what the capture could not
/// hand on. A pcap is surveyed from its file; another recording of packets (a bag) hands its
/// own to [`decode_beside`].
#[derive(Clone, Debug, Default)]
pub struct Survey {
    seen: BTreeMap<(u16, usize), u64>,
    /// Hesai models of the packets on port 2368, by their first bytes
    /// ([`hesai::identify`]).
    hesai: BTreeMap<&'static str, (hesai::Model, u64)>,
    /// Robosense RS-M1 or E1R packets (by their length and first bytes), on any port.
    solid: BTreeMap<&'static str, (robosense::solid::Model, u64)>,
    /// Spinning Robosense packets of a layout only one model writes (the RS-Ruby's, the
    /// RS-Airy's; [`robosense::wire::model_of`]), on any port.
    robosense: BTreeMap<&'static str, (robosense::Model, u64)>,
    damaged: BTreeSet<u16>,
    notes: Vec<String>,
    records: usize,
}

impl Survey {
    /// How many records a survey looks at.
    pub const RECORDS: usize = 2000;

    /// Counts one record; false once the survey has seen enough.
    pub fn add(&mut self, record: &Record) -> bool {
        match record {
            Record::Datagram(d) => {
                *self.seen.entry((d.port, d.payload.len())).or_insert(0) += 1;
                if let (VELODYNE_PORT, Some(model)) = (d.port, hesai::identify(&d.payload)) {
                    self.hesai.entry(model.name()).or_insert((model, 0)).1 += 1;
                }
                if let Some(model) = robosense::solid::Model::of(&d.payload) {
                    self.solid.entry(model.name()).or_insert((model, 0)).1 += 1;
                }
                if let Some(model) = robosense::wire::model_of(&d.payload) {
                    self.robosense.entry(model.name()).or_insert((model, 0)).1 += 1;
                }
            }
            Record::Damaged { port, .. } => {
                self.damaged.insert(*port);
            }
        }
        self.records += 1;
        self.records < Self::RECORDS
    }
}

fn survey(path: &Path) -> Result<Survey> {
    let mut capture = pcap::open(path)?;
    let mut s = Survey::default();
    while let Ok(Some(record)) = capture.next_record() {
        if !s.add(&record) {
            break;
        }
    }
    s.notes = capture.counts().warnings();
    Ok(s)
}

/// What a recording other than a pcap knows beside its packets (a bag of packets).
#[derive(Default)]
pub struct Beside {
    /// Its first datagrams, for telling the sensor (a pcap is surveyed from its file).
    pub survey: Option<Survey>,
    /// The Ouster metadata it carries, and where (`--calibration` wins over it).
    pub ouster_meta: Option<(ouster_meta::OusterMeta, String)>,
    /// A device-information packet it carries (a Robosense DIFOP: the lasers' angles), and
    /// where (`--calibration` wins over it).
    pub device: Option<(Vec<u8>, String)>,
}

fn describe(s: &Survey) -> String {
    let mut text = if s.seen.is_empty() {
        "no UDP packets at all".to_string()
    } else {
        let list: Vec<_> = s
            .seen
            .iter()
            .map(|((p, l), n)| format!("{n} x {l} bytes on port {p}"))
            .collect();
        format!("UDP seen: {}", list.join(", "))
    };
    for n in &s.notes {
        text.push_str("; ");
        text.push_str(n);
    }
    text
}

/// Decodes the datagrams of `capture`, named `path` in messages; without `opts.port` a
/// Velodyne recording at `path` is looked at first, for an error that says what it holds.
pub fn decode(
    path: &Path,
    capture: Box<dyn DatagramSource>,
    opts: &SensorOptions,
) -> Result<PcapSweeps> {
    decode_beside(path, capture, opts, Beside::default())
}

/// [`decode`], for a recording that knows what `beside` says (a bag of packets).
pub fn decode_beside(
    path: &Path,
    capture: Box<dyn DatagramSource>,
    opts: &SensorOptions,
    beside: Beside,
) -> Result<PcapSweeps> {
    let Beside {
        survey: surveyed,
        ouster_meta: carried_meta,
        device,
    } = beside;
    let ouster = opts.meta.is_some() || carried_meta.is_some() || opts.sensor == SensorKind::Ouster;
    if ouster {
        let (meta, meta_path) = match (&opts.meta, carried_meta) {
            (Some(file), _) => (ouster_meta::read(file)?, file.display().to_string()),
            (None, Some(carried)) => carried,
            (None, None) => bail!(
                "{}: an Ouster recording needs the sensor's metadata JSON (--calibration)",
                path.display()
            ),
        };
        let dec = ouster::Decoder::new(&meta.info).map_err(|e| anyhow!("{meta_path}: {e}"))?;
        let port = opts.port.or(meta.udp_port_lidar).unwrap_or(OUSTER_PORT);
        let name = format!(
            "Ouster {} {} ({})",
            meta.prod_line, meta.serial, meta.firmware
        );
        let mut notes: Vec<String> = meta
            .warnings
            .iter()
            .map(|w| format!("{meta_path}: {w}"))
            .collect();
        notes.extend(unused(
            opts,
            "an Ouster",
            &[Unused::Calibration, Unused::CutAngle, Unused::FramePeriod],
        )?);
        let mut s = sweeps(
            path,
            capture,
            Decoder::Ouster(Box::new(dec)),
            opts,
            (port, name, notes),
        );
        s.imu_port = Some(meta.udp_port_imu.unwrap_or(OUSTER_IMU_PORT));
        s.meta_path = Some(PathBuf::from(meta_path));
        return Ok(s);
    }
    let mut capture = capture;
    if let (SensorKind::Auto, Some(port)) = (opts.sensor, opts.port) {
        let (ahead, family) = read_ahead(capture, port);
        let robosense_alike = |r: &Record| match r {
            Record::Datagram(d) => d.port == port && robosense_msop(&d.payload),
            Record::Damaged { .. } => false,
        };
        if family.is_none() && ahead.held.iter().any(robosense_alike) {
            return Err(robosense_unnamed(path));
        }
        capture = Box::new(ahead);
        match family {
            Some(Family::Hesai(model)) => {
                return hesai_decoder(path, capture, opts, model, port);
            }
            Some(Family::Livox(model)) => {
                return livox_decoder(path, capture, opts, model, Some(port));
            }
            Some(Family::Robosense(model)) => {
                return robosense_decoder(path, capture, opts, (model, device));
            }
            Some(Family::RobosenseSolid(model)) => {
                return solid_decoder(path, capture, opts, model);
            }
            Some(Family::Velodyne) | None => {}
        }
    }
    let (decoder, port, sensor) = {
        let model = match opts.sensor {
            SensorKind::Vlp16 => Some(Model::Vlp16),
            SensorKind::PuckHiRes => Some(Model::PuckHiRes),
            SensorKind::Vlp32c => Some(Model::Vlp32c),
            SensorKind::Hdl32e => Some(Model::Hdl32e),
            SensorKind::Vlp32ab => Some(Model::Vlp32ab),
            SensorKind::Hdl64eS2 => Some(Model::Hdl64eS2),
            SensorKind::Hdl64eS3 => Some(Model::Hdl64eS3),
            SensorKind::Vls128 => Some(Model::Vls128),
            _ => None,
        };
        if let Some(model) = livox_model(opts.sensor) {
            return livox_decoder(path, capture, opts, model, opts.port);
        }
        if let Some(model) = robosense_model(opts.sensor) {
            return robosense_decoder(path, capture, opts, (model, device));
        }
        if let Some(model) = solid_model(opts.sensor) {
            return solid_decoder(path, capture, opts, model);
        }
        let port = opts.port.unwrap_or(VELODYNE_PORT);
        let mut hesai = hesai_model(opts.sensor);
        if opts.port.is_none() && hesai.is_none() {
            let s = match surveyed {
                Some(s) => s,
                None => survey(path)?,
            };
            let data = s
                .seen
                .keys()
                .any(|(_, len)| *len == velodyne::wire::field::LEN)
                || s.damaged.contains(&port);
            let auto = !data && opts.sensor == SensorKind::Auto;
            hesai = if auto { hesai_in(&s) } else { None };
            if auto && hesai.is_none() && s.seen.keys().any(is_livox) {
                return livox_decoder(path, capture, opts, livox::Model::Horizon, None);
            }
            if auto && hesai.is_none() && s.seen.keys().any(is_livox2) {
                return livox_decoder(path, capture, opts, livox::Model::Mid360, None);
            }
            let solid = s.solid.values().max_by_key(|(_, n)| *n).map(|(m, _)| *m);
            if let (true, None, Some(model)) = (auto, hesai, solid) {
                return solid_decoder(path, capture, opts, model);
            }
            let spinning = s
                .robosense
                .values()
                .max_by_key(|(_, n)| *n)
                .map(|(m, _)| *m);
            if let (true, None, Some(model)) = (auto, hesai, spinning) {
                return robosense_decoder(path, capture, opts, (model, device));
            }
            if !data && hesai.is_none() {
                if s.seen.keys().any(|(p, _)| *p == OUSTER_PORT) {
                    bail!(
                        "{}: packets on port {OUSTER_PORT} look like an Ouster's: give its \
                         metadata JSON (--calibration)",
                        path.display()
                    );
                }
                if s.seen.keys().any(|(_, len)| *len == robosense::wire::LEN) {
                    return Err(robosense_unnamed(path));
                }
                bail!(
                    "{}: no Velodyne (1206 bytes), Hesai (EE FF on port 2368), Livox (ports \
                     56001, 56301) or Robosense RS-M1, E1R (55 AA 5A A5), Ruby or Airy data \
                     packets; {}",
                    path.display(),
                    describe(&s)
                );
            }
        }
        if let Some(model) = hesai {
            return hesai_decoder(path, capture, opts, model, port);
        }
        let calibration = opts
            .calibration
            .as_deref()
            .map(velodyne_calib::read)
            .transpose()?;
        if let Some(m) = model.filter(|m| m.needs_calibration() && calibration.is_none()) {
            bail!(
                "{}: a Velodyne {} needs the unit's calibration file (--calibration: Velodyne's \
                 XML or the ROS YAML)",
                path.display(),
                m.name()
            );
        }
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
    let notes = unused(opts, "a Velodyne", &[Unused::FramePeriod])?;
    Ok(sweeps(path, capture, decoder, opts, (port, sensor, notes)))
}

/// Whether `payload` is a spinning Robosense MSOP packet by its length and id.
fn robosense_msop(payload: &[u8]) -> bool {
    payload.len() == robosense::wire::LEN
        && robosense::Model::ALL
            .iter()
            .any(|m| payload.starts_with(m.layout().id))
}

/// The refusal of spinning Robosense packets that do not say which model sent them.
fn robosense_unnamed(path: &Path) -> anyhow::Error {
    anyhow!(
        "{}: {}-byte packets look like a spinning Robosense's, whose models send alike: name \
         it (--sensor rs16, rs32, bpearl, helios or helios16p; the Ruby and Airy are found by \
         their packets)",
        path.display(),
        robosense::wire::LEN
    )
}

/// The Hesai model most packets on port 2368 come from ([`hesai::identify`]). Protocol 1.4 is
/// taken for an OT128: the Pandar128 sends the same packets and differs in firing times only
/// (`--sensor pandar128`).
fn hesai_in(s: &Survey) -> Option<hesai::Model> {
    s.hesai.values().max_by_key(|(_, n)| *n).map(|(m, _)| *m)
}

/// The Hesai model `--sensor` names, if it names one.
fn hesai_model(sensor: SensorKind) -> Option<hesai::Model> {
    match sensor {
        SensorKind::Xt32 => Some(hesai::Model::Xt32),
        SensorKind::Qt128 => Some(hesai::Model::Qt128),
        SensorKind::Pandar128 => Some(hesai::Model::Pandar128),
        SensorKind::Ot128 => Some(hesai::Model::Ot128),
        SensorKind::Xt16 => Some(hesai::Model::Xt16),
        SensorKind::Xt32m => Some(hesai::Model::Xt32m),
        SensorKind::Pandar40p => Some(hesai::Model::Pandar40P),
        SensorKind::Pandar64 => Some(hesai::Model::Pandar64),
        SensorKind::Qt64 => Some(hesai::Model::PandarQT64),
        SensorKind::At128 => Some(hesai::Model::At128),
        _ => None,
    }
}

/// Whether packets of this port and length look like Livox SDK 1 point packets.
fn is_livox(&(port, len): &(u16, usize)) -> bool {
    port == LIVOX_PORT && (0..6).any(|t| livox::sdk1::packet_len(t) == Some(len))
}

/// Whether packets of this port and length look like Mid-360 (SDK 2) point packets.
fn is_livox2(&(port, len): &(u16, usize)) -> bool {
    port == LIVOX2_PORT
        && (1..4).any(|t| livox::sdk2::packet_len(t, livox::sdk2::MID360_POINTS) == Some(len))
}

/// The Livox model `--sensor` names, if it names one.
fn livox_model(sensor: SensorKind) -> Option<livox::Model> {
    match sensor {
        SensorKind::Livox => Some(livox::Model::Horizon),
        SensorKind::Mid40 => Some(livox::Model::Mid40),
        SensorKind::Mid360 => Some(livox::Model::Mid360),
        _ => None,
    }
}

/// The Livox decoder for `model`, on `port` or the model's default.
fn livox_decoder(
    path: &Path,
    capture: Box<dyn DatagramSource>,
    opts: &SensorOptions,
    model: livox::Model,
    port: Option<u16>,
) -> Result<PcapSweeps> {
    let (name, default_port) = match model {
        livox::Model::Mid40 => ("Livox Mid-40/70", LIVOX_PORT),
        livox::Model::Horizon => ("Livox Horizon/Tele-15/Avia", LIVOX_PORT),
        livox::Model::Mid360 => ("Livox Mid-360/HAP", LIVOX2_PORT),
    };
    let port = port.unwrap_or(default_port);
    let mut config = livox::Config {
        model,
        ..livox::Config::default()
    };
    if let Some(p) = opts.frame_period_s {
        if !(p.is_finite() && p > 0.0) {
            bail!("input.frame_period = {p}: give a positive number of seconds");
        }
        config.frame_period_ns = (p * 1e9).round() as u64;
    }
    let dec = livox::Decoder::new(config).map_err(|e| anyhow!("input.frame_period: {e}"))?;
    let decoder = Decoder::Livox(Box::new(dec));
    let notes = unused(opts, "a Livox", &[Unused::Calibration, Unused::CutAngle])?;
    Ok(sweeps(
        path,
        capture,
        decoder,
        opts,
        (port, name.to_string(), notes),
    ))
}

/// The Robosense model whose returns carry their directions that `--sensor` names.
fn solid_model(kind: SensorKind) -> Option<robosense::solid::Model> {
    match kind {
        SensorKind::M1 => Some(robosense::solid::Model::M1),
        SensorKind::E1r => Some(robosense::solid::Model::E1r),
        _ => None,
    }
}

/// A Robosense RS-M1 or E1R recording: MSOP packets on port 6699 unless `input.port` says.
fn solid_decoder(
    path: &Path,
    capture: Box<dyn DatagramSource>,
    opts: &SensorOptions,
    model: robosense::solid::Model,
) -> Result<PcapSweeps> {
    let port = opts.port.unwrap_or(robosense_calib::MSOP_PORT);
    let dec = Decoder::RobosenseSolid(Box::new(robosense::solid::Decoder::new(model)));
    let name = format!("Robosense {}", model.name());
    let all = [Unused::Calibration, Unused::CutAngle, Unused::FramePeriod];
    let notes = unused(opts, &format!("a Robosense {}", model.name()), &all)?;
    Ok(sweeps(path, capture, dec, opts, (port, name, notes)))
}

/// The Robosense model `--sensor` names.
fn robosense_model(kind: SensorKind) -> Option<robosense::Model> {
    Some(match kind {
        SensorKind::Rs16 => robosense::Model::Rs16,
        SensorKind::Rs32 => robosense::Model::Rs32,
        SensorKind::Bpearl => robosense::Model::Bpearl,
        SensorKind::Helios => robosense::Model::Helios,
        SensorKind::Helios16p => robosense::Model::Helios16p,
        SensorKind::Ruby => robosense::Model::Ruby,
        SensorKind::Airy => robosense::Model::Airy,
        _ => return None,
    })
}

/// A Robosense recording: MSOP packets on port 6699, the angles from `--calibration`
/// (`angle.csv`) or the recording's first DIFOP packet; without either, exit with both named.
fn robosense_decoder(
    path: &Path,
    capture: Box<dyn DatagramSource>,
    opts: &SensorOptions,
    (model, device): (robosense::Model, Option<(Vec<u8>, String)>),
) -> Result<PcapSweeps> {
    // A bag carries the DIFOP packet on a topic of its own; a pcap is searched for it.
    let carried =
        device.map(
            |(payload, from)| match robosense_calib::from_payload(&payload, model) {
                Some(angles) => angles.map_err(|e| anyhow!("{from}: {e}")),
                None => Err(anyhow!("{from}: not a DIFOP packet")),
            },
        );
    let calibration = match (opts.calibration.as_deref(), carried) {
        (Some(csv), _) => robosense_calib::read(csv, model)?,
        (None, Some(angles)) => angles?,
        (None, None) => match path
            .is_file()
            .then(|| robosense_calib::from_capture(path, model))
            .transpose()?
            .flatten()
        {
            Some(c) => c,
            None => bail!(
                "{}: a {} needs its laser angles: the recording has no DIFOP packet (port \
                 {}); give the unit's angle.csv with --calibration",
                path.display(),
                model.name(),
                robosense_calib::DIFOP_PORT
            ),
        },
    };
    let config = robosense::Config {
        model,
        calibration: Some(calibration),
        cut_angle_deg: opts.cut_angle_deg,
    };
    let dec = robosense::Decoder::new(config).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    let notes = unused(opts, "a Robosense", &[Unused::FramePeriod])?;
    let port = opts.port.unwrap_or(robosense_calib::MSOP_PORT);
    Ok(sweeps(
        path,
        capture,
        Decoder::Robosense(Box::new(dec)),
        opts,
        (port, format!("Robosense {}", model.name()), notes),
    ))
}

/// The Hesai decoder for `model`, with the angle correction file if one is given (the
/// 128-channel models need one).
fn hesai_decoder(
    path: &Path,
    capture: Box<dyn DatagramSource>,
    opts: &SensorOptions,
    model: hesai::Model,
    port: u16,
) -> Result<PcapSweeps> {
    if model == hesai::Model::At128 {
        return at128_decoder(path, capture, opts, port);
    }
    let calibration = match opts.calibration.as_deref() {
        Some(csv) => Some(hesai_calib::read(csv, model.channels())?),
        None if model.nominal_calibration().is_none() => bail!(
            "{}: packets of a {}: give its angle correction file (the CSV Hesai ships with \
             the sensor) with --calibration",
            path.display(),
            model.name()
        ),
        None => None,
    };
    let config = hesai::Config {
        model,
        calibration,
        cut_angle_deg: opts.cut_angle_deg,
    };
    let dec = hesai::Decoder::new(config).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    let sensor = model.name().to_string();
    let decoder = Decoder::Hesai(Box::new(dec));
    let notes = unused(opts, "a Hesai", &[Unused::FramePeriod])?;
    Ok(sweeps(path, capture, decoder, opts, (port, sensor, notes)))
}

/// The PandarAT128 decoder with its angle correction file (`.dat`, [`hesai_at128`]).
fn at128_decoder(
    path: &Path,
    capture: Box<dyn DatagramSource>,
    opts: &SensorOptions,
    port: u16,
) -> Result<PcapSweeps> {
    let name = hesai::Model::At128.name();
    let Some(dat) = opts.calibration.as_deref() else {
        bail!(
            "{}: packets of a {name}: give its angle correction file (the .dat the sensor \
             hands out and Hesai ships) with --calibration",
            path.display()
        );
    };
    if opts.cut_angle_deg.is_some() {
        bail!(
            "{}: packets of a {name}: its sweeps are its mirror frames, so input.cut_angle does not \
             apply",
            path.display()
        );
    }
    let correction = hesai_at128::read(dat)?;
    let notes = unused(opts, "a Hesai", &[Unused::FramePeriod])?;
    let dec = hesai::Decoder::at128(&correction).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    Ok(sweeps(
        path,
        capture,
        Decoder::HesaiAt128(Box::new(dec)),
        opts,
        (port, name.to_string(), notes),
    ))
}

/// Datagrams read ahead on the decoded port before the family is taken for a Velodyne's.
const READ_AHEAD: usize = 64;

/// A source whose first records were read ahead, to see which sensor sends them, and are
/// handed on first (an error met then comes after them).
struct ReadAhead {
    held: VecDeque<Record>,
    error: Option<anyhow::Error>,
    rest: Box<dyn DatagramSource>,
}

impl DatagramSource for ReadAhead {
    fn next_datagram(&mut self) -> Result<Option<Datagram>> {
        while let Some(r) = self.held.pop_front() {
            if let Record::Datagram(d) = r {
                return Ok(Some(d));
            }
        }
        self.next_record().map(|r| match r {
            Some(Record::Datagram(d)) => Some(d),
            _ => None,
        })
    }
    fn next_record(&mut self) -> Result<Option<Record>> {
        if let Some(r) = self.held.pop_front() {
            return Ok(Some(r));
        }
        match self.error.take() {
            Some(e) => Err(e),
            None => self.rest.next_record(),
        }
    }
    fn warnings(&self) -> Vec<String> {
        self.rest.warnings()
    }
}

/// Reads `capture` up to the first datagram on `port` whose bytes name a sensor family
/// ([`family_of`]), or [`READ_AHEAD`] datagrams on the port: `auto` on a given port (and
/// `live`, which listens on one) decodes what the packets are, not a Velodyne's by default.
fn read_ahead(mut rest: Box<dyn DatagramSource>, port: u16) -> (ReadAhead, Option<Family>) {
    let (mut held, mut on_port, mut error) = (VecDeque::new(), 0, None);
    let mut family = None;
    while on_port < READ_AHEAD && family.is_none() {
        match rest.next_record() {
            Ok(Some(r)) => {
                if let Record::Datagram(d) = &r {
                    if d.port == port {
                        on_port += 1;
                        family = family_of(&d.payload);
                    }
                }
                held.push_back(r);
            }
            Ok(None) => break,
            Err(e) => {
                error = Some(e);
                break;
            }
        }
    }
    (ReadAhead { held, error, rest }, family)
}

/// A sensor option the decoder chosen does not use.
#[derive(Clone, Copy)]
enum Unused {
    Calibration,
    CutAngle,
    FramePeriod,
}

/// A warning for each option in `which` that was given, naming it and why `sensor` (e.g. "a
/// Livox") does not use it; a calibration file that does not exist is an error, as it would
/// be for a sensor that reads one.
fn unused(opts: &SensorOptions, sensor: &str, which: &[Unused]) -> Result<Vec<String>> {
    let mut notes = Vec::new();
    for u in which {
        match u {
            Unused::Calibration => {
                if let Some(file) = &opts.calibration {
                    if !file.is_file() {
                        bail!(
                            "--calibration {}: no such file (and {sensor} recording does not \
                             use one)",
                            file.display()
                        );
                    }
                    notes.push(format!(
                        "--calibration {} not used: {sensor} recording needs no calibration \
                         file",
                        file.display()
                    ));
                }
            }
            Unused::CutAngle => {
                if let Some(a) = opts.cut_angle_deg {
                    notes.push(format!(
                        "input.cut_angle = {a} not used: {sensor} recording's frames are not cut by \
                         azimuth"
                    ));
                }
            }
            Unused::FramePeriod => {
                if let Some(p) = opts.frame_period_s {
                    notes.push(format!(
                        "input.frame_period = {p} not used: only a Livox sensor's frames are cut by \
                         time; {sensor} sensor's packets mark where its sweeps end"
                    ));
                }
            }
        }
    }
    Ok(notes)
}

#[cfg(test)]
mod tests;
