//! Sensor sweeps as frames: a pcap recording (or a live socket) decoded by
//! [`super::sweeps`] becomes a [`FrameSource`], so `run` and `live` drive
//! its sweeps through the same frame loop as any dataset.
//!
//! Frame `k` is the `k`-th sweep decoded, named `file#k`; it carries its per-point times (for
//! deskewing) and its [`SweepInfo`](crate::SweepInfo) (packet statistics for
//! `frames.csv`, the instants `output.pose_time` chooses from), at most `scan_points` points (the
//! rest counted and warned about as the sweep fills), and a warning when the decoder took a
//! new timeline before it. What only the whole recording shows (packets from a second
//! sender, refused packets, frames the capture could not read) is reported once, naming the
//! file, when the source has ended: as warnings of the last frame if it had ended by then,
//! otherwise in the [`Trailer`]; packets refused after the last sweep are added to the last
//! frame's statistics or the trailer's. A capture that ends in damage ends the stream with
//! its error.
//!
//! A sweep the recording ends in ([`SweepEnd::Finished`]) with fewer packets than the whole
//! sweeps before it (under 98 % of the most they held) is not a frame: registering part of a turn (or of a Livox frame's period)
//! gives a pose that is off, so it is dropped, with a warning giving its packets and a whole
//! sweep's; its packets go in the trailer's, so the totals still count them. A recording of
//! one sweep, or one whose sweeps never ended whole, keeps it.

use super::sweeps::{self, PcapSweeps};
use crate::dataset::{Dataset, DatasetInfo, Format, FrameSource, Item, OpenOptions, Trailer};
use anyhow::Result;
use kiss_odom_sensors::{SweepEnd, SweepStats, RESYNC_PACKETS};
use std::path::Path;

/// Sweeps of a decoder as frames.
pub struct SweepFrames {
    sweeps: PcapSweeps,
    name: String,
    next: usize,
    scan_points: usize,
    /// Whether the end-of-stream report has been handed on.
    reported: bool,
    /// The most packets a sweep that ended whole held so far.
    whole_packets: u32,
    /// The warning and refusals of an open sweep at the end that was dropped.
    dropped: Option<(String, SweepStats)>,
}

impl SweepFrames {
    /// Frames of `sweeps`, named after `name`, each at most `scan_points` points.
    pub fn new(mut sweeps: PcapSweeps, name: &str, scan_points: usize) -> Self {
        sweeps.limit_points(scan_points);
        Self {
            sweeps,
            name: name.to_string(),
            next: 0,
            scan_points,
            reported: false,
            whole_packets: 0,
            dropped: None,
        }
    }

    /// The report of the whole stream, once.
    fn end_report(&mut self) -> Trailer {
        self.reported = true;
        let file = &self.name;
        let mut after = self.sweeps.after_last_sweep();
        let mut warnings: Vec<String> = (self.sweeps.report().warnings().iter())
            .map(|w| format!("{file}: {w}"))
            .collect();
        let dropped = self.dropped.take().map(|(w, stats)| {
            warnings.insert(0, w);
            add_refusals(&mut after, &stats);
            after.packets = after.packets.saturating_add(stats.packets);
        });
        let refused = after.lost_packets + after.out_of_order + after.bad_packets;
        Trailer {
            warnings,
            packets: (refused + after.other_sensor > 0 || dropped.is_some()).then_some(after),
        }
    }
}

/// Opens a pcap or pcapng recording as a dataset.
pub fn open(path: &Path, opts: &OpenOptions) -> Result<Dataset> {
    let sweeps = sweeps::open(path, &opts.sensor)?;
    Ok(Dataset {
        frames: Box::new(SweepFrames::new(
            sweeps,
            &path.display().to_string(),
            opts.scan_points,
        )),
        info: DatasetInfo {
            format: Some(Format::Pcap),
            ..DatasetInfo::default()
        },
    })
}

/// Adds packets refused or lost outside every sweep to a sweep's statistics.
pub fn add_refusals(into: &mut SweepStats, from: &SweepStats) {
    into.lost_packets = into.lost_packets.saturating_add(from.lost_packets);
    into.out_of_order = into.out_of_order.saturating_add(from.out_of_order);
    into.bad_packets = into.bad_packets.saturating_add(from.bad_packets);
    into.other_sensor = into.other_sensor.saturating_add(from.other_sensor);
}

impl FrameSource for SweepFrames {
    fn len_hint(&self) -> Option<usize> {
        None
    }

    fn next_item(&mut self) -> Result<Option<Item>> {
        let Some(sweep) = self.sweeps.next().transpose()? else {
            return Ok(None);
        };
        let stats = sweep.stats;
        if matches!(stats.end, SweepEnd::Complete | SweepEnd::NextFrame) {
            self.whole_packets = self.whole_packets.max(stats.packets);
        }
        // Whole sweeps differ by a packet or two where the turn falls between packets.
        let short = u64::from(stats.packets) * 50 < u64::from(self.whole_packets) * 49;
        if stats.end == SweepEnd::Finished && short {
            self.dropped = Some((
                format!(
                    "{}#{}: the recording ends in this sweep, {} packet(s) into it (a whole one \
                     had {}): not registered",
                    self.name, self.next, stats.packets, self.whole_packets
                ),
                stats,
            ));
            // The open sweep is the last: the rest of the report goes in the trailer.
            return Ok(None);
        }
        let index = self.next;
        self.next += 1;
        let name = format!("{}#{index}", self.name);
        let (beyond, resyncs) = (sweep.beyond_capacity, sweep.stats.resyncs);
        let mut frame = sweep.into_frame(index, name);
        if beyond > 0 {
            frame.warnings.push(format!(
                "{}: {} points, only the first {} read (the core's scan capacity)",
                frame.name,
                frame.points.len() as u64 + beyond,
                self.scan_points
            ));
        }
        if resyncs > 0 {
            frame.warnings.push(format!(
                "{}: the packets' clock or frame ids jumped and stayed there (a sensor restart, \
                 a clock step, a packet far ahead): decoding resynchronised to them after {} \
                 packets refused as older than the sweep",
                frame.name,
                RESYNC_PACKETS - 1
            ));
        }
        if self.sweeps.exhausted() && !self.reported {
            let t = self.end_report();
            frame.warnings.extend(t.warnings);
            if let (Some(p), Some(s)) = (t.packets, &mut frame.sweep) {
                add_refusals(&mut s.stats, &p);
            }
        }
        Ok(Some(Item::Frame(frame)))
    }

    fn trailer(&mut self) -> Trailer {
        if self.reported {
            return Trailer::default();
        }
        self.end_report()
    }
}
