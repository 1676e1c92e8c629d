//! Velodyne packets to sweeps: checks, time unwrapping, loss and order detection, the cut,
//! then each return to a point.

use super::model::{Calibration, Config, Model, MAX_LASERS};
use super::wire::{field, Packet, AZIMUTH_UNITS, HOUR_US};
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

/// One laser, ready to use.
#[derive(Clone, Copy, Debug, Default)]
struct Beam {
    cos_v: f64,
    sin_v: f64,
    offset_deg: f64,
    distance_offset: f64,
    vertical_offset: f64,
    horizontal_offset: f64,
    ring: u16,
}

/// The sensor's tables, built once its model is known.
#[derive(Clone, Debug)]
struct Sensor {
    model: Model,
    mode: Mode,
    mode_byte: u8,
    /// The first packet's product byte: later packets with another are another sensor's.
    product_byte: u8,
    beams: [Beam; MAX_LASERS],
    resolution: f64,
    /// Firing times after the packet timestamp (s), in f32 as velodyne-decoder interpolates
    /// azimuths with them; `[group][channel]`.
    firing_f32: [[f32; field::CHANNELS]; field::BLOCKS],
}

impl Sensor {
    fn new(model: Model, mode: Mode, bytes: (u8, u8), calib: &Calibration) -> Self {
        let (mode_byte, product_byte) = bytes;
        let mut beams = [Beam::default(); MAX_LASERS];
        for (b, l) in beams.iter_mut().zip(calib.lasers.iter()) {
            let v = l.vertical_deg.to_radians();
            *b = Beam {
                cos_v: libm::cos(v),
                sin_v: libm::sin(v),
                offset_deg: l.azimuth_offset_deg,
                distance_offset: l.distance_offset_m,
                vertical_offset: l.vertical_offset_m,
                horizontal_offset: l.horizontal_offset_m,
                ring: 0,
            };
        }
        // Rings count up from the lowest laser; ties keep firing order.
        let lasers = &calib.lasers;
        for (i, (b, l)) in beams.iter_mut().zip(lasers.iter()).enumerate() {
            let below = lasers
                .iter()
                .enumerate()
                .filter(|&(j, m)| {
                    m.vertical_deg < l.vertical_deg || (m.vertical_deg == l.vertical_deg && j < i)
                })
                .count();
            b.ring = below as u16;
        }
        let mut firing_f32 = [[0.0f32; field::CHANNELS]; field::BLOCKS];
        for (g, row) in firing_f32.iter_mut().enumerate() {
            for (c, t) in row.iter_mut().enumerate() {
                *t = model.firing_time_s(g, c) as f32;
            }
        }
        Self {
            model,
            mode,
            mode_byte,
            product_byte,
            beams,
            resolution: calib.distance_resolution_m,
            firing_f32,
        }
    }

    fn firing_f32(&self, g: usize, c: usize) -> f32 {
        self.firing_f32
            .get(g)
            .and_then(|r| r.get(c))
            .copied()
            .unwrap_or(0.0)
    }

    /// Microseconds from one packet to the next.
    fn packet_us(&self) -> f64 {
        self.model.packet_us(self.mode == Mode::Dual)
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
    calibration: Option<Calibration>,
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
        if let Some(c) = &config.calibration {
            c.validate()?;
            if config.model.is_some_and(|m| m.lasers() != c.lasers.len()) {
                return Err(ConfigError::Calibration);
            }
        }
        let cut = AzimuthCut::new(config.cut_angle_deg)?;
        Ok(Self {
            config_model: config.model,
            calibration: config.calibration,
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
            return if product == s.product_byte && byte == s.mode_byte {
                Ok(())
            } else {
                Err(PacketError::OtherSensor)
            };
        }
        // A configured model overrides the product byte (which some units get wrong).
        let model = match self.config_model {
            Some(m) => m,
            None => Model::from_product(product).ok_or(PacketError::UnknownModel)?,
        };
        let mode = match byte {
            0x37 => Mode::Single(Return::Strongest),
            0x38 => Mode::Single(Return::Last),
            0x39 => Mode::Dual,
            // Old HDL-32E firmware writes neither byte; it fires strongest-return only.
            0 if product == 0 => Mode::Single(Return::Strongest),
            _ => return Err(PacketError::UnknownReturnMode),
        };
        let calib = match &self.calibration {
            Some(c) if c.lasers.len() != model.lasers() => return Err(PacketError::OtherSensor),
            Some(c) => c.clone(),
            None => Calibration::nominal(model),
        };
        self.sensor = Some(Sensor::new(model, mode, (byte, product), &calib));
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
        let first_az = p.azimuth(0);
        let last_az = p.azimuth(field::BLOCKS - 1);

        if self.asm.open.is_some() && now - self.sweep_first_us > GAP_US {
            self.asm.end(sink, SweepEnd::Gap);
            self.cut.restart(Some(self.last_azimuth));
            return Ok(Pushed::Again);
        }
        if self.asm.open.is_none() {
            self.asm
                .begin(sink, (now as u64).saturating_mul(1000), None);
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
                let blocks = match sensor.mode {
                    Mode::Single(_) => field::BLOCKS - 1,
                    Mode::Dual => field::BLOCKS / 2 - 1,
                };
                let block_step = (span / blocks as u32).max(1);
                let advance = wrap(i32::from(first_az) - i32::from(self.last_azimuth));
                jump = advance > 3 * block_step + 10;
            }
        }
        let rel_s = (now - self.sweep_first_us) as f64 * 1e-6;
        self.decode(&p, rel_s, sink);
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
    fn decode<S: SweepSink>(&mut self, p: &Packet<'_>, rel_s: f64, sink: &mut S) {
        let Some(sensor) = &self.sensor else { return };
        let dual = sensor.mode == Mode::Dual;
        let (step, groups) = if dual {
            (2, field::BLOCKS / 2)
        } else {
            (1, field::BLOCKS)
        };
        // Rotation rate over the packet, in f32 as velodyne-decoder computes it.
        let span = wrap(i32::from(p.azimuth(field::BLOCKS - 1)) - i32::from(p.azimuth(0)));
        let duration = sensor.firing_f32(groups - 1, 0) - sensor.firing_f32(0, 0);
        let rate = span as f32 / duration;
        let columns_per_block: u16 = if sensor.model.lasers() == 16 { 2 } else { 1 };
        let mut column = self.next_column;
        let mut last_column = None;
        for g in 0..groups {
            let block = g * step;
            let block_az = p.azimuth(block);
            let t0 = sensor.firing_f32(g, 0);
            for c in 0..field::CHANNELS {
                let first = p.channel(block, c);
                let second = if dual {
                    p.channel(block + 1, c)
                } else {
                    (0, 0)
                };
                if first.0 == 0 && second.0 == 0 {
                    continue;
                }
                let t = sensor.firing_f32(g, c);
                let az = interpolate(block_az, rate, t - t0);
                let (laser, col) = if columns_per_block == 2 && c >= 16 {
                    (c - 16, column.wrapping_add(1))
                } else {
                    (c, column)
                };
                let Some(beam) = sensor.beams.get(laser) else {
                    continue;
                };
                let time = rel_s + sensor.model.firing_time_s(g, c);
                let mut emit = |raw: (u16, u8), ret| {
                    let xyz = point(beam, sensor.resolution, raw.0, az);
                    let meta = PointMeta {
                        ring: beam.ring,
                        column: col,
                        ret,
                        intensity: u16::from(raw.1),
                    };
                    self.asm.push(sink, xyz, time, meta);
                    last_column = Some(col);
                };
                match sensor.mode {
                    Mode::Single(ret) => emit(first, ret),
                    // In a dual pair the first block holds the last return, the second the
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
            column = column.wrapping_add(columns_per_block);
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

/// The azimuth `dt` seconds after a block's, rounded to 0.01 degree: f32 arithmetic and
/// round-half-away, exactly as velodyne-decoder, so both pick the same hundredth.
fn interpolate(block_az: u16, rate: f32, dt: f32) -> u16 {
    let a = f32::from(block_az) + rate * dt;
    let r = libm::roundf(a + 36000.0);
    if !r.is_finite() {
        return block_az;
    }
    (r as i64).rem_euclid(i64::from(AZIMUTH_UNITS)) as u16
}

/// Azimuth units to radians through f32, as velodyne-decoder's sine table: its angles are
/// up to 2e-6 rad off the exact hundredth (a hundredth of the 0.01 degree quantisation), which
/// at 200 m moves a point by 3e-4 m; taking the same angle keeps the two within 1e-4 m.
fn azimuth_rad(az: u16) -> f64 {
    let deg2rad = (core::f64::consts::PI / 180.0) as f32;
    f64::from(0.01f32 * f32::from(az) * deg2rad)
}

/// A return in the sensor frame: x forward, y left, z up (the ROS convention).
fn point(beam: &Beam, resolution: f64, raw: u16, az: u16) -> [f64; 3] {
    let d = f64::from(raw) * resolution + beam.distance_offset;
    let theta = azimuth_rad(az) + beam.offset_deg.to_radians();
    let (s, c) = (libm::sin(theta), libm::cos(theta));
    let xy = d * beam.cos_v;
    [
        xy * c + beam.horizontal_offset * s,
        -xy * s + beam.horizontal_offset * c,
        d * beam.sin_v + beam.vertical_offset,
    ]
}
