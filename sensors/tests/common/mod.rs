//! What the Hesai and Livox decoder tests share: a sink that keeps everything, and a push as a
//! caller must do it.

use kiss_odom_sensors::{
    Chunk, Decode, PacketError, PointMeta, Pushed, SweepSink, SweepStart, SweepStats,
};

/// Everything a decoder hands on.
#[derive(Default)]
pub struct Log {
    pub starts: Vec<SweepStart>,
    pub ends: Vec<SweepStats>,
    /// (sweep, xyz, time, meta) of every point.
    pub points: Vec<(usize, [f64; 3], f64, PointMeta)>,
}

impl SweepSink for Log {
    fn begin_sweep(&mut self, s: &SweepStart) {
        assert_eq!(self.starts.len(), self.ends.len(), "begin inside a sweep");
        self.starts.push(*s);
    }
    fn points(&mut self, c: Chunk<'_>) {
        let sweep = self.starts.len() - 1;
        for ((p, t), m) in c.xyz.iter().zip(c.times).zip(c.meta) {
            self.points.push((sweep, *p, *t, *m));
        }
    }
    fn end_sweep(&mut self, s: &SweepStats) {
        self.ends.push(*s);
    }
}

/// Pushes `bytes`, again when the decoder says they begin a new sweep.
pub fn feed<D: Decode>(dec: &mut D, bytes: &[u8], log: &mut Log) -> Result<Pushed, PacketError> {
    match dec.push(bytes, log)? {
        Pushed::Again => {
            let second = dec.push(bytes, log)?;
            assert_ne!(second, Pushed::Again, "two Again in a row");
            Ok(second)
        }
        p => Ok(p),
    }
}

/// `b` with byte `at` set to `v`.
pub fn with(b: &[u8], at: usize, v: u8) -> Vec<u8> {
    let mut b = b.to_vec();
    b[at] = v;
    b
}
