//! Hesai packets to sweeps: checks, order and loss detection (by the UDP sequence number when
//! the packets carry one, else by their times), the cut, then each return to a point.

use super::angles::{Angles, ChannelAngles, MirrorAngles};
use super::at128::At128Correction;
use super::model::{Config, Firing, Model, ReturnMode, DISTANCE_UNIT_M, PANDAR128_NEAR_M};
use super::wire::Packet;
use super::{wire128, wire_fixed};
use crate::error::{ConfigError, PacketError};
use crate::sweep::{
    lost_in_step, Assembly, AzimuthCut, Decode, LateRun, PointMeta, Pushed, Return, SweepEnd,
    SweepSink, SweepStats,
};

/// A sweep whose packets span more than this (sensor time) ends and the next packet begins a
/// new one: the sensor stopped, or the recording has a hole.
pub const GAP_NS: u64 = 300_000_000;

/// A sequence number this far ahead of the last is not a count of lost packets (a sensor
/// restart): losses are then counted from the times.
const MAX_SEQUENCE_STEP: u32 = 1 << 20;

/// The return-mode byte of triple return (first, last, strongest: the XT32M's).
const TRIPLE_RETURN: u8 = 0x3D;

/// A checked packet of either layout.
#[derive(Clone, Copy)]
enum View<'a> {
    Xt32(Packet<'a>),
    Wide(wire128::Packet<'a>),
    Fixed(wire_fixed::Packet<'a>),
}

impl<'a> View<'a> {
    /// Checks `bytes` as a packet of `model`'s protocol.
    fn new_checked(model: Model, bytes: &'a [u8]) -> Result<Self, PacketError> {
        if let Some((format, _)) = model.fixed() {
            return wire_fixed::Packet::new_checked(format, bytes).map(Self::Fixed);
        }
        let version = match model {
            Model::Xt32 => return Packet::new_checked(bytes).map(Self::Xt32),
            Model::Qt128 => wire128::VERSION_QT,
            _ => wire128::VERSION_128,
        };
        let p = wire128::Packet::new_checked(bytes)?;
        if p.version() != version {
            return Err(PacketError::Version);
        }
        Ok(Self::Wide(p))
    }
    /// Whether the header's return count fits `mode`. Where the count is the mode's (QT64,
    /// QT128, Pandar128, OT128: their manuals' "1 single, 2 dual"; the QT64's capture says 2
    /// in dual) it must equal it. Protocol 6.1 (XT32, XT16, XT32M) and the AT128 may state
    /// the most returns the unit sends instead (the XT manual's later edition: "0x02, each
    /// channel can generate two returns maximum"; the XT32M's capture says 3 in dual mode):
    /// the count must be at least the mode's and at most that maximum. The 40P has no header
    /// and the Pandar64's has no count: bytes 6 and 7 are reserved (nebula's `Header8B`, the
    /// manual) and its "first block's return" byte 4 reads 0, single, in all 2,400 packets of
    /// its dual-return capture, so neither can be checked.
    fn returns_fit(&self, model: Model, mode: ReturnMode) -> bool {
        let n = mode.returns();
        let count = match self {
            Self::Xt32(p) => p.returns(),
            Self::Wide(p) => return usize::from(p.returns()) == n,
            Self::Fixed(p) => match p.header_returns() {
                Some(r) => r,
                None => return true,
            },
        };
        let most = match model {
            Model::PandarQT64 => return usize::from(count) == n,
            Model::Xt32m => 3,
            _ => 2,
        };
        (n..=most).contains(&usize::from(count))
    }
    /// Metres per distance unit.
    fn distance_unit_m(&self) -> f64 {
        match self {
            Self::Fixed(p) => f64::from(p.distance_unit_mm()) * 1e-3,
            _ => DISTANCE_UNIT_M,
        }
    }
    fn return_mode(&self) -> u8 {
        match self {
            Self::Xt32(p) => p.return_mode(),
            Self::Wide(p) => p.return_mode(),
            Self::Fixed(p) => p.return_mode(),
        }
    }
    fn azimuth(&self, k: usize) -> u16 {
        match self {
            Self::Xt32(p) => p.azimuth(k),
            Self::Wide(p) => p.azimuth(k),
            Self::Fixed(p) => p.azimuth(k),
        }
    }
    /// Block `k`'s azimuth in 1/25,600 degree (the AT128's fine byte; the others' hundredths
    /// times 256).
    fn fine_azimuth(&self, k: usize) -> u32 {
        match self {
            Self::Fixed(p) => p.fine_azimuth(k),
            _ => u32::from(self.azimuth(k)) << 8,
        }
    }
    fn channel(&self, k: usize, c: usize) -> (u16, u8) {
        match self {
            Self::Xt32(p) => p.channel(k, c),
            Self::Wide(p) => p.channel(k, c),
            Self::Fixed(p) => p.channel(k, c),
        }
    }
    fn unix_ns(&self) -> Option<u64> {
        match self {
            Self::Xt32(p) => p.unix_ns(),
            Self::Wide(p) => p.unix_ns(),
            Self::Fixed(p) => p.unix_ns(),
        }
    }
    fn udp_sequence(&self) -> Option<u32> {
        match self {
            Self::Xt32(p) => p.udp_sequence(),
            Self::Wide(p) => p.udp_sequence(),
            Self::Fixed(p) => p.udp_sequence(),
        }
    }
    /// Block `k`'s firing state, for a mode of `returns` returns.
    fn firing(&self, k: usize, returns: usize) -> Firing {
        match self {
            Self::Xt32(_) | Self::Fixed(_) => Firing {
                returns,
                ..Firing::default()
            },
            Self::Wide(p) => Firing {
                returns,
                mode_flag: p.mode_flag(),
                operational_state: p.operational_state(),
                azimuth_state: p.azimuth_state(k),
                near: false,
            },
        }
    }
}

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
    /// Time of the last packet accepted, ns since the Unix epoch.
    last_ns: Option<u64>,
    last_sequence: Option<u32>,
    last_azimuth: u16,
    cut: AzimuthCut,
    /// The AT128's mirror frame the open sweep holds.
    sweep_frame: Option<usize>,
    /// The open sweep's time origin: its first packet's first firing, ns.
    sweep_start_ns: u64,
    /// Firings decoded into the open sweep.
    column: u16,
    late_run: LateRun,
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
            last_ns: None,
            last_sequence: None,
            last_azimuth: 0,
            cut,
            sweep_frame: None,
            sweep_start_ns: 0,
            column: 0,
            late_run: LateRun::default(),
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

    /// The packet's return mode: the one the first packet fixed, which every packet's mode
    /// byte must repeat (else another sensor's) and its header's return count fit (else the
    /// header is damaged).
    fn identify(&mut self, p: &View<'_>) -> Result<ReturnMode, PacketError> {
        let byte = p.return_mode();
        let mode = match self.mode {
            Some((mode, b)) if b == byte => mode,
            Some(_) => return Err(PacketError::OtherSensor),
            None if byte == TRIPLE_RETURN => return Err(PacketError::TripleReturn),
            None => {
                ReturnMode::from_byte(self.model, byte).ok_or(PacketError::UnknownReturnMode)?
            }
        };
        if !p.returns_fit(self.model, mode) {
            return Err(PacketError::UnknownReturnMode);
        }
        self.mode = Some((mode, byte));
        Ok(mode)
    }

    /// Abandons the open sweep's clock; true if a sweep was open and has ended.
    fn resync<S: SweepSink>(&mut self, sink: &mut S) -> bool {
        self.late_run.clear();
        self.last_ns = None;
        self.last_sequence = None;
        let open = self.asm.open.is_some();
        self.asm.end(sink, SweepEnd::Resync);
        self.cut.restart(None);
        self.asm.resynced();
        open
    }

    fn accept<S: SweepSink>(&mut self, bytes: &[u8], sink: &mut S) -> Result<Pushed, PacketError> {
        let p = View::new_checked(self.model, bytes)?;
        let mode = self.identify(&p)?;
        let t = p.unix_ns().ok_or(PacketError::Timestamp)?;
        // Every block's azimuth must lie in a frame of the AT128's correction.
        let blocks = self.model.blocks();
        if (0..blocks).any(|k| self.angles.frame(p.fine_azimuth(k)).is_none()) {
            return Err(PacketError::Azimuth);
        }
        let mut step = None;
        if let Some(last) = self.last_ns {
            if t <= last {
                if !self.late_run.complete(t, GAP_NS) {
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
        let returns = mode.returns();
        if self.asm.open.is_some() && t.saturating_sub(self.sweep_start_ns) > GAP_NS {
            self.asm.end(sink, SweepEnd::Gap);
            self.cut.restart(Some(self.last_azimuth));
            return Ok(Pushed::Again);
        }
        let frame = self.angles.frame(p.fine_azimuth(0));
        let by_frame = self.angles.sweeps_are_frames();
        if by_frame && self.asm.open.is_some() && frame != self.sweep_frame {
            // The AT128's next mirror frame: this sweep is complete.
            self.asm.end(sink, SweepEnd::Complete);
            return Ok(Pushed::Again);
        }
        if self.asm.open.is_none() {
            let (earliest, _) = self.model.firing_span_ns(0, &p.firing(0, returns));
            let start = t.saturating_add_signed(earliest);
            self.asm.begin(sink, start, None);
            self.sweep_start_ns = start;
            self.sweep_frame = frame;
            self.column = 0;
        }
        let lost = self.lost_before(&p, step, returns);
        self.decode(&p, t, mode, sink);
        let stats = self.asm.stats();
        stats.packets = stats.packets.saturating_add(1);
        stats.lost_packets = stats.lost_packets.saturating_add(lost);
        let last_az = p.azimuth(blocks - 1);
        self.last_ns = Some(t);
        self.last_sequence = p.udp_sequence();
        self.last_azimuth = last_az;
        if !by_frame && self.cut.passed(last_az) {
            self.asm.end(sink, SweepEnd::Complete);
            self.cut.restart(Some(last_az));
            return Ok(Pushed::Ended);
        }
        Ok(Pushed::Decoded)
    }

    /// Packets missing between the last one and `p`: the sequence numbers' step, or the
    /// time step in packet periods when there are none.
    fn lost_before(&self, p: &View<'_>, step_ns: Option<u64>, returns: usize) -> u32 {
        let Some(step_ns) = step_ns else { return 0 };
        if let (Some(now), Some(last)) = (p.udp_sequence(), self.last_sequence) {
            let d = now.wrapping_sub(last);
            if (1..MAX_SEQUENCE_STEP).contains(&d) {
                return d - 1;
            }
        }
        let state = p.firing(0, returns).operational_state;
        let period = (self.model.blocks() / returns) as f64 * self.model.firing_ns(state) as f64;
        lost_in_step(step_ns as f64, period)
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
