//! Sweep assembly's shared vocabulary: what a decoder hands its [`SweepSink`] and the per-sweep
//! packet statistics.
//!
//! A decoder calls `begin_sweep`, then `points` with chunks of at most [`CHUNK`] points as
//! packets arrive, then `end_sweep` with the sweep's [`SweepStats`]. Between two sweeps it
//! holds no points, only one chunk being filled, so the caller decides where a sweep lives
//! (streamed into the odometry's `begin_frame`/`push`/`finish`, or collected).

use crate::error::PacketError;
pub(crate) use crate::timeline::{
    lost_between, lost_in_step, max_step_ns, LateRun, Step, Timeline,
};

/// Points handed to the sink at a time, at most: one chunk buffer of this many points lives in
/// each decoder (40 bytes a point).
pub const CHUNK: usize = 256;

/// Which return of a firing a point is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Return {
    /// Strongest return (strongest mode, or the strongest of a dual pair).
    #[default]
    Strongest,
    /// Last return (last mode, or the last of a dual pair).
    Last,
    /// Dual mode where both returns of the pair are the same echo: one point.
    Both,
    /// Ouster first (legacy and single profiles: the only) return; Hesai first return;
    /// Livox single-return types, or the first of a dual pair.
    First,
    /// Ouster second return (dual profiles); Livox second of a dual pair.
    Second,
}

/// Per-point attributes beside the coordinates and time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PointMeta {
    /// Velodyne: ring, 0 the lowest laser. Ouster: beam (row), 0 the highest. Hesai:
    /// channel, 0 the highest. Livox (no rings): the point's tag byte.
    pub ring: u16,
    /// Velodyne: firing column in the sweep (velodyne-decoder's numbering). Ouster:
    /// measurement id (column of the staggered image). Hesai: firing in the sweep. Livox:
    /// firing in the packet.
    pub column: u16,
    /// Which return.
    pub ret: Return,
    /// Velodyne and Hesai reflectivity byte; Ouster reflectivity (8 bits in the eUDP profiles).
    pub intensity: u16,
}

/// A chunk of a sweep's points, in arrival order; the three slices have one entry per point.
#[derive(Clone, Copy, Debug)]
pub struct Chunk<'a> {
    /// Sensor-frame coordinates in metres.
    pub xyz: &'a [[f64; 3]],
    /// Capture times in seconds since [`SweepStart::start_ns`].
    pub times: &'a [f64],
    /// Ring, column, return, intensity.
    pub meta: &'a [PointMeta],
}

/// What is known when a sweep begins.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SweepStart {
    /// Sweeps begun by this decoder before this one.
    pub index: u32,
    /// Sensor clock at the sweep's time origin, in ns. Velodyne: the first packet's
    /// timestamp (microseconds past the hour, counted on across hours). Ouster: the first
    /// column's timestamp. Hesai: the first packet's first firing (UTC, ns since the Unix
    /// epoch).
    pub start_ns: u64,
    /// Ouster frame id.
    pub frame_id: Option<u16>,
}

/// Why a sweep ended.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SweepEnd {
    /// Velodyne: the azimuth passed the cut. Ouster: the last column of the window arrived.
    #[default]
    Complete,
    /// Ouster: a packet of a later frame arrived before this frame's last column.
    NextFrame,
    /// Velodyne: more than [`crate::velodyne::GAP_NS`] since the sweep's first packet.
    Gap,
    /// The caller called `finish` (end of the recording).
    Finished,
    /// The packets' clock (Velodyne) or frame ids (Ouster) jumped and stayed there (a sensor
    /// restart, a clock step, a packet far ahead): the decoder gave up this sweep's timeline
    /// and took theirs ([`RESYNC_PACKETS`]).
    Resync,
}

/// Consecutive packets refused as older than the sweep, agreeing among themselves on a
/// timeline (times or frame ids moving on from one to the next), after which the decoder
/// takes their timeline: a sensor restarted or its clock stepped, or one packet far ahead
/// opened a sweep the others can never join. Those packets are dropped and counted in
/// `out_of_order`; the sweep that takes their timeline counts the resync in
/// [`SweepStats::resyncs`].
pub const RESYNC_PACKETS: u32 = 16;

/// Per-sweep packet statistics: what arrived, what was lost, what was refused.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SweepStats {
    /// As in [`SweepStart`].
    pub index: u32,
    /// As in [`SweepStart`].
    pub start_ns: u64,
    /// As in [`SweepStart`].
    pub frame_id: Option<u16>,
    /// Packets decoded into the sweep.
    pub packets: u32,
    /// Points handed to the sink.
    pub points: u32,
    /// Packets missing, estimated from timestamp gaps (Velodyne) or missing columns and frame
    /// ids (Ouster).
    pub lost_packets: u32,
    /// Late or repeated packets and packets whose time is too far ahead ([`PacketError::Ahead`])
    /// (dropped) and, for Ouster, columns out of order within the frame (decoded: their
    /// position is explicit).
    pub out_of_order: u32,
    /// Velodyne: azimuth jumps between consecutive packets that the timestamps do not explain.
    pub azimuth_jumps: u32,
    /// Packets refused as malformed (see `last_error`).
    pub bad_packets: u32,
    /// Packets refused as coming from another sensor ([`PacketError::OtherSensor`]) or, for
    /// Ouster, contradicting the metadata ([`PacketError::MetadataMismatch`],
    /// [`PacketError::MeasurementId`], [`PacketError::ColumnWindow`],
    /// [`PacketError::ColumnRate`]).
    pub other_sensor: u32,
    /// The last refusal's reason.
    pub last_error: Option<PacketError>,
    /// Times the decoder took a new timeline before this sweep ([`SweepEnd::Resync`]).
    pub resyncs: u32,
    /// Why the sweep ended.
    pub end: SweepEnd,
}

impl SweepStats {
    /// Counts a refused packet.
    pub(crate) fn refuse(&mut self, e: PacketError) {
        match e {
            PacketError::Late | PacketError::Ahead => {
                self.out_of_order = self.out_of_order.saturating_add(1)
            }
            PacketError::OtherSensor
            | PacketError::MetadataMismatch
            | PacketError::MeasurementId { .. }
            | PacketError::ColumnWindow
            | PacketError::ColumnRate => self.other_sensor = self.other_sensor.saturating_add(1),
            _ => self.bad_packets = self.bad_packets.saturating_add(1),
        }
        self.last_error = Some(e);
    }
}

/// What a decoder did with a packet it accepted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Pushed {
    /// Decoded into the open sweep (which may have begun with it).
    Decoded,
    /// Decoded, and it completed the sweep: `end_sweep` was the sink's last call.
    Ended,
    /// Not decoded: it begins a new sweep, so the open one was ended (`end_sweep` was the
    /// sink's only call). Push the same packet again. A push therefore never hands on points
    /// of two sweeps, so a caller can finish one frame before the next begins.
    Again,
}

/// A packet decoder (Velodyne or Ouster): packets in, sweeps to a [`SweepSink`] out.
pub trait Decode {
    /// Decodes one UDP payload from the sensor's data port, handing points and finished
    /// sweeps to `sink` (see [`Pushed`]: on `Again`, push the same bytes again). A refused
    /// packet changes nothing but the sweep's counters.
    fn push<S: SweepSink>(&mut self, bytes: &[u8], sink: &mut S) -> Result<Pushed, PacketError>;
    /// Ends the open sweep ([`SweepEnd::Finished`]): call at the end of a recording.
    fn finish<S: SweepSink>(&mut self, sink: &mut S);
    /// Refusals and losses counted since the last sweep ended that no sweep has taken yet
    /// (they go to the next one): after [`Self::finish`], what came after the last sweep.
    fn between_sweeps(&self) -> &SweepStats;
}

/// Receives sweeps from a decoder.
pub trait SweepSink {
    /// A sweep begins; points follow.
    fn begin_sweep(&mut self, start: &SweepStart);
    /// Points of the current sweep, in arrival order.
    fn points(&mut self, chunk: Chunk<'_>);
    /// The sweep ended; no more points for it.
    fn end_sweep(&mut self, stats: &SweepStats);
}

/// One chunk being filled, and the open sweep's bookkeeping.
pub(crate) struct Assembly {
    xyz: [[f64; 3]; CHUNK],
    times: [f64; CHUNK],
    meta: [PointMeta; CHUNK],
    len: usize,
    /// The open sweep, if any.
    pub open: Option<SweepStats>,
    /// Refusals and losses seen while no sweep was open: they go to the next one.
    pub pending: SweepStats,
    /// Sweeps begun so far.
    pub begun: u32,
}

impl Assembly {
    pub const fn new() -> Self {
        Self {
            xyz: [[0.0; 3]; CHUNK],
            times: [0.0; CHUNK],
            meta: [PointMeta {
                ring: 0,
                column: 0,
                ret: Return::Strongest,
                intensity: 0,
            }; CHUNK],
            len: 0,
            open: None,
            pending: SweepStats {
                index: 0,
                start_ns: 0,
                frame_id: None,
                packets: 0,
                points: 0,
                lost_packets: 0,
                out_of_order: 0,
                azimuth_jumps: 0,
                bad_packets: 0,
                other_sensor: 0,
                last_error: None,
                resyncs: 0,
                end: SweepEnd::Complete,
            },
            begun: 0,
        }
    }

    /// Passes a push's result on, counting a refusal in the sweep's statistics.
    pub fn counted<T>(&mut self, r: Result<T, PacketError>) -> Result<T, PacketError> {
        if let Err(e) = &r {
            self.stats().refuse(*e);
        }
        r
    }

    /// The statistics refusals go to: the open sweep's, or the next one's.
    pub fn stats(&mut self) -> &mut SweepStats {
        match &mut self.open {
            Some(s) => s,
            None => &mut self.pending,
        }
    }

    /// Opens a sweep (the caller has ended any open one).
    pub fn begin<S: SweepSink>(&mut self, sink: &mut S, start_ns: u64, frame_id: Option<u16>) {
        let start = SweepStart {
            index: self.begun,
            start_ns,
            frame_id,
        };
        self.begun = self.begun.wrapping_add(1);
        let mut stats = core::mem::take(&mut self.pending);
        stats.index = start.index;
        stats.start_ns = start_ns;
        stats.frame_id = frame_id;
        self.open = Some(stats);
        sink.begin_sweep(&start);
    }

    /// Adds a point to the open sweep, handing a full chunk on.
    pub fn push<S: SweepSink>(&mut self, sink: &mut S, xyz: [f64; 3], time: f64, meta: PointMeta) {
        if self.len == CHUNK {
            self.flush(sink);
        }
        if let (Some(p), Some(t), Some(m)) = (
            self.xyz.get_mut(self.len),
            self.times.get_mut(self.len),
            self.meta.get_mut(self.len),
        ) {
            *p = xyz;
            *t = time;
            *m = meta;
            self.len += 1;
            if let Some(s) = &mut self.open {
                s.points = s.points.saturating_add(1);
            }
        }
    }

    /// Hands the points gathered so far on.
    pub fn flush<S: SweepSink>(&mut self, sink: &mut S) {
        let n = self.len;
        if n > 0 {
            sink.points(Chunk {
                xyz: &self.xyz[..n],
                times: &self.times[..n],
                meta: &self.meta[..n],
            });
        }
        self.len = 0;
    }

    /// Counts a resync in the next sweep's statistics.
    pub fn resynced(&mut self) {
        self.pending.resyncs = self.pending.resyncs.saturating_add(1);
    }

    /// Closes the open sweep, if any.
    pub fn end<S: SweepSink>(&mut self, sink: &mut S, end: SweepEnd) {
        self.flush(sink);
        if let Some(mut stats) = self.open.take() {
            stats.end = end;
            sink.end_sweep(&stats);
        }
    }
}

/// Azimuth units per turn of the spinning sensors' packets (hundredths of a degree).
pub(crate) const AZIMUTH_UNITS: u16 = 36000;

/// `a` modulo one turn, in azimuth units.
pub(crate) fn wrap_azimuth(a: i32) -> u32 {
    a.rem_euclid(i32::from(AZIMUTH_UNITS)) as u32
}

/// Where a spinning sensor's sweep ends: at a fixed cut azimuth, or a full turn from wherever
/// the last one ended (velodyne-decoder's coverage rule). Sweeps are whole packets: the packet
/// whose last azimuth wraps past the start ends its sweep.
#[derive(Clone, Copy, Debug)]
pub(crate) struct AzimuthCut {
    cut: Option<u16>,
    initial: Option<u16>,
    coverage: u32,
}

impl AzimuthCut {
    /// A cut at `cut_angle_deg` (`[0, 360)`), or by coverage for `None`.
    pub fn new(cut_angle_deg: Option<f64>) -> Result<Self, crate::ConfigError> {
        let cut = match cut_angle_deg {
            None => None,
            Some(a) if a.is_finite() && (0.0..360.0).contains(&a) => {
                Some((libm::round(a * 100.0) as u32 % u32::from(AZIMUTH_UNITS)) as u16)
            }
            Some(_) => return Err(crate::ConfigError::CutAngle),
        };
        Ok(Self {
            cut,
            initial: cut,
            coverage: 0,
        })
    }

    /// A new sweep begins after the azimuth `last` (`None`: wherever the next packet is).
    pub fn restart(&mut self, last: Option<u16>) {
        self.initial = self.cut.or(last);
        self.coverage = 0;
    }

    /// Whether a packet whose last azimuth is `last` completes the sweep: it wrapped past the
    /// start after more than half a turn.
    pub fn passed(&mut self, last: u16) -> bool {
        let initial = *self.initial.get_or_insert(last);
        let coverage = wrap_azimuth(i32::from(last) - i32::from(initial));
        let complete = self.coverage > u32::from(AZIMUTH_UNITS) / 2 && self.coverage > coverage;
        self.coverage = coverage;
        complete
    }
}
