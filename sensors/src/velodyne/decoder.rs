//! Velodyne packets to sweeps: checks, time unwrapping, loss and order detection, the cut,
//! then each return to a point.

use super::calibration::{Config, Laser};
use super::layout::{single_return, Blocks, Layout};
use super::model::{Model, BANK_FLAGS, MAX_LASERS};
use super::point::{interpolate, Beam, Gap};
use super::wire::{Packet, HOUR_US, UNUSED_FLAG};
use crate::error::{ConfigError, PacketError};
use crate::sweep::{
    lost_in_step, wrap_azimuth as wrap, Assembly, AzimuthCut, Decode, PointMeta, Pushed, Return,
    SweepEnd, SweepSink, SweepStats, RESYNC_PACKETS,
};

/// A sweep whose packets span more than this (sensor time) ends and the next packet begins a
/// new one: the sensor stopped, or the recording has a hole (velodyne-decoder's 0.3 s).
pub const GAP_NS: u64 = 300_000_000;

const GAP_US: i64 = (GAP_NS / 1000) as i64;
const HALF_HOUR_US: i64 = HOUR_US as i64 / 2;

/// How the sensor fires: fixed by the first packet decoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Single(Return),
    Dual,
}

/// The sensor's tables, built once its model and return mode are known.
#[derive(Clone, Debug)]
struct Sensor {
    model: Model,
    mode: Mode,
    layout: Layout,
    /// The first packet's return-mode and product bytes: later packets with others are
    /// another sensor's (not checked on the HDL-64E, whose two bytes are a cycling status).
    mode_byte: u8,
    product_byte: u8,
    resolution: f64,
}

/// The lasers, ready to use: from the calibration file when the decoder is made, or the
/// model's nominal ones once a packet names it. Kept instead of the [`Calibration`] itself.
struct Beams {
    beams: [Beam; MAX_LASERS],
    /// Lasers set; 0 until known.
    count: usize,
    /// Metres per distance unit.
    resolution: f64,
}

impl Beams {
    const NONE: Self = Self {
        beams: [Beam::ZERO; MAX_LASERS],
        count: 0,
        resolution: 0.0,
    };

    /// Beams of `count` lasers, laser `i` being `laser(i)`.
    fn set(&mut self, count: usize, resolution: f64, laser: impl Fn(usize) -> Laser) {
        let count = count.min(MAX_LASERS);
        for (i, b) in self.beams.iter_mut().enumerate().take(count) {
            *b = Beam::new(&laser(i));
        }
        // Rings count up from the lowest laser; ties keep firing order.
        for i in 0..count {
            let v = laser(i).vertical_deg;
            let below = (0..count)
                .filter(|&j| {
                    let w = laser(j).vertical_deg;
                    w < v || (w == v && j < i)
                })
                .count();
            self.beams[i].ring = below as u16;
        }
        self.count = count;
        self.resolution = resolution;
    }
}

impl Sensor {
    fn new(model: Model, mode: Mode, bytes: (u8, u8), file_resolution: f64) -> Self {
        let (mode_byte, product_byte) = bytes;
        Self {
            model,
            mode,
            layout: Layout {
                model,
                dual: mode == Mode::Dual,
            },
            mode_byte,
            product_byte,
            // The VLS-128 counts 4 mm (manual 63-9483 section 9.3.1.3) whatever a calibration
            // file says: the ROS driver and nebula ignore the YAML's `distance_resolution` for
            // it too (nebula's VLS128.yaml has 0.007).
            resolution: if model == Model::Vls128 {
                model.distance_resolution_m()
            } else {
                file_resolution
            },
        }
    }

    /// Microseconds from one packet to the next.
    fn packet_us(&self) -> f64 {
        self.layout.packet_us()
    }

    /// Whether every block the layout reads carries its bank's flag: a packet of another
    /// model (an HDL-64E's upper/lower pairs, a VLS-128's four banks) does not.
    fn flags_match(&self, p: &Packet<'_>) -> Result<(), PacketError> {
        let l = self.layout;
        for g in 0..l.groups() {
            for b in 0..self.model.banks() {
                let want = BANK_FLAGS.get(b).copied().unwrap_or(0);
                let (k0, k1) = match l.blocks(g, b) {
                    Blocks::Single(k) => (k, k),
                    Blocks::Dual { last, strongest } => (last, strongest),
                };
                for k in [k0, k1] {
                    match p.flag(k) {
                        f if f == want => {}
                        // An unused block where this layout reads one: not this model's packet.
                        f if BANK_FLAGS.contains(&f) || f == UNUSED_FLAG => {
                            return Err(PacketError::OtherSensor)
                        }
                        _ => return Err(PacketError::BlockFlag),
                    }
                }
            }
        }
        Ok(())
    }

    /// Azimuths of the packet's first and last firing groups.
    fn azimuth_span(&self, p: &Packet<'_>) -> (u16, u16) {
        let l = self.layout;
        let at = |g: usize| l.group_block(g).map_or(0, |k| p.azimuth(k));
        (at(0), at(l.groups().saturating_sub(1)))
    }
}

/// The HDL-64E's return mode, from its azimuths (it has no mode byte): in dual-return mode
/// each firing's two upper/lower pairs repeat one azimuth (velodyne-decoder's test).
fn hdl64e_mode(p: &Packet<'_>) -> Mode {
    if p.azimuth(0) == p.azimuth(2) {
        Mode::Dual
    } else {
        Mode::Single(Return::Strongest)
    }
}

/// The mode a return-mode byte names, `None` for a byte no model writes.
fn mode_of(byte: u8, product: u8) -> Option<Mode> {
    match (single_return(byte), byte) {
        (Some(r), _) => Some(Mode::Single(r)),
        (None, 0x39) => Some(Mode::Dual),
        // Old HDL-32E firmware writes neither byte; it fires strongest-return only.
        (None, 0) if product == 0 => Some(Mode::Single(Return::Strongest)),
        _ => None,
    }
}

/// Velodyne packets in, sweeps out (see the module doc of [`crate::velodyne`]).
///
/// ```
/// use kiss_odom_sensors::{velodyne, Chunk, Decode, SweepSink, SweepStart, SweepStats};
/// struct Count(usize);
/// impl SweepSink for Count {
///     fn begin_sweep(&mut self, _: &SweepStart) {}
///     fn points(&mut self, c: Chunk<'_>) { self.0 += c.xyz.len(); }
///     fn end_sweep(&mut self, _: &SweepStats) {}
/// }
/// let mut dec = velodyne::Decoder::new(velodyne::Config::default()).unwrap();
/// let mut sink = Count(0);
/// // A 1206-byte payload from UDP port 2368; anything else is refused with a reason.
/// assert!(dec.push(&[0u8; 100], &mut sink).is_err());
/// dec.finish(&mut sink);
/// ```
pub struct Decoder {
    config_model: Option<Model>,
    beams: Beams,
    sensor: Option<Sensor>,
    /// Sensor time of the last packet accepted, microseconds, counted on across hours.
    last_us: Option<i64>,
    last_azimuth: u16,
    /// Where sweeps end.
    cut: AzimuthCut,
    sweep_first_us: i64,
    next_column: u16,
    /// Shortest time between consecutive packets seen, microseconds.
    shortest_step_us: Option<i64>,
    /// Consecutive late packets and the last one's timestamp (microseconds past the hour).
    late_run: Option<(u32, u32)>,
    asm: Assembly,
}

impl Decoder {
    /// A decoder for `config`; nothing is decoded until the first packet.
    pub fn new(config: Config) -> Result<Self, ConfigError> {
        match (&config.calibration, config.model) {
            (Some(c), m) => {
                c.validate()?;
                if m.is_some_and(|m| m.lasers() != c.lasers.len()) {
                    return Err(ConfigError::Calibration);
                }
            }
            (None, Some(m)) if m.needs_calibration() => return Err(ConfigError::Calibration),
            (None, _) => {}
        }
        let cut = AzimuthCut::new(config.cut_angle_deg)?;
        let mut beams = Beams::NONE;
        if let Some(c) = &config.calibration {
            let at = |i: usize| c.lasers.get(i).copied().unwrap_or_default();
            beams.set(c.lasers.len(), c.distance_resolution_m, at);
        }
        Ok(Self {
            config_model: config.model,
            beams,
            sensor: None,
            last_us: None,
            last_azimuth: 0,
            cut,
            sweep_first_us: 0,
            next_column: 0,
            shortest_step_us: None,
            late_run: None,
            asm: Assembly::new(),
        })
    }

    /// Time from one packet to the next as the model fires, microseconds (once a packet told
    /// the return mode).
    pub fn packet_us(&self) -> Option<f64> {
        self.sensor.as_ref().map(Sensor::packet_us)
    }

    /// The shortest time between consecutive packets seen, microseconds: the model's
    /// [`Self::packet_us`] unless the packets come from another model or many are lost.
    pub fn shortest_step_us(&self) -> Option<u32> {
        self.shortest_step_us
            .map(|s| s.clamp(0, i64::from(u32::MAX)) as u32)
    }

    /// The period losses are counted by: the model's, unless the packets never come that
    /// close or always come closer (a product byte naming another model), when their own
    /// shortest spacing is what a step of one packet looks like.
    fn loss_period_us(&self, model_us: f64) -> f64 {
        match self.shortest_step_us {
            Some(s) if (s as f64) > 1.5 * model_us || (s as f64) < model_us / 1.5 => s as f64,
            _ => model_us,
        }
    }

    /// Counts a packet older than the sweep; true when it is the [`RESYNC_PACKETS`]-th in a
    /// row whose timestamps move on from one to the next as a sensor's do (within
    /// [`GAP_NS`]): their clock is the sensor's now.
    fn late_run_complete(&mut self, ts: u32) -> bool {
        let n = match self.late_run {
            Some((n, last)) => {
                let d = wrap_us(i64::from(ts) - i64::from(last));
                if d > 0 && d <= GAP_US {
                    n + 1
                } else {
                    1
                }
            }
            None => 1,
        };
        self.late_run = Some((n, ts));
        n >= RESYNC_PACKETS
    }

    /// Abandons the open sweep's clock; true if a sweep was open and has ended.
    fn resync<S: SweepSink>(&mut self, sink: &mut S) -> bool {
        self.late_run = None;
        self.last_us = None;
        self.shortest_step_us = None;
        let open = self.asm.open.is_some();
        self.asm.end(sink, SweepEnd::Resync);
        self.cut.restart(None);
        self.asm.resynced();
        open
    }

    /// The model, once a packet has been decoded or if configured.
    pub fn model(&self) -> Option<Model> {
        self.sensor.as_ref().map(|s| s.model).or(self.config_model)
    }

    fn identify(&mut self, p: &Packet<'_>) -> Result<(), PacketError> {
        let product = p.product();
        let byte = p.return_mode();
        if let Some(s) = &self.sensor {
            s.flags_match(p)?;
            // Blocks laid out as the model's (not an HDL-64E's, whose two bytes are a status):
            // a byte no model writes is corrupted, not another sensor's. Product 0 is old
            // HDL-32E firmware's.
            if s.model.has_mode_byte() {
                let known = product == 0 || Model::from_product(product).is_some();
                if product != s.product_byte && !known {
                    return Err(PacketError::UnknownModel);
                }
                if byte != s.mode_byte && mode_of(byte, product).is_none() {
                    return Err(PacketError::UnknownReturnMode);
                }
            }
            let bytes_match =
                !s.model.has_mode_byte() || (product == s.product_byte && byte == s.mode_byte);
            let mode_match = s.model.has_mode_byte() || hdl64e_mode(p) == s.mode;
            if !(bytes_match && mode_match) {
                return Err(PacketError::OtherSensor);
            }
            return Ok(());
        }
        // A configured model overrides the product byte (which some units get wrong).
        let model = match self.config_model {
            Some(m) => m,
            None => Model::from_product(product).ok_or(PacketError::UnknownModel)?,
        };
        let mode = if model.has_mode_byte() {
            mode_of(byte, product).ok_or(PacketError::UnknownReturnMode)?
        } else {
            hdl64e_mode(p)
        };
        match self.beams.count {
            0 if model.needs_calibration() => return Err(PacketError::NoCalibration),
            0 => {
                let nominal = |i: usize| Laser {
                    vertical_deg: model.vertical_deg().get(i).copied().unwrap_or(0.0),
                    azimuth_offset_deg: model.azimuth_offset_deg(i),
                    vertical_offset_m: model.vertical_offset_m(i),
                    ..Laser::default()
                };
                let resolution = model.distance_resolution_m();
                self.beams.set(model.lasers(), resolution, nominal);
            }
            n if n != model.lasers() => return Err(PacketError::OtherSensor),
            _ => {}
        }
        let sensor = Sensor::new(model, mode, (byte, product), self.beams.resolution);
        sensor.flags_match(p)?;
        self.sensor = Some(sensor);
        Ok(())
    }

    fn accept<S: SweepSink>(&mut self, bytes: &[u8], sink: &mut S) -> Result<Pushed, PacketError> {
        let p = Packet::new_checked(bytes)?;
        self.identify(&p)?;

        // Sensor time, counted on across the hour; anything not after the last packet is late.
        let raw = p.timestamp_us();
        let ts = i64::from(raw);
        let (now, step) = match self.last_us {
            None => (ts, None),
            Some(last) => {
                let d = wrap_us(ts - last.rem_euclid(i64::from(HOUR_US)));
                if d <= 0 {
                    if !self.late_run_complete(raw) {
                        return Err(PacketError::Late);
                    }
                    if self.resync(sink) {
                        return Ok(Pushed::Again);
                    }
                    (ts, None)
                } else {
                    (last + d, Some(d))
                }
            }
        };
        self.late_run = None;
        let Some(sensor) = &self.sensor else {
            return Err(PacketError::UnknownModel);
        };
        if let Some(d) = step.filter(|&d| d <= GAP_US) {
            self.shortest_step_us = Some(self.shortest_step_us.map_or(d, |s| s.min(d)));
        }
        let period = self.loss_period_us(sensor.packet_us());
        let (first_az, last_az) = sensor.azimuth_span(&p);
        let groups = sensor.layout.groups();

        if self.asm.open.is_some() && now - self.sweep_first_us > GAP_US {
            self.asm.end(sink, SweepEnd::Gap);
            self.cut.restart(Some(self.last_azimuth));
            return Ok(Pushed::Again);
        }
        if self.asm.open.is_none() {
            // The sweep's time origin is its first packet's first firing.
            let lead_ns = libm::round(sensor.model.stamp_lead_us() * 1e3) as u64;
            let start_ns = (now as u64).saturating_mul(1000).saturating_sub(lead_ns);
            self.asm.begin(sink, start_ns, None);
            self.sweep_first_us = now;
            self.next_column = 0;
        }

        // Losses from the time step; azimuth jumps the time step does not explain.
        let mut lost = 0;
        let mut jump = false;
        if let Some(d) = step {
            lost = lost_in_step(d as f64, period);
            if lost == 0 {
                let span = wrap(i32::from(last_az) - i32::from(first_az));
                let block_step = (span / groups.saturating_sub(1).max(1) as u32).max(1);
                let advance = wrap(i32::from(first_az) - i32::from(self.last_azimuth));
                jump = advance > 3 * block_step + 10;
            }
        }
        let rel_s = (now - self.sweep_first_us) as f64 * 1e-6;
        let previous = (step.is_some() && lost == 0).then_some(self.last_azimuth);
        self.decode(&p, rel_s, previous, sink);
        let stats = self.asm.stats();
        stats.packets = stats.packets.saturating_add(1);
        stats.lost_packets = stats.lost_packets.saturating_add(lost);
        stats.azimuth_jumps = stats.azimuth_jumps.saturating_add(u32::from(jump));
        self.last_us = Some(now);
        self.last_azimuth = last_az;

        // The cut: the sweep ends with the packet whose last azimuth wraps past the start.
        if self.cut.passed(last_az) {
            self.asm.end(sink, SweepEnd::Complete);
            self.cut.restart(Some(last_az));
            return Ok(Pushed::Ended);
        }
        Ok(Pushed::Decoded)
    }

    /// Every return of a checked packet of the identified sensor.
    fn decode<S: SweepSink>(
        &mut self,
        p: &Packet<'_>,
        rel_s: f64,
        previous: Option<u16>,
        sink: &mut S,
    ) {
        let Some(sensor) = &self.sensor else { return };
        let l = sensor.layout;
        let model = sensor.model;
        let (_, group_ticks) = model.ticks();
        let sixteen = model.lasers() == 16;
        let columns_per_group: u16 = if sixteen { 2 } else { 1 };
        let mut column = self.next_column;
        let mut last_column = None;
        let groups = l.groups();
        // The packet's mean step, for its last group; a packet of one group (VLS-128 dual
        // return) steps from the previous packet's, if it came just before.
        let (first_az, last_az) = sensor.azimuth_span(p);
        let mean = if groups > 1 {
            Gap {
                turn: wrap(i32::from(last_az) - i32::from(first_az)),
                groups: (groups - 1) as u32,
            }
        } else {
            Gap {
                turn: previous.map_or(0, |a| wrap(i32::from(first_az) - i32::from(a))),
                groups: 1,
            }
        };
        for g in 0..l.groups() {
            let base_az = l.group_block(g).map_or(0, |k| p.azimuth(k));
            // The manuals' precision azimuth (VLP-16 63-9243, VLP-32C 63-9325 and VLS-128
            // 63-9483, section 9.5): the rotation from this firing group's azimuth to the next
            // group's, spread over the group's firing time. The last group's next azimuth is
            // in the next packet: it takes the packet's mean step (within a hundredth of a
            // degree of the manual's, half the quantisation of a single step).
            let gap = match l.group_block(g + 1) {
                Some(next) => Gap {
                    turn: wrap(i32::from(p.azimuth(next)) - i32::from(base_az)),
                    groups: 1,
                },
                None => mean,
            };
            for b in 0..model.banks() {
                let (first_block, second_block) = match l.blocks(g, b) {
                    Blocks::Single(k) => (k, None),
                    Blocks::Dual { last, strongest } => (last, Some(strongest)),
                };
                let block_az = p.azimuth(first_block);
                for c in 0..32 {
                    let first = p.channel(first_block, c);
                    let second = second_block.map_or((0, 0), |k| p.channel(k, c));
                    if first.0 == 0 && second.0 == 0 {
                        continue;
                    }
                    let az = interpolate(block_az, gap, model.firing_ticks(b, c), group_ticks);
                    let (laser, col) = if sixteen && c >= 16 {
                        (c - 16, column.wrapping_add(1))
                    } else {
                        (32 * b + c, column)
                    };
                    let Some(beam) = self.beams.beams.get(laser) else {
                        continue;
                    };
                    let time = rel_s + model.firing_s(g, b, c);
                    let mut emit = |raw: (u16, u8), ret| {
                        let meta = PointMeta {
                            ring: beam.ring,
                            column: col,
                            ret,
                            intensity: u16::from(raw.1),
                        };
                        let xyz = beam.point(sensor.resolution, raw.0, az);
                        self.asm.push(sink, xyz, time, meta);
                        last_column = Some(col);
                    };
                    match sensor.mode {
                        Mode::Single(ret) => emit(first, ret),
                        // In a dual pair one block holds the last return, the other the
                        // strongest; one point when they coincide.
                        Mode::Dual if first.0 == second.0 => emit(second, Return::Both),
                        Mode::Dual => {
                            if first.0 != 0 {
                                emit(first, Return::Last);
                            }
                            if second.0 != 0 {
                                emit(second, Return::Strongest);
                            }
                        }
                    }
                }
            }
            column = column.wrapping_add(columns_per_group);
        }
        // Columns continue from the last point's (velodyne-decoder's numbering).
        if let Some(c) = last_column {
            self.next_column = c.wrapping_add(1);
        }
    }
}

impl Decode for Decoder {
    fn push<S: SweepSink>(&mut self, bytes: &[u8], sink: &mut S) -> Result<Pushed, PacketError> {
        let r = self.accept(bytes, sink);
        self.asm.counted(r)
    }
    fn finish<S: SweepSink>(&mut self, sink: &mut S) {
        self.asm.end(sink, SweepEnd::Finished);
    }
    fn between_sweeps(&self) -> &SweepStats {
        &self.asm.pending
    }
}

/// A time step in microseconds taken to the nearest of its values modulo an hour (the
/// timestamp counts microseconds past the hour).
fn wrap_us(d: i64) -> i64 {
    let hour = i64::from(HOUR_US);
    let mut d = d.rem_euclid(hour);
    if d > HALF_HOUR_US {
        d -= hour;
    }
    d
}
