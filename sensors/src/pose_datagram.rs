//! The pose datagram: what a receiver that runs the odometry (the firmware in `embedded/`) sends
//! back for each sweep, one UDP datagram of [`field::LEN`] bytes, little-endian.
//!
//! It carries the sweep's pose and the core's status, and the receiver's running counts of
//! what it took from the wire and what it refused, so a consumer sees every loss without a
//! second channel. `kiss-odom listen-poses` reads it into `run`'s outputs.
//!
//! | bytes | field | |
//! |---|---|---|
//! | 0..4 | magic | `KOPD` |
//! | 4..6 | version | 1 |
//! | 6..8 | link flags | [`Link`] bits |
//! | 8..12 | sweep | index from 0, counting every sweep the receiver ended |
//! | 12..16 | points | points the decoder gave the sweep |
//! | 16..24 | start_ns | the sweep's first packet, sensor clock (ns) |
//! | 24..120 | pose | `[R \| t]` row-major, 12 x f64 (the KITTI line) |
//! | 120..122 | status | the core's `Status` bits (0 = ok) |
//! | 122..124 | iterations | ICP iterations |
//! | 124..128 | sweep_lost | packets the decoder found missing in this sweep |
//! | 128..160 | [`Counters`] | 8 x u32, totals since start |

use core::ops::Range;

/// Byte ranges of the datagram.
pub mod field {
    use super::Range;
    /// `KOPD`.
    pub const MAGIC: Range<usize> = 0..4;
    /// Format version, [`super::VERSION`].
    pub const VERSION: Range<usize> = 4..6;
    /// [`super::Link`] bits.
    pub const LINK: Range<usize> = 6..8;
    /// Sweep index.
    pub const SWEEP: Range<usize> = 8..12;
    /// Points in the sweep.
    pub const POINTS: Range<usize> = 12..16;
    /// Sensor time of the sweep's first packet, ns.
    pub const START_NS: Range<usize> = 16..24;
    /// The pose, 12 f64.
    pub const POSE: Range<usize> = 24..120;
    /// The core's status bits.
    pub const STATUS: Range<usize> = 120..122;
    /// ICP iterations.
    pub const ITERATIONS: Range<usize> = 122..124;
    /// Packets missing in this sweep.
    pub const SWEEP_LOST: Range<usize> = 124..128;
    /// The counters, 8 u32.
    pub const COUNTERS: Range<usize> = 128..160;
    /// Length of a datagram.
    pub const LEN: usize = 160;
}

/// Start of every datagram.
pub const MAGIC: [u8; 4] = *b"KOPD";
/// The layout's version.
pub const VERSION: u16 = 1;

/// What happened on the link during the sweep, one bit each.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u16)]
pub enum Link {
    /// The core refused the sweep (`FrameError`): the pose is the previous one.
    FrameError = 1 << 0,
    /// The decoder found packets missing in the sweep (`sweep_lost`).
    Gap = 1 << 1,
    /// The sweep was ended by silence on the port, not by the sensor (the recording stopped).
    Idle = 1 << 2,
    /// Datagrams from a second sender came during the sweep (counted, skipped).
    Foreign = 1 << 3,
    /// Datagrams of the wrong length came during the sweep (counted, skipped).
    WrongSize = 1 << 4,
    /// Frames were dropped during the sweep because the receive ring was full.
    Overflow = 1 << 5,
    /// The decoder refused packets during the sweep (corrupt, another model).
    Bad = 1 << 6,
}

impl Link {
    /// Every bit, in order.
    pub const ALL: [Link; 7] = [
        Link::FrameError,
        Link::Gap,
        Link::Idle,
        Link::Foreign,
        Link::WrongSize,
        Link::Overflow,
        Link::Bad,
    ];
    /// The bit's name in `frames.csv`.
    pub const fn name(self) -> &'static str {
        match self {
            Link::FrameError => "frame_error",
            Link::Gap => "gap",
            Link::Idle => "idle",
            Link::Foreign => "foreign",
            Link::WrongSize => "wrong_size",
            Link::Overflow => "overflow",
            Link::Bad => "bad",
        }
    }
}

/// The receiver's running totals since it started.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    /// Datagrams taken from the sensor and handed to the decoder.
    pub packets: u32,
    /// Packets the decoder found missing (gaps in the sensor's sequence).
    pub lost: u32,
    /// Packets the decoder refused (corrupt, another model or mode).
    pub bad: u32,
    /// Datagrams on the port from a second sender.
    pub foreign: u32,
    /// Datagrams of the wrong length for the sensor (oversized, truncated).
    pub wrong_size: u32,
    /// Ethernet frames dropped because the receive ring was full.
    pub overflow: u32,
    /// Pose datagrams that could not be queued for sending.
    pub unsent: u32,
    /// Sweeps the core refused.
    pub frame_errors: u32,
}

impl Counters {
    /// Each counter with its name (a `frames.csv` column, a `summary.json` field), in the
    /// datagram's order.
    pub fn named(&self) -> [(&'static str, u32); 8] {
        [
            ("packets", self.packets),
            ("lost", self.lost),
            ("bad", self.bad),
            ("foreign", self.foreign),
            ("wrong_size", self.wrong_size),
            ("overflow", self.overflow),
            ("unsent", self.unsent),
            ("frame_errors", self.frame_errors),
        ]
    }
    fn words(&self) -> [u32; 8] {
        self.named().map(|(_, v)| v)
    }
    fn from_words(w: [u32; 8]) -> Self {
        Self {
            packets: w[0],
            lost: w[1],
            bad: w[2],
            foreign: w[3],
            wrong_size: w[4],
            overflow: w[5],
            unsent: w[6],
            frame_errors: w[7],
        }
    }
}

/// One sweep's datagram.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseDatagram {
    /// [`Link`] bits.
    pub link: u16,
    /// Sweep index.
    pub sweep: u32,
    /// Points in the sweep.
    pub points: u32,
    /// Sensor time of the sweep's first packet, ns.
    pub start_ns: u64,
    /// `[R | t]` row-major.
    pub pose: [f64; 12],
    /// The core's status bits.
    pub status: u16,
    /// ICP iterations.
    pub iterations: u16,
    /// Packets missing in this sweep.
    pub sweep_lost: u32,
    /// Totals since start.
    pub counters: Counters,
}

/// Why bytes are not a pose datagram.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PoseDatagramError {
    /// Not [`field::LEN`] bytes.
    Length,
    /// Does not start with [`MAGIC`].
    Magic,
    /// Another layout version.
    Version,
}

impl core::fmt::Display for PoseDatagramError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            PoseDatagramError::Length => "not 160 bytes",
            PoseDatagramError::Magic => "does not start with KOPD",
            PoseDatagramError::Version => "another layout version",
        })
    }
}

fn put(out: &mut [u8; field::LEN], at: Range<usize>, bytes: &[u8]) {
    if let Some(dst) = out.get_mut(at) {
        dst.copy_from_slice(bytes);
    }
}

fn get<const N: usize>(buf: &[u8; field::LEN], at: Range<usize>) -> [u8; N] {
    buf.get(at)
        .and_then(|s| s.try_into().ok())
        .unwrap_or([0; N])
}

impl PoseDatagram {
    /// Whether `bit` is set in [`Self::link`].
    pub fn has(&self, bit: Link) -> bool {
        self.link & bit as u16 != 0
    }

    /// The datagram's bytes.
    pub fn encode(&self) -> [u8; field::LEN] {
        let mut out = [0u8; field::LEN];
        put(&mut out, field::MAGIC, &MAGIC);
        put(&mut out, field::VERSION, &VERSION.to_le_bytes());
        put(&mut out, field::LINK, &self.link.to_le_bytes());
        put(&mut out, field::SWEEP, &self.sweep.to_le_bytes());
        put(&mut out, field::POINTS, &self.points.to_le_bytes());
        put(&mut out, field::START_NS, &self.start_ns.to_le_bytes());
        for (k, v) in self.pose.iter().enumerate() {
            let at = field::POSE.start + 8 * k;
            put(&mut out, at..at + 8, &v.to_le_bytes());
        }
        put(&mut out, field::STATUS, &self.status.to_le_bytes());
        put(&mut out, field::ITERATIONS, &self.iterations.to_le_bytes());
        put(&mut out, field::SWEEP_LOST, &self.sweep_lost.to_le_bytes());
        for (k, v) in self.counters.words().iter().enumerate() {
            let at = field::COUNTERS.start + 4 * k;
            put(&mut out, at..at + 4, &v.to_le_bytes());
        }
        out
    }

    /// Reads a datagram, checking its length, magic and version first.
    pub fn decode(bytes: &[u8]) -> Result<Self, PoseDatagramError> {
        let buf: &[u8; field::LEN] = bytes.try_into().map_err(|_| PoseDatagramError::Length)?;
        if get::<4>(buf, field::MAGIC) != MAGIC {
            return Err(PoseDatagramError::Magic);
        }
        if u16::from_le_bytes(get(buf, field::VERSION)) != VERSION {
            return Err(PoseDatagramError::Version);
        }
        let pose = core::array::from_fn(|k| {
            let at = field::POSE.start + 8 * k;
            f64::from_le_bytes(get(buf, at..at + 8))
        });
        let words = core::array::from_fn(|k| {
            let at = field::COUNTERS.start + 4 * k;
            u32::from_le_bytes(get(buf, at..at + 4))
        });
        Ok(Self {
            link: u16::from_le_bytes(get(buf, field::LINK)),
            sweep: u32::from_le_bytes(get(buf, field::SWEEP)),
            points: u32::from_le_bytes(get(buf, field::POINTS)),
            start_ns: u64::from_le_bytes(get(buf, field::START_NS)),
            pose,
            status: u16::from_le_bytes(get(buf, field::STATUS)),
            iterations: u16::from_le_bytes(get(buf, field::ITERATIONS)),
            sweep_lost: u32::from_le_bytes(get(buf, field::SWEEP_LOST)),
            counters: Counters::from_words(words),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> PoseDatagram {
        PoseDatagram {
            link: Link::Gap as u16 | Link::Foreign as u16,
            sweep: 0x0102_0304,
            points: 28_800,
            start_ns: 0x1122_3344_5566_7788,
            pose: core::array::from_fn(|k| k as f64 * 0.1 - 0.3),
            status: 0x0180,
            iterations: 17,
            sweep_lost: 3,
            counters: Counters::from_words(core::array::from_fn(|k| 1000 + k as u32)),
        }
    }

    #[test]
    fn round_trips_every_field() {
        let d = sample();
        assert_eq!(PoseDatagram::decode(&d.encode()), Ok(d));
    }

    #[test]
    fn fields_sit_at_their_documented_bytes() {
        let b = sample().encode();
        assert_eq!(&b[0..4], b"KOPD");
        assert_eq!(&b[4..6], &[1, 0]);
        assert_eq!(&b[8..12], &[4, 3, 2, 1]);
        assert_eq!(&b[16..24], &0x1122_3344_5566_7788u64.to_le_bytes());
        assert_eq!(&b[24..32], &(-0.3f64).to_le_bytes());
        assert_eq!(&b[112..120], &(11.0 * 0.1 - 0.3f64).to_le_bytes());
        assert_eq!(&b[120..122], &[0x80, 0x01]);
        assert_eq!(&b[128..132], &1000u32.to_le_bytes());
        assert_eq!(&b[156..160], &1007u32.to_le_bytes());
    }

    #[test]
    fn refuses_what_is_not_a_datagram() {
        let b = sample().encode();
        assert_eq!(
            PoseDatagram::decode(&b[..159]),
            Err(PoseDatagramError::Length)
        );
        let mut m = b;
        m[0] = b'X';
        assert_eq!(PoseDatagram::decode(&m), Err(PoseDatagramError::Magic));
        let mut v = b;
        v[4] = 2;
        assert_eq!(PoseDatagram::decode(&v), Err(PoseDatagramError::Version));
    }

    #[test]
    fn link_bits_are_distinct_and_named() {
        let mut all = 0u16;
        for bit in Link::ALL {
            assert_eq!(all & bit as u16, 0, "{}", bit.name());
            all |= bit as u16;
            let d = PoseDatagram {
                link: bit as u16,
                ..sample()
            };
            assert!(d.has(bit) && !d.has(Link::Idle) || bit == Link::Idle);
        }
        assert_eq!(all, 0x7f);
    }
}
