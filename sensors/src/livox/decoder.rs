//! Livox packets to frames: checks, order and loss detection by the packets' times, the cut
//! every frame period, then each return to a point.

use super::{sdk1, sdk2, Config, Model};
use crate::error::{ConfigError, PacketError};
use crate::sweep::{
    lost_in_step, Assembly, Decode, LateRun, PointMeta, Pushed, Return, SweepEnd, SweepSink,
    SweepStats,
};

/// Packets more than this apart (sensor time) are not one frame's: the sensor stopped, or the
/// recording has a hole; the next packet begins a new frame.
pub const GAP_NS: u64 = 300_000_000;

/// Livox packets in, frames out (see the module doc of [`crate::livox`]).
///
/// ```
/// use kiss_odom_sensors::{livox, Chunk, Decode, SweepSink, SweepStart, SweepStats};
/// struct Count(usize);
/// impl SweepSink for Count {
///     fn begin_sweep(&mut self, _: &SweepStart) {}
///     fn points(&mut self, c: Chunk<'_>) { self.0 += c.xyz.len(); }
///     fn end_sweep(&mut self, _: &SweepStats) {}
/// }
/// let mut dec = livox::Decoder::new(livox::Config::default()).unwrap();
/// let mut sink = Count(0);
/// assert!(dec.push(&[5u8; 10], &mut sink).is_err());
/// dec.finish(&mut sink);
/// ```
pub struct Decoder {
    model: Model,
    period: u64,
    /// Sender (SDK 1 slot and lidar id) and data type, fixed by the first packet decoded.
    sender: Option<((u8, u8), u8)>,
    last_ns: Option<u64>,
    /// The open frame's start, ns.
    frame_start: u64,
    late_run: LateRun,
    asm: Assembly,
}

impl Decoder {
    /// A decoder for `config`; nothing is decoded until the first packet.
    pub fn new(config: Config) -> Result<Self, ConfigError> {
        if config.frame_period_ns == 0 || config.frame_period_ns > GAP_NS {
            return Err(ConfigError::FramePeriod);
        }
        Ok(Self {
            model: config.model,
            period: config.frame_period_ns,
            sender: None,
            last_ns: None,
            frame_start: 0,
            late_run: LateRun::default(),
            asm: Assembly::new(),
        })
    }

    /// The model decoded.
    pub fn model(&self) -> Model {
        self.model
    }

    fn identify(&mut self, p: &Packet<'_>) -> Result<(), PacketError> {
        if p.is_imu() {
            return Err(PacketError::PacketType);
        }
        let id = p.identity();
        match self.sender {
            Some(s) if s != id => Err(PacketError::OtherSensor),
            Some(_) => Ok(()),
            None => {
                self.sender = Some(id);
                Ok(())
            }
        }
    }

    fn accept<S: SweepSink>(&mut self, bytes: &[u8], sink: &mut S) -> Result<Pushed, PacketError> {
        let p = Packet::new_checked(bytes, self.model)?;
        self.identify(&p)?;
        let t = p.time_ns();
        let mut step = None;
        if let Some(last) = self.last_ns {
            if t <= last {
                if !self.late_run.complete(t, GAP_NS) {
                    return Err(PacketError::Late);
                }
                self.late_run.clear();
                self.last_ns = None;
                let open = self.asm.open.is_some();
                self.asm.end(sink, SweepEnd::Resync);
                self.asm.resynced();
                if open {
                    return Ok(Pushed::Again);
                }
            } else {
                step = Some(t - last);
            }
        }
        self.late_run.clear();
        if self.asm.open.is_some() {
            let end = if step.is_some_and(|s| s > GAP_NS) {
                Some(SweepEnd::Gap)
            } else if t >= self.frame_start.saturating_add(self.period) {
                Some(SweepEnd::Complete)
            } else {
                None
            };
            if let Some(end) = end {
                self.asm.end(sink, end);
                if end == SweepEnd::Complete {
                    // Frames keep their grid: the next starts at the period the packet is in.
                    let periods = (t - self.frame_start) / self.period;
                    self.frame_start += periods * self.period;
                } else {
                    self.frame_start = t;
                }
                return Ok(Pushed::Again);
            }
        } else {
            if self.last_ns.is_none() || step.is_some_and(|s| s > GAP_NS) {
                self.frame_start = t;
            }
            self.asm.begin(sink, self.frame_start, None);
        }
        let lost = step.map_or(0, |s| lost_in_step(s as f64, p.span_ns()));
        self.decode(&p, t, sink);
        let stats = self.asm.stats();
        stats.packets = stats.packets.saturating_add(1);
        stats.lost_packets = stats.lost_packets.saturating_add(lost);
        self.last_ns = Some(t);
        Ok(Pushed::Decoded)
    }

    fn decode<S: SweepSink>(&mut self, p: &Packet<'_>, t: u64, sink: &mut S) {
        let base = (t - self.frame_start) as f64;
        let dual = p.returns() == 2;
        let firing_ns = p.firing_ns();
        for k in 0..p.firings() {
            let time = (base + k as f64 * firing_ns) * 1e-9;
            for r in 0..p.returns() {
                let Some((xyz, reflectivity, tag)) = p.point(k, r) else {
                    continue;
                };
                let ret = match (dual, r) {
                    (true, 1) => Return::Second,
                    _ => Return::First,
                };
                let meta = PointMeta {
                    ring: u16::from(tag),
                    column: k as u16,
                    ret,
                    intensity: u16::from(reflectivity),
                };
                self.asm.push(sink, xyz, time, meta);
            }
        }
    }
}

/// A checked packet of either protocol, as the decoder reads it.
enum Packet<'a> {
    Sdk1(sdk1::Packet<'a>, f64),
    Sdk2(sdk2::Packet<'a>),
}

impl<'a> Packet<'a> {
    /// The model says the protocol (and, on SDK 1, the firing interval).
    fn new_checked(bytes: &'a [u8], model: Model) -> Result<Self, PacketError> {
        Ok(match model.firing_ns() {
            Some(firing_ns) => {
                let p = sdk1::Packet::new_checked(bytes)?;
                Self::Sdk1(p, firing_ns)
            }
            None => Self::Sdk2(sdk2::Packet::new_checked(bytes)?),
        })
    }
    /// What must stay the same from packet to packet: SDK 1's slot and lidar id, the data type.
    fn identity(&self) -> ((u8, u8), u8) {
        match self {
            Self::Sdk1(p, _) => (p.sender(), p.data_type()),
            Self::Sdk2(p) => ((0, 0), p.data_type()),
        }
    }
    fn is_imu(&self) -> bool {
        match self {
            Self::Sdk1(p, _) => p.imu().is_some(),
            Self::Sdk2(p) => p.imu().is_some(),
        }
    }
    fn time_ns(&self) -> u64 {
        match self {
            // Checked by `new_checked`.
            Self::Sdk1(p, _) => p.time_ns().unwrap_or(0),
            Self::Sdk2(p) => p.time_ns(),
        }
    }
    fn firings(&self) -> usize {
        match self {
            Self::Sdk1(p, _) => p.firings(),
            Self::Sdk2(p) => p.firings(),
        }
    }
    fn returns(&self) -> usize {
        match self {
            Self::Sdk1(p, _) => p.returns(),
            Self::Sdk2(p) => p.returns(),
        }
    }
    fn firing_ns(&self) -> f64 {
        match self {
            Self::Sdk1(_, firing_ns) => *firing_ns,
            Self::Sdk2(p) => p.firing_ns(),
        }
    }
    /// Time a packet's firings span, ns.
    fn span_ns(&self) -> f64 {
        match self {
            Self::Sdk1(p, firing_ns) => p.firings() as f64 * firing_ns,
            Self::Sdk2(p) => p.span_ns(),
        }
    }
    fn point(&self, k: usize, r: usize) -> super::Return {
        match self {
            Self::Sdk1(p, _) => p.point(k, r),
            Self::Sdk2(p) => p.point(k, r),
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
