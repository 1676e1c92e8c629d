//! Sensor sweeps as frames: a pcap recording (or a live socket) decoded by
//! [`sensor_pcap`] becomes a [`FrameSource`], so `run` and `live` drive
//! its sweeps through the same frame loop as any dataset.
//!
//! Frame `k` is the `k`-th sweep decoded, named `file#k`; it carries its per-point times (for
//! deskewing) and its [`SweepInfo`](super::sensor_pcap::SweepInfo) (packet statistics for
//! `frames.csv`, the instants `--pose-time` chooses from). What only the whole recording shows
//! (packets from a second sender, refused packets) is reported as warnings of the last frame,
//! naming the file; a capture that ends in damage ends the stream with its error.

use super::sensor_pcap::{self, PcapSweeps};
use super::{Dataset, DatasetInfo, Format, FrameSource, Item, OpenOptions};
use anyhow::Result;
use std::path::Path;

/// Sweeps of a decoder as frames.
pub struct SweepFrames {
    sweeps: PcapSweeps,
    name: String,
    next: usize,
    scan_points: usize,
}

impl SweepFrames {
    /// Frames of `sweeps`, named after `name`, each at most `scan_points` points.
    pub fn new(sweeps: PcapSweeps, name: &str, scan_points: usize) -> Self {
        Self {
            sweeps,
            name: name.to_string(),
            next: 0,
            scan_points,
        }
    }
}

/// Opens a pcap or pcapng recording as a dataset.
pub fn open(path: &Path, opts: &OpenOptions) -> Result<Dataset> {
    let sweeps = sensor_pcap::open(path, &opts.sensor)?;
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

impl FrameSource for SweepFrames {
    fn len_hint(&self) -> Option<usize> {
        None
    }

    fn next_item(&mut self) -> Result<Option<Item>> {
        let Some(sweep) = self.sweeps.next().transpose()? else {
            return Ok(None);
        };
        let index = self.next;
        self.next += 1;
        let name = format!("{}#{index}", self.name);
        let mut frame = sweep.into_frame(index, name);
        if frame.points.len() > self.scan_points {
            frame.warnings.push(format!(
                "{}: {} points, only the first {} read (the core's scan capacity)",
                frame.name,
                frame.points.len(),
                self.scan_points
            ));
            frame.points.truncate(self.scan_points);
            if let Some(s) = &mut frame.stamps {
                s.truncate(self.scan_points);
            }
            if let Some(i) = &mut frame.intensity {
                i.truncate(self.scan_points);
            }
        }
        if self.sweeps.exhausted() {
            let file = &self.name;
            let report = self.sweeps.report();
            frame
                .warnings
                .extend(report.warnings().iter().map(|w| format!("{file}: {w}")));
        }
        Ok(Some(Item::Frame(frame)))
    }
}
