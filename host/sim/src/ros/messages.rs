//! The two messages a simulated recording of points carries, serialized from their definitions the two
//! ways ROS does: ROS 1 (bags: little-endian, packed, strings without a terminator) and CDR
//! (ROS 2: a 4-byte encapsulation header, little-endian here, each value aligned to its size
//! from the header's end, strings with a terminating NUL).
//!
//! A cloud's points are x, y, z and intensity as FLOAT32 (the frame files' values) and `time`
//! as FLOAT64, each point's capture time in seconds on the header's clock (the
//! `timestamps/` files' values), so a reader gets the folder's numbers bit for bit.

use crate::imu::ImuSample;
use crate::sensor::Frame;

/// A header stamp: whole seconds and nanoseconds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stamp {
    /// Seconds since the epoch (not negative).
    pub sec: u32,
    /// Nanoseconds, below 1e9.
    pub nsec: u32,
}

impl Stamp {
    /// The stamp of `t` seconds, to the nanosecond as `imu.csv` writes times (`{:.9}`), so
    /// that both give the same instant; `None` before 0 or after 2106.
    pub fn of(t: f64) -> Option<Self> {
        let text = format!("{t:.9}");
        let (sec, frac) = text.split_once('.')?;
        Some(Self {
            sec: sec.parse().ok()?,
            nsec: frac.parse().ok()?,
        })
    }

    /// Nanoseconds since the epoch.
    pub fn nanos(self) -> u64 {
        u64::from(self.sec) * 1_000_000_000 + u64::from(self.nsec)
    }
}

/// `sensor_msgs/PointField` datatypes used here.
const FLOAT32: u8 = 7;
const FLOAT64: u8 = 8;

/// The point layout: name, byte offset, datatype; 24 bytes a point.
const FIELDS: [(&str, u32, u8); 5] = [
    ("x", 0, FLOAT32),
    ("y", 4, FLOAT32),
    ("z", 8, FLOAT32),
    ("intensity", 12, FLOAT32),
    ("time", 16, FLOAT64),
];
const POINT_STEP: u32 = 24;

/// The points of `frame` in the layout of [`FIELDS`].
fn point_data(frame: &Frame) -> Vec<u8> {
    let mut data = Vec::with_capacity(frame.points.len() * POINT_STEP as usize);
    for (p, t) in frame.points.iter().zip(&frame.stamps) {
        for v in p {
            data.extend_from_slice(&v.to_le_bytes());
        }
        data.extend_from_slice(&t.to_le_bytes());
    }
    data
}

/// Appends values with ROS 1's or CDR's rules.
pub(super) struct Out {
    pub(super) bytes: Vec<u8>,
    /// Where CDR alignment counts from; `None` for ROS 1 (no alignment).
    cdr_origin: Option<usize>,
}

impl Out {
    fn ros1() -> Self {
        Self {
            bytes: Vec::new(),
            cdr_origin: None,
        }
    }

    /// Little-endian plain CDR: the encapsulation header first.
    fn cdr() -> Self {
        Self {
            bytes: vec![0, 1, 0, 0],
            cdr_origin: Some(4),
        }
    }

    pub(super) fn align(&mut self, n: usize) {
        if let Some(origin) = self.cdr_origin {
            while (self.bytes.len() - origin) % n != 0 {
                self.bytes.push(0);
            }
        }
    }

    pub(super) fn u8(&mut self, v: u8) {
        self.bytes.push(v);
    }

    pub(super) fn u32(&mut self, v: u32) {
        self.align(4);
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    pub(super) fn f64(&mut self, v: f64) {
        self.align(8);
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    pub(super) fn string(&mut self, s: &str) {
        let nul = usize::from(self.cdr_origin.is_some());
        self.u32((s.len() + nul) as u32);
        self.bytes.extend_from_slice(s.as_bytes());
        if nul == 1 {
            self.bytes.push(0);
        }
    }

    /// `std_msgs/Header`: ROS 1 has a `seq` first.
    pub(super) fn header(&mut self, seq: u32, stamp: Stamp, frame_id: &str) {
        if self.cdr_origin.is_none() {
            self.u32(seq);
        }
        self.u32(stamp.sec);
        self.u32(stamp.nsec);
        self.string(frame_id);
    }

    pub(super) fn bytes(&mut self, data: &[u8]) {
        self.u32(data.len() as u32);
        self.bytes.extend_from_slice(data);
    }
}

/// Which serialization.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// ROS 1, for bags.
    Ros1,
    /// CDR, for ROS 2's MCAP files.
    Cdr,
}

impl Encoding {
    pub(super) fn out(self) -> Out {
        match self {
            Self::Ros1 => Out::ros1(),
            Self::Cdr => Out::cdr(),
        }
    }
}

/// `sensor_msgs/PointCloud2` of `frame`, stamped `stamp`: one row of its points.
pub fn point_cloud2(enc: Encoding, frame: &Frame, stamp: Stamp, frame_id: &str) -> Vec<u8> {
    let data = point_data(frame);
    let width = frame.points.len() as u32;
    let mut o = enc.out();
    o.header(frame.index as u32, stamp, frame_id);
    o.u32(1); // height
    o.u32(width);
    o.u32(FIELDS.len() as u32);
    for (name, offset, datatype) in FIELDS {
        o.string(name);
        o.u32(offset);
        o.u8(datatype);
        o.u32(1); // count
    }
    o.u8(0); // is_bigendian
    o.u32(POINT_STEP);
    o.u32(POINT_STEP * width); // row_step
    o.bytes(&data);
    o.u8(1); // is_dense
    o.bytes
}

/// `sensor_msgs/Imu` of `sample`, stamped `stamp`: no orientation (its covariance's first
/// element -1, as REP 145 asks), covariances unknown (0).
pub fn imu(enc: Encoding, seq: u32, sample: &ImuSample, stamp: Stamp, frame_id: &str) -> Vec<u8> {
    let mut o = enc.out();
    o.header(seq, stamp, frame_id);
    for v in [0.0, 0.0, 0.0, 1.0] {
        o.f64(v);
    }
    let covariance = |o: &mut Out, first: f64| {
        o.f64(first);
        for _ in 1..9 {
            o.f64(0.0);
        }
    };
    covariance(&mut o, -1.0);
    for v in sample.gyro {
        o.f64(v);
    }
    covariance(&mut o, 0.0);
    for v in sample.accel {
        o.f64(v);
    }
    covariance(&mut o, 0.0);
    o.bytes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamps_are_the_nanoseconds_imu_csv_writes() {
        assert_eq!(
            Stamp::of(12.5),
            Some(Stamp {
                sec: 12,
                nsec: 500_000_000
            })
        );
        assert_eq!(Stamp::of(0.1).map(Stamp::nanos), Some(100_000_000));
        assert_eq!(Stamp::of(-0.5), None);
    }

    #[test]
    fn an_imu_message_has_the_definitions_length() {
        let s = ImuSample {
            time: 1.0,
            gyro: [1.0, 2.0, 3.0],
            accel: [4.0, 5.0, 6.0],
        };
        let stamp = Stamp { sec: 1, nsec: 0 };
        // ROS 1: seq, stamp, frame id "imu" (4 + 3), 37 f64.
        assert_eq!(imu(Encoding::Ros1, 0, &s, stamp, "imu").len(), 12 + 7 + 296);
        // CDR: header, stamp, "imu\0" (4 + 4), padding to 8, 37 f64.
        assert_eq!(imu(Encoding::Cdr, 0, &s, stamp, "imu").len(), 4 + 16 + 296);
    }
}
