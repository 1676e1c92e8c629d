//! Packet continuity: each packet's time against the last one's, the decoders' shared rule
//! for cutting sweeps and frames by time only along a timeline the packets keep ([`Timeline`]),
//! and the packets missing between two consecutive ones ([`lost_between`]).

use crate::error::PacketError;
use crate::sweep::RESYNC_PACKETS;

/// Consecutive packets refused as older than the last one accepted, and the last one's time
/// (ns): after [`RESYNC_PACKETS`] of them whose times move on from one to the next, by at most
/// a decoder's gap, their timeline is the sensor's.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct LateRun(Option<(u32, u64)>);

impl LateRun {
    /// Counts a late packet of time `t`; true when it completes a run.
    pub fn complete(&mut self, t: u64, gap_ns: u64) -> bool {
        let n = match self.0 {
            Some((n, last)) if t > last && t - last <= gap_ns => n + 1,
            _ => 1,
        };
        self.0 = Some((n, t));
        n >= RESYNC_PACKETS
    }

    /// A packet in order ends any run.
    pub fn clear(&mut self) {
        self.0 = None;
    }
}

/// Packets missing in a time step of `step` between two consecutive packets sent `period`
/// apart: none up to one and a half periods, else the step in whole periods less one; none
/// for a period that is not a positive number (nothing to count by).
pub(crate) fn lost_in_step(step: f64, period: f64) -> u32 {
    if period > 0.0 && period.is_finite() && step > 1.5 * period {
        (libm::round(step / period) - 1.0).min(f64::from(u32::MAX)) as u32
    } else {
        0
    }
}

/// Packets missing between two consecutive packets `step_ns` apart, sent `period_ns` apart,
/// whose sequence numbers (if they carry any) differ by `sequence_step`: the sequence's count
/// where the time step agrees with it (a quarter of a period each, an eighth of the step
/// beside), else the time's. The caller passes only steps within its sweep's gap, so neither
/// count grows without bound: a wrong sequence number or time gives no absurd loss.
pub(crate) fn lost_between(step_ns: u64, period_ns: f64, sequence_step: Option<u32>) -> u32 {
    let step = step_ns as f64;
    match sequence_step {
        Some(d) if d >= 1 && agrees(step, d, period_ns) => d - 1,
        _ => lost_in_step(step, period_ns),
    }
}

/// Whether a time step agrees with `packets` packet periods.
fn agrees(step: f64, packets: u32, period: f64) -> bool {
    let want = f64::from(packets) * period;
    (step - want).abs() <= 0.5 * period + want / 8.0
}

/// The furthest after the last packet the next may come, ns: [`RESYNC_PACKETS`] periods, or
/// as many as its sequence number says came between and a period more, with a quarter of
/// those as slack. A packet further ahead is held out ([`PacketError::Ahead`]).
pub(crate) fn max_step_ns(period_ns: f64, sequence_step: Option<u32>) -> u64 {
    let packets = f64::from(sequence_step.unwrap_or(0)).max(f64::from(RESYNC_PACKETS));
    let ns = (1.25 * packets + 1.0) * period_ns;
    if ns.is_finite() && ns > 0.0 {
        ns.min(u64::MAX as f64) as u64
    } else {
        0
    }
}

/// Where a packet's time lies against the last packet accepted ([`Timeline::judge`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Step {
    /// The first packet of a timeline: no step to judge.
    First,
    /// After the last packet accepted, by this many ns.
    After(u64),
    /// [`RESYNC_PACKETS`] packets in a row came no later than the last one accepted and agree
    /// among themselves: their timeline is the sensor's now (a clock step back, a restart).
    /// The caller abandons the sweep's; this packet is the first of theirs.
    Resync,
}

/// The packets' times, one after the other: a sweep is cut by time only along a timeline its
/// packets keep. Each packet must come after the last one accepted (else it is late) by no
/// more than the packets between explain (else its time is a stray's, held out as
/// [`PacketError::Ahead`]); [`RESYNC_PACKETS`] refused packets in a row that agree on a
/// timeline of their own make it the sensor's, behind (a restart) or ahead (a pause).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Timeline {
    last: Option<u64>,
    late: LateRun,
    ahead: LateRun,
    /// The time of the packet that completed a run ahead: pushed again after its sweep ended,
    /// it is taken.
    taken: Option<u64>,
}

impl Timeline {
    /// Judges a packet of time `t` (ns) that may come at most `max_step` after the last one
    /// accepted; runs of refused packets agree when each follows the one before by at most
    /// `gap_ns`. Judging the same packet again gives the same answer, so it can be pushed
    /// again after it ended a sweep.
    pub fn judge(&mut self, t: u64, max_step: u64, gap_ns: u64) -> Result<Step, PacketError> {
        let Some(last) = self.last else {
            return Ok(Step::First);
        };
        if t <= last {
            self.ahead.clear();
            if !self.late.complete(t, gap_ns) {
                return Err(PacketError::Late);
            }
            *self = Self::default();
            return Ok(Step::Resync);
        }
        self.late.clear();
        let step = t - last;
        if step > max_step && self.taken != Some(t) {
            if !self.ahead.complete(t, gap_ns) {
                return Err(PacketError::Ahead);
            }
            self.taken = Some(t);
        }
        Ok(Step::After(step))
    }

    /// The packet of time `t` was decoded.
    pub fn accept(&mut self, t: u64) {
        *self = Self {
            last: Some(t),
            ..Self::default()
        };
    }

    /// Forgets the last packet (a sweep ended by a gap): the next is the first of a timeline.
    pub fn restart(&mut self) {
        *self = Self::default();
    }
}
