//! Hesai packets to sweeps: checks (the format, then what the fields must agree on,
//! `consistency.rs`), order and loss detection (each packet's time against the last one's, by
//! the UDP sequence number when the packets carry one, else by their times: [`Timeline`]), the
//! cut, then each return to a point.

use super::angles::{Angles, ChannelAngles, MirrorAngles};
use super::at128::At128Correction;
use super::consistency::azimuths_agree;
use super::model::{Config, Firing, Model, ReturnMode, PANDAR128_NEAR_M};
use super::view::View;
use crate::error::{ConfigError, PacketError};
use crate::sweep::{
    lost_between, max_step_ns, Assembly, AzimuthCut, Decode, PointMeta, Pushed, Return, Step,
    SweepEnd, SweepSink, SweepStats, Timeline,
};

/// A sweep whose packets span more than this (sensor time) ends and the next packet begins a
/// new one: the sensor stopped, or the recording has a hole.
pub const GAP_NS: u64 = 300_000_000;

/// The longest step between two AT128 packets of one timeline: the pause between mirror frames
/// is under a frame's time at 10 Hz, and a packet further ahead is still held out as a stray.
const MIRROR_PAUSE_NS: u64 = 100_000_000;

/// A sequence number this far ahead of the last is not a count of lost packets (a sensor
/// restart): losses are then counted from the times.
const MAX_SEQUENCE_STEP: u32 = 1 << 20;

/// The return-mode byte of triple return (first, last, strongest: the XT32M's).
const TRIPLE_RETURN: u8 = 0x3D;

/// Hesai packets in, sweeps out (see the module doc of [`crate::hesai`]). `A` is how returns
/// get their directions: each channel's angles ([`Decoder::new`]) or the AT128's mirror-frame
/// correction ([`Decoder::at128`]).
///
/// ```
/// use kiss_odom_sensors::{hesai, Chunk, Decode, SweepSink, SweepStart, SweepStats};
/// struct Count(usize);
/// impl SweepSink for Count {
///     fn begin_sweep(&mut self, _: &SweepStart) {}
///     fn points(&mut self, c: Chunk<'_>) { self.0 += c.xyz.len(); }
///     fn end_sweep(&mut self, _: &SweepStats) {}
/// }
/// let mut dec = hesai::Decoder::new(hesai::Config::default()).unwrap();
/// let mut sink = Count(0);
/// // A payload from UDP port 2368 (XT32: 1076 or 1080 bytes); anything else is refused with
/// // a reason.
/// assert!(dec.push(&[0u8; 100], &mut sink).is_err());
/// dec.finish(&mut sink);
/// ```
pub struct Decoder<A: Angles = ChannelAngles> {
    model: Model,
    angles: A,
    /// The return mode and its byte, fixed by the first packet decoded.
    mode: Option<(ReturnMode, u8)>,
    /// The packets' times, packet to packet.
    timeline: Timeline,
    last_sequence: Option<u32>,
    last_azimuth: u16,
    cut: AzimuthCut,
    /// The AT128's mirror frame the open sweep holds.
    sweep_frame: Option<usize>,
    /// The open sweep's time origin: its first packet's first firing, ns.
    sweep_start_ns: u64,
    /// Firings decoded into the open sweep.
    column: u16,
    asm: Assembly,
}

impl Decoder<ChannelAngles> {
    /// A decoder for `config`; nothing is decoded until the first packet. The calibration
    /// must have one entry per channel of the model, and only the XT32 and XT16 may go
    /// without. The AT128 has no per-channel angles: [`Decoder::at128`].
    pub fn new(config: Config) -> Result<Self, ConfigError> {
        let model = config.model;
        if model == Model::At128 {
            return Err(ConfigError::Calibration);
        }
        let calibration = config
            .calibration
            .or(model.nominal_calibration())
            .ok_or(ConfigError::Calibration)?;
        calibration.validate()?;
        if calibration.channels != model.channels() {
            return Err(ConfigError::Calibration);
        }
        let angles = ChannelAngles::new(&calibration);
        Self::with(model, angles, AzimuthCut::new(config.cut_angle_deg)?)
    }
}

impl Decoder<MirrorAngles> {
    /// A PandarAT128 decoder with the unit's mirror-frame angle correction (the `.dat` the
    /// host reads); its sweeps are its mirror frames (each sweep ends when a packet of the
    /// next frame arrives), so it takes no cut angle.
    pub fn at128(correction: &At128Correction) -> Result<Self, ConfigError> {
        let angles = MirrorAngles::new(correction)?;
        Self::with(Model::At128, angles, AzimuthCut::new(None)?)
    }
}

impl<A: Angles> Decoder<A> {
    fn with(model: Model, angles: A, cut: AzimuthCut) -> Result<Self, ConfigError> {
        Ok(Self {
            model,
            angles,
            mode: None,
            timeline: Timeline::default(),
            last_sequence: None,
            last_azimuth: 0,
            cut,
            sweep_frame: None,
            sweep_start_ns: 0,
            column: 0,
            asm: Assembly::new(),
        })
    }

    /// The sensor decoded.
    pub fn model(&self) -> Model {
        self.model
    }

    /// The return mode, once a packet told it.
    pub fn return_mode(&self) -> Option<ReturnMode> {
        self.mode.map(|(m, _)| m)
    }

    /// The packet's return mode and its byte: one of the model's modes that its header's
    /// return count fits (else the packet is damaged, whatever the sweep's mode), and the one
    /// the first packet decoded fixed (else another sensor's).
    fn identify(&self, p: &View<'_>) -> Result<(ReturnMode, u8), PacketError> {
        let byte = p.return_mode();
        if byte == TRIPLE_RETURN {
            return Err(PacketError::TripleReturn);
        }
        let mode = ReturnMode::from_byte(self.model, byte).ok_or(PacketError::UnknownReturnMode)?;
        p.returns_fit(self.model, mode)?;
        match self.mode {
            Some((_, b)) if b != byte => Err(PacketError::OtherSensor),
            _ => Ok((mode, byte)),
        }
    }

    /// Abandons the open sweep's clock; true if a sweep was open and has ended.
    fn resync<S: SweepSink>(&mut self, sink: &mut S) -> bool {
        self.timeline.restart();
        self.last_sequence = None;
        let open = self.asm.open.is_some();
        self.asm.end(sink, SweepEnd::Resync);
        self.cut.restart(None);
        self.asm.resynced();
        open
    }

    /// Checks what the packet's fields must agree on (`consistency.rs`): a protocol 1.4
    /// packet's states with the firing-time file, and the block azimuths with the return mode
    /// and motor speed (the AT128's blocks sweep its mirror frames: not checked so).
    fn consistent(&self, p: &View<'_>, returns: usize) -> Result<(), PacketError> {
        let blocks = self.model.blocks();
        for k in 0..blocks {
            let f = p.firing(k, returns);
            if !self.model.lists_state(&f) {
                return Err(PacketError::FiringState {
                    operational: f.operational_state,
                    azimuth: f.azimuth_state,
                });
            }
        }
        if self.angles.sweeps_are_frames() {
            return Ok(());
        }
        let firing_ns = self.model.firing_ns(p.firing(0, returns).operational_state);
        let azimuth = |k| p.azimuth(k);
        azimuths_agree(azimuth, blocks, returns, p.motor_rpm(), firing_ns)
    }

    /// Time from one packet to the next, ns, in the packet's mode and state.
    fn period_ns(&self, p: &View<'_>, returns: usize) -> f64 {
        let state = p.firing(0, returns).operational_state;
        (self.model.blocks() / returns.max(1)) as f64 * self.model.firing_ns(state) as f64
    }

    /// Packets since the last one by their UDP sequence numbers, if both carry one and the
    /// step is one a sensor makes (not a restart's).
    fn sequence_step(&self, p: &View<'_>) -> Option<u32> {
        let d = p.udp_sequence()?.wrapping_sub(self.last_sequence?);
        (1..MAX_SEQUENCE_STEP).contains(&d).then_some(d)
    }

    fn accept<S: SweepSink>(&mut self, bytes: &[u8], sink: &mut S) -> Result<Pushed, PacketError> {
        let p = View::new_checked(self.model, bytes)?;
        let (mode, mode_byte) = self.identify(&p)?;
        let t = p.unix_ns().ok_or(PacketError::DateTime)?;
        // Every block's azimuth must lie in a frame of the AT128's correction.
        let blocks = self.model.blocks();
        if (0..blocks).any(|k| self.angles.frame(p.fine_azimuth(k)).is_none()) {
            return Err(PacketError::MirrorFrame);
        }
        let returns = mode.returns();
        self.consistent(&p, returns)?;
        let period = self.period_ns(&p, returns);
        let sequence = self.sequence_step(&p);
        let mut max_step = max_step_ns(period, sequence);
        if self.angles.sweeps_are_frames() {
            // The AT128 pauses between mirror frames: a pause within a frame's time is its own.
            max_step = max_step.max(MIRROR_PAUSE_NS);
        }
        let step = match self.timeline.judge(t, max_step, GAP_NS)? {
            Step::First => None,
            Step::After(s) => Some(s),
            Step::Resync if self.resync(sink) => return Ok(Pushed::Again),
            Step::Resync => None,
        };
        self.mode = Some((mode, mode_byte));
        if self.asm.open.is_some() && t.saturating_sub(self.sweep_start_ns) > GAP_NS {
            self.asm.end(sink, SweepEnd::Gap);
            self.cut.restart(Some(self.last_azimuth));
            // A gap is not counted as losses: the packet begins a timeline of its own.
            self.timeline.restart();
            self.last_sequence = None;
            return Ok(Pushed::Again);
        }
        let frame = self.angles.frame(p.fine_azimuth(0));
        let by_frame = self.angles.sweeps_are_frames();
        if by_frame && self.asm.open.is_some() && frame != self.sweep_frame {
            // The AT128's next mirror frame: this sweep is complete.
            self.asm.end(sink, SweepEnd::Complete);
            return Ok(Pushed::Again);
        }
        let begins = self.asm.open.is_none();
        if begins {
            let (earliest, _) = self.model.firing_span_ns(0, &p.firing(0, returns));
            let start = t.saturating_add_signed(earliest);
            self.asm.begin(sink, start, None);
            self.sweep_start_ns = start;
            self.sweep_frame = frame;
            self.column = 0;
        }
        let lost = match step {
            // The pause before an AT128 mirror frame is not packets lost: only its sequence
            // number can say.
            Some(_) if by_frame && begins => sequence.map_or(0, |d| d - 1),
            Some(s) => lost_between(s, period, sequence),
            None => 0,
        };
        self.decode(&p, t, mode, sink);
        let stats = self.asm.stats();
        stats.packets = stats.packets.saturating_add(1);
        stats.lost_packets = stats.lost_packets.saturating_add(lost);
        let last_az = p.azimuth(blocks - 1);
        self.timeline.accept(t);
        self.last_sequence = p.udp_sequence();
        self.last_azimuth = last_az;
        if !by_frame && self.cut.passed(last_az) {
            self.asm.end(sink, SweepEnd::Complete);
            self.cut.restart(Some(last_az));
            return Ok(Pushed::Ended);
        }
        Ok(Pushed::Decoded)
    }

    /// Every return of a checked packet of time `t` (ns).
    fn decode<S: SweepSink>(&mut self, p: &View<'_>, t: u64, mode: ReturnMode, sink: &mut S) {
        let returns = mode.returns();
        let base = t as i64 - self.sweep_start_ns as i64;
        let channels = self.model.channels();
        let unit_m = p.distance_unit_m();
        for firing in 0..self.model.blocks() / returns {
            let block = firing * returns;
            let fine = p.fine_azimuth(block);
            let frame = self.angles.frame(fine).unwrap_or(0);
            let state = p.firing(block, returns);
            for c in 0..channels {
                let mut emit = |raw: (u16, u8), ret| {
                    let d = f64::from(raw.0) * unit_m;
                    let near = d < PANDAR128_NEAR_M;
                    let offset = self
                        .model
                        .point_offset_ns(block, c, &Firing { near, ..state });
                    let time = (base + offset) as f64 * 1e-9;
                    let meta = PointMeta {
                        ring: c as u16,
                        column: self.column,
                        ret,
                        intensity: u16::from(raw.1),
                    };
                    let xyz = self.angles.point(fine, frame, c, d);
                    self.asm.push(sink, xyz, time, meta);
                };
                let first = p.channel(block, c);
                match mode {
                    ReturnMode::Single(ret) => {
                        if first.0 != 0 {
                            emit(first, ret);
                        }
                    }
                    ReturnMode::Dual(ret_a, ret_b) => {
                        let second = p.channel(block + 1, c);
                        if first.0 == second.0 {
                            if first.0 != 0 {
                                emit(first, Return::Both);
                            }
                        } else {
                            if first.0 != 0 {
                                emit(first, ret_a);
                            }
                            if second.0 != 0 {
                                emit(second, ret_b);
                            }
                        }
                    }
                }
            }
            self.column = self.column.wrapping_add(1);
        }
    }
}

impl<A: Angles> Decode for Decoder<A> {
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
