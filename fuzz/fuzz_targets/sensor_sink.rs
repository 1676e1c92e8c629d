//! A sink for the sensor decoders' fuzz targets that checks the sweep protocol: begin and end
//! alternate, chunks come only inside a sweep, are non-empty, at most `CHUNK` long, with one
//! time and one meta per point, every coordinate and time finite, and the points counted in the statistics are those handed on.
#![allow(dead_code)]

use kiss_odom_sensors::{Chunk, PacketError, Pushed, SweepSink, SweepStart, SweepStats, CHUNK};

/// Pushes a packet as a caller must: again after `Pushed::Again`, which must not repeat and
/// must have ended the sweep without handing on points.
pub fn feed(sink: &mut Checked, mut push: impl FnMut(&mut Checked) -> Result<Pushed, PacketError>) {
    if push(sink) == Ok(Pushed::Again) {
        assert!(sink.open.is_none(), "Again left a sweep open");
        assert_ne!(push(sink), Ok(Pushed::Again), "Again twice");
    }
}

#[derive(Default)]
pub struct Checked {
    open: Option<SweepStart>,
    points: u32,
    /// The most packets one accepted packet may count as lost before it (no bound if `None`).
    lost_per_packet: Option<u64>,
}

impl Checked {
    /// A sink that also checks that no sweep counts more than `most` packets lost per packet.
    pub fn with_lost_per_packet(most: u64) -> Self {
        Self {
            lost_per_packet: Some(most),
            ..Self::default()
        }
    }
}

impl SweepSink for Checked {
    fn begin_sweep(&mut self, s: &SweepStart) {
        assert!(self.open.is_none(), "begin inside a sweep");
        self.open = Some(*s);
        self.points = 0;
    }
    fn points(&mut self, c: Chunk<'_>) {
        assert!(self.open.is_some(), "points outside a sweep");
        assert!(!c.xyz.is_empty() && c.xyz.len() <= CHUNK);
        assert!(c.xyz.len() == c.times.len() && c.times.len() == c.meta.len());
        assert!(c.xyz.iter().flatten().chain(c.times).all(|v| v.is_finite()));
        self.points += c.xyz.len() as u32;
    }
    fn end_sweep(&mut self, s: &SweepStats) {
        let start = self.open.take().expect("end outside a sweep");
        assert_eq!(s.index, start.index);
        assert_eq!(s.points, self.points);
        if let Some(most) = self.lost_per_packet {
            let (lost, packets) = (u64::from(s.lost_packets), u64::from(s.packets));
            assert!(
                lost <= most * packets,
                "{lost} packets lost in a sweep of {packets}"
            );
        }
    }
}
