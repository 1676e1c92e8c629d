//! Robosense MSOP packets to sweeps (DIFOP packets pushed to the same decoder give it the
//! unit's angles): checks, order and loss detection by time, the cut, then each return to a
//! point.

use super::calibration::{Calibration, Config};
use super::model::{Model, MAX_LASERS};
use super::wire::{Difop, Msop, AZIMUTH_UNITS, DIFOP_ID};
use crate::error::{ConfigError, PacketError};
use crate::sweep::{
    lost_in_step, wrap_azimuth as wrap, Assembly, AzimuthCut, Decode, LateRun, PointMeta, Pushed,
    Return, SweepEnd, SweepSink, SweepStats,
};

/// A sweep whose packets span more than this (sensor time) ends and the next packet begins a
/// new one: the sensor stopped, or the recording has a hole.
pub const GAP_NS: u64 = 300_000_000;

/// A block-to-block azimuth step above this (hundredths of a degree) is the blind sector of a
/// restricted field of view, not rotation (rs_driver's block iterators use 100).
const BLIND_STEP: u32 = 100;

/// One laser, ready to use.
#[derive(Clone, Copy, Debug, Default)]
struct Beam {
    cos_v: f64,
    sin_v: f64,
    horizontal_deg: f64,
    ring: u16,
}

/// Robosense packets in, sweeps out (see the module doc of [`crate::robosense`]).
pub struct Decoder {
    model: Model,
    calibration: Option<Calibration>,
    beams: [Beam; MAX_LASERS],
    /// Dual-return mode, once known (the DIFOP packet, or the first packet's azimuths).
    dual: Option<bool>,
    last_us: Option<u64>,
    last_azimuth: u16,
    /// Block-to-block azimuth step of the last firing, hundredths of a degree.
    gap: u32,
    cut: AzimuthCut,
    sweep_start_us: u64,
    column: u16,
    late_run: LateRun,
    asm: Assembly,
}

impl Decoder {
    /// A decoder for `config`.
    pub fn new(config: Config) -> Result<Self, ConfigError> {
        if let Some(c) = &config.calibration {
            c.validate(config.model)?;
        }
        let mut d = Self {
            model: config.model,
            calibration: None,
            beams: [Beam::default(); MAX_LASERS],
            dual: None,
            last_us: None,
            last_azimuth: 0,
            gap: 0,
            cut: AzimuthCut::new(config.cut_angle_deg)?,
            sweep_start_us: 0,
            column: 0,
            late_run: LateRun::default(),
            asm: Assembly::new(),
        };
        if let Some(c) = config.calibration {
            d.calibrate(c);
        }
        Ok(d)
    }

    /// The model decoded.
    pub fn model(&self) -> Model {
        self.model
    }

    /// Whether the unit's angles are known.
    pub fn calibrated(&self) -> bool {
        self.calibration.is_some()
    }

    fn calibrate(&mut self, c: Calibration) {
        for (i, (b, l)) in self.beams.iter_mut().zip(c.lasers.iter()).enumerate() {
            let v = l.vertical_deg.to_radians();
            let below = c
                .lasers
                .iter()
                .enumerate()
                .filter(|&(j, m)| {
                    m.vertical_deg < l.vertical_deg || (m.vertical_deg == l.vertical_deg && j < i)
                })
                .count();
            *b = Beam {
                cos_v: libm::cos(v),
                sin_v: libm::sin(v),
                horizontal_deg: l.horizontal_deg,
                ring: below as u16,
            };
        }
        if self.dual.is_none() {
            self.dual = c.dual;
        }
        self.calibration = Some(c);
    }

    /// A DIFOP packet: the angles, if none yet, and the return mode.
    fn difop(&mut self, bytes: &[u8]) -> Result<Pushed, PacketError> {
        let d = Difop::new_checked(bytes)?;
        if self.calibration.is_none() {
            let c =
                Calibration::from_difop(self.model, &d).map_err(|_| PacketError::NoCalibration)?;
            self.calibrate(c);
        }
        Err(PacketError::PacketType)
    }

    /// Dual-return mode: known, or from the packet's azimuths (a dual packet repeats each
    /// firing's azimuth over its two blocks; a 16-laser model's single block holds both and
    /// is read as single return); the RS-Airy's packet says it, and one that says otherwise
    /// than the first is another sensor's. A dual-return RS-Ruby packet pairs its blocks as
    /// AAB or ABB ([`role`]); one that does neither is another return mode's.
    fn mode(&mut self, p: &Msop<'_>) -> Result<bool, PacketError> {
        if self.model == Model::Airy {
            let dual = p.airy_dual();
            if *self.dual.get_or_insert(dual) != dual {
                return Err(PacketError::OtherSensor);
            }
            return Ok(dual);
        }
        let ruby = self.model == Model::Ruby;
        let abb = ruby && p.azimuth(1) == p.azimuth(2);
        let dual = *self.dual.get_or_insert_with(|| {
            self.model.layout().blocks > 1
                && !self.model.two_sequences()
                && (p.azimuth(0) == p.azimuth(1) || abb)
        });
        if dual && ruby && p.azimuth(0) != p.azimuth(1) && !abb {
            return Err(PacketError::OtherSensor);
        }
        Ok(dual)
    }

    fn resync<S: SweepSink>(&mut self, sink: &mut S) -> bool {
        self.late_run.clear();
        self.last_us = None;
        let open = self.asm.open.is_some();
        self.asm.end(sink, SweepEnd::Resync);
        self.cut.restart(None);
        self.asm.resynced();
        open
    }

    fn accept<S: SweepSink>(&mut self, bytes: &[u8], sink: &mut S) -> Result<Pushed, PacketError> {
        if bytes.starts_with(&DIFOP_ID) {
            return self.difop(bytes);
        }
        let p = Msop::new_checked(bytes, self.model)?;
        if self.calibration.is_none() {
            return Err(PacketError::NoCalibration);
        }
        let dual = self.mode(&p)?;
        let t = p.time_us().ok_or(PacketError::DateTime)?;
        let mut step = None;
        if let Some(last) = self.last_us {
            if t <= last {
                if !self.late_run.complete(t * 1000, GAP_NS) {
                    return Err(PacketError::Late);
                }
                if self.resync(sink) {
                    return Ok(Pushed::Again);
                }
            } else {
                step = Some(t - last);
            }
        }
        self.late_run.clear();
        if self.asm.open.is_some() && t.saturating_sub(self.sweep_start_us) * 1000 > GAP_NS {
            self.asm.end(sink, SweepEnd::Gap);
            self.cut.restart(Some(self.last_azimuth));
            return Ok(Pushed::Again);
        }
        if self.asm.open.is_none() {
            self.asm.begin(sink, t.saturating_mul(1000), None);
            self.sweep_start_us = t;
            self.column = 0;
        }
        let lost = step.map_or(0, |s| lost_in_step(s as f64, self.model.packet_us(dual)));
        self.decode(&p, t, dual, sink);
        let stats = self.asm.stats();
        stats.packets = stats.packets.saturating_add(1);
        stats.lost_packets = stats.lost_packets.saturating_add(lost);
        let last_az = p.azimuth(self.model.layout().blocks - 1);
        self.last_us = Some(t);
        self.last_azimuth = last_az;
        if self.cut.passed(last_az) {
            self.asm.end(sink, SweepEnd::Complete);
            self.cut.restart(Some(last_az));
            return Ok(Pushed::Ended);
        }
        Ok(Pushed::Decoded)
    }

    /// Every return of a checked packet of time `t` (us).
    fn decode<S: SweepSink>(&mut self, p: &Msop<'_>, t: u64, dual: bool, sink: &mut S) {
        let m = self.model;
        let l = m.layout();
        let install = self
            .calibration
            .as_ref()
            .map(|c| c.install)
            .unwrap_or_default();
        let block_us = m.block_us(dual);
        let (rx, rz) = m.lens_m();
        let res = m.distance_resolution_m();
        let (min, max) = m.range_m();
        let base_s = (t - self.sweep_start_us) as f64 * 1e-6;
        let role = |k: usize| role(m, p, dual, k);
        let mut block = 0;
        while block < l.blocks {
            let (f, _) = role(block);
            let end = (block + 1..l.blocks)
                .find(|&k| role(k).0 != f)
                .unwrap_or(l.blocks);
            let az0 = p.azimuth(block);
            // The rotation to the next firing's block; past the last firing, or across the
            // blind sector of a restricted field of view, the step before it.
            if end < l.blocks {
                let g = wrap(i32::from(p.azimuth(end)) - i32::from(az0));
                if g <= BLIND_STEP {
                    self.gap = g;
                }
            }
            // A firing whose first return the packet before held (the RS-Ruby's ABB) is
            // that packet's last column.
            let continued = block == 0 && role(0).1;
            let column = if continued {
                self.column.wrapping_sub(1)
            } else {
                self.column
            };
            let elapsed_us = f as f64 * block_us;
            for k in block..end {
                let ret = if role(k).1 {
                    Return::Second
                } else {
                    Return::Strongest
                };
                let first = m.channel(k, 0);
                for c in 0..l.channels {
                    let (raw, intensity) = p.channel(k, c);
                    let d = f64::from(raw) * res;
                    if raw == 0 || d < min || d > max {
                        continue;
                    }
                    let ch = first + c;
                    let Some(beam) = self.beams.get(m.laser(ch)) else {
                        continue;
                    };
                    let fire_us = m.firing_us(ch, dual, install);
                    let ret = if dual && m.two_sequences() && c >= 16 {
                        Return::Second
                    } else {
                        ret
                    };
                    // The block's azimuth plus its share of the rotation to the next firing.
                    let az = f64::from(az0) + f64::from(self.gap) * fire_us / block_us;
                    let xyz = point(beam, d, az, (rx, rz));
                    let time = base_s + (elapsed_us + fire_us) * 1e-6;
                    let meta = PointMeta {
                        ring: beam.ring,
                        column,
                        ret,
                        intensity: u16::from(intensity),
                    };
                    self.asm.push(sink, xyz, time, meta);
                }
            }
            if !continued {
                self.column = self.column.wrapping_add(1);
            }
            block = end;
        }
    }
}

/// Block `k`'s firing in the packet, and whether the block holds that firing's second return
/// (rs_driver's block iterators). A firing's blocks hold its first return's
/// [`Model::halves`], then its second's. A dual-return RS-Ruby packet holds one and a half
/// firings (`ABDualReturnBlockIterator`): its blocks pair as AAB (the B the first return of a
/// firing the next packet ends) or ABB (the A the second return of the last packet's).
fn role(m: Model, p: &Msop<'_>, dual: bool, k: usize) -> (usize, bool) {
    if dual && m == Model::Ruby {
        return match (p.azimuth(0) == p.azimuth(1), k) {
            (true, 0) => (0, false),
            (true, 1) => (0, true),
            (true, _) => (1, false),
            (false, 0) => (0, true),
            (false, 1) => (1, false),
            (false, _) => (1, true),
        };
    }
    let per = m.blocks_per_firing(dual);
    (k / per, k % per >= m.halves())
}

/// A return at range `d` (m) along azimuth `az` (hundredths of a degree, before the laser's
/// horizontal offset), x forward, y left, z up: rs_driver's geometry, the range measured from
/// the lens centre `rx` off the axis along the rotor's azimuth and `rz` above the origin.
fn point(beam: &Beam, d: f64, az: f64, (rx, rz): (f64, f64)) -> [f64; 3] {
    let units = f64::from(AZIMUTH_UNITS);
    let rotor = (libm::fmod(az, units) * 0.01).to_radians();
    let theta = rotor + beam.horizontal_deg.to_radians();
    let xy = d * beam.cos_v;
    [
        xy * libm::cos(theta) + rx * libm::cos(rotor),
        -xy * libm::sin(theta) - rx * libm::sin(rotor),
        d * beam.sin_v + rz,
    ]
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
