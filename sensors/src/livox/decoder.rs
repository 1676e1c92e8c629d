//! Livox packets to frames: checks, order and loss detection (each packet's time against the
//! last one's, with the SDK 2 packet counter where there is one: [`Timeline`]), the cut every
//! frame period, then each return to a point.

use super::{sdk1, sdk2, Config, Model};
use crate::error::{ConfigError, PacketError};
use crate::sweep::{
    lost_between, max_step_ns, Assembly, Decode, PointMeta, Pushed, Return, Step, SweepEnd,
    SweepSink, SweepStats, Timeline,
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
    /// The packets' times, packet to packet.
    timeline: Timeline,
    /// The last packet's SDK 2 counter.
    last_count: Option<u16>,
    /// The open frame's start, ns.
    frame_start: u64,
    /// Where the last packet's points end and how long they span, ns.
    covered: (u64, u64),
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
            timeline: Timeline::default(),
            last_count: None,
            frame_start: 0,
            covered: (0, 0),
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

    /// Packets since the last one by the SDK 2 counter (none on SDK 1), if it moved on as a
    /// sensor's does (not back, not half its range).
    fn sequence_step(&self, p: &Packet<'_>) -> Option<u32> {
        let d = p.count()?.wrapping_sub(self.last_count?);
        (1..0x8000).contains(&d).then_some(u32::from(d))
    }

    /// Abandons the open frame's clock (a run of packets agreed on a timeline of their own);
    /// true if a frame was open and has ended.
    fn resync<S: SweepSink>(&mut self, sink: &mut S) -> bool {
        self.timeline.restart();
        self.last_count = None;
        let open = self.asm.open.is_some();
        self.asm.end(sink, SweepEnd::Resync);
        self.asm.resynced();
        open
    }

    fn accept<S: SweepSink>(&mut self, bytes: &[u8], sink: &mut S) -> Result<Pushed, PacketError> {
        let p = Packet::new_checked(bytes, self.model)?;
        self.identify(&p)?;
        let t = p.time_ns();
        let span = p.span_ns();
        let sequence = self.sequence_step(&p);
        let step = match self
            .timeline
            .judge(t, max_step_ns(span, sequence), GAP_NS)?
        {
            Step::First => None,
            Step::After(s) => Some(s),
            Step::Resync if self.resync(sink) => return Ok(Pushed::Again),
            Step::Resync => None,
        };
        if self.asm.open.is_some() {
            if step.is_some_and(|s| s > GAP_NS) {
                // A pause: not counted as losses; the packet begins a timeline of its own.
                self.asm.end(sink, SweepEnd::Gap);
                self.timeline.restart();
                self.last_count = None;
                return Ok(Pushed::Again);
            }
            if t >= self.frame_start.saturating_add(self.period) {
                self.asm.end(sink, SweepEnd::Complete);
                // Frames keep their grid: the next starts at the period the packet is in.
                let periods = (t - self.frame_start) / self.period;
                self.frame_start += periods * self.period;
                return Ok(Pushed::Again);
            }
        } else {
            if step.is_none() {
                self.frame_start = t;
            }
            self.asm.begin(sink, self.frame_start, None);
        }
        let lost = step.map_or(0, |s| lost_between(s, span, sequence));
        self.decode(&p, t, sink);
        let stats = self.asm.stats();
        stats.packets = stats.packets.saturating_add(1);
        stats.lost_packets = stats.lost_packets.saturating_add(lost);
        self.timeline.accept(t);
        self.last_count = p.count();
        self.covered = (t.saturating_add(span as u64), span as u64);
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
    /// The SDK 2 packet counter (SDK 1 has none).
    fn count(&self) -> Option<u16> {
        match self {
            Self::Sdk1(..) => None,
            Self::Sdk2(p) => Some(p.udp_cnt()),
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
    /// Ends the open frame: complete if its packets' points reach its period's end (within
    /// half a packet), else [`SweepEnd::Finished`], a frame the recording cut short.
    fn finish<S: SweepSink>(&mut self, sink: &mut S) {
        let (until, span) = self.covered;
        let whole = until.saturating_add(span / 2) >= self.frame_start.saturating_add(self.period);
        let how = if whole {
            SweepEnd::Complete
        } else {
            SweepEnd::Finished
        };
        self.asm.end(sink, how);
    }
    fn between_sweeps(&self) -> &SweepStats {
        &self.asm.pending
    }
}
