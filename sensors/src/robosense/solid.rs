//! The Robosense models whose every return carries its own direction, frames cut by the packet
//! sequence number: the MEMS RS-M1 and the solid-state (flash) E1R.
//!
//! ```text
//! header (32 bytes): id 55 AA 5A A5 | pkt_seq u16 at 4 | protocol u16 | return mode at 8 |
//!                    time mode | UTC s (48-bit) + us (32-bit) at 10..20 | ... | temperature
//! RS-M1, 1210 bytes: 25 blocks of 47 bytes at 32: time offset u8 (us after the packet time) |
//!     return seq u8 | 5 channels x (distance u16, pitch u16, yaw u16, intensity, attribute,
//!     elongation)
//! E1R, 1200 bytes: 96 blocks of 12 bytes at 32: time offset u16 (us) | distance u16 | x, y, z
//!     i16 | intensity | attribute; 16 bytes reserved
//! ```
//! Big-endian; distance in 5 mm. M1: pitch and yaw in 0.01 degree offset by 32768, a point is
//! `d (cos p cos y, cos p sin y, sin p)`. E1R: the direction as a vector of 32768ths, a point
//! is `d (x, y, z) / 32768`. The packet sequence starts again at 1 with each frame (M1: 630
//! packets a 10 Hz frame in single return; E1R: 288). Source: rs_driver `decoder_RSM1.hpp`
//! (`RSM1MsopPkt`, `decodeMsopPkt`, `SplitStrategyBySeq`) and `decoder_RSE1.hpp`
//! (`RSEOSMsopPkt`, `VECTOR_BASE`), commit 4eeadace. Their DIFOP packets carry no angles the
//! points need: they are not read.

use crate::error::PacketError;
use crate::sweep::{Assembly, Decode, PointMeta, Pushed, Return, SweepEnd, SweepSink, SweepStats};

/// The MSOP packet's first bytes.
pub const ID: [u8; 4] = [0x55, 0xAA, 0x5A, 0xA5];
/// Where the header's sequence number (u16), return-mode byte and UTC time (10 bytes) begin.
pub const SEQ: usize = 4;
/// See [`SEQ`].
pub const RETURN_MODE: usize = 8;
/// See [`SEQ`].
pub const STAMP: usize = 10;
/// Where the first block begins.
pub const BLOCKS_AT: usize = 32;
/// Metres per distance unit.
pub const DISTANCE_RES_M: f64 = 0.005;
/// Angle offset of the M1's pitch and yaw, hundredths of a degree.
const ANGLE_OFFSET: i32 = 32768;
/// The E1R's direction vector: 32768ths (rs_driver's `VECTOR_BASE`).
pub const VECTOR_BASE: f64 = 32768.0;
/// A frame whose packets span more than this (sensor time) ends.
pub const GAP_NS: u64 = 300_000_000;
/// Bytes of an RS-M1 MSOP packet.
pub const M1_LEN: usize = 1210;
/// Bytes of an E1R MSOP packet.
pub const E1R_LEN: usize = 1200;

/// A model whose returns carry their directions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Model {
    /// RS-M1 (MEMS): five channels a block, each return its pitch and yaw.
    M1,
    /// E1R (solid state): one return a block, its direction as a vector.
    E1r,
}

impl Model {
    /// Bytes of its MSOP packet.
    pub const fn packet_len(self) -> usize {
        match self {
            Self::M1 => M1_LEN,
            Self::E1r => E1R_LEN,
        }
    }
    /// Blocks a packet.
    pub const fn blocks(self) -> usize {
        match self {
            Self::M1 => 25,
            Self::E1r => 96,
        }
    }
    /// Returns a block.
    pub const fn channels(self) -> usize {
        match self {
            Self::M1 => 5,
            Self::E1r => 1,
        }
    }
    /// Bytes of a block: its time offset (and the M1's return sequence), then its returns.
    pub const fn block_len(self) -> usize {
        2 + self.channels() * self.channel_len()
    }
    /// Bytes of a return.
    pub const fn channel_len(self) -> usize {
        match self {
            Self::M1 => 9,
            Self::E1r => 10,
        }
    }
    /// Where a return's intensity byte lies in it.
    pub const fn intensity_at(self) -> usize {
        match self {
            Self::M1 => 6,
            Self::E1r => 8,
        }
    }
    /// Distance range, metres (rs_driver's `distance min`/`max`).
    pub const fn range_m(self) -> (f64, f64) {
        match self {
            Self::M1 => (0.2, 200.0),
            Self::E1r => (0.0, 200.0),
        }
    }
    /// Its name, as the reports give it.
    pub const fn name(self) -> &'static str {
        match self {
            Self::M1 => "RS-M1",
            Self::E1r => "E1R",
        }
    }
    /// The model whose packets `bytes` is: by its first bytes and length.
    pub fn of(bytes: &[u8]) -> Option<Self> {
        if !bytes.starts_with(&ID) {
            return None;
        }
        [Self::M1, Self::E1r]
            .into_iter()
            .find(|m| m.packet_len() == bytes.len())
    }
}

fn be16(b: &[u8], at: usize) -> u16 {
    match (b.get(at), b.get(at + 1)) {
        (Some(&h), Some(&l)) => u16::from_be_bytes([h, l]),
        _ => 0,
    }
}

/// A checked MSOP packet of `model`.
#[derive(Clone, Copy, Debug)]
pub struct Packet<'a> {
    buf: &'a [u8],
    model: Model,
}

impl<'a> Packet<'a> {
    /// Checks length, id and time.
    pub fn new_checked(bytes: &'a [u8], model: Model) -> Result<Self, PacketError> {
        if bytes.len() < model.packet_len() {
            return Err(PacketError::Truncated);
        }
        if bytes.len() > model.packet_len() {
            return Err(PacketError::Length);
        }
        if !bytes.starts_with(&ID) {
            return Err(PacketError::StartBytes);
        }
        let p = Self { buf: bytes, model };
        p.time_us().ok_or(PacketError::DateTime)?;
        Ok(p)
    }
    /// The packet's sequence number in its frame (from 1).
    pub fn sequence(&self) -> u16 {
        be16(self.buf, SEQ)
    }
    /// The return-mode byte (0x00 dual; 0x04 strongest, 0x05 last, 0x06 first).
    pub fn return_mode(&self) -> u8 {
        self.buf.get(RETURN_MODE).copied().unwrap_or(0)
    }
    /// The packet time, microseconds since the Unix epoch (`None` past what a `u64` holds or
    /// for microseconds of a second or more).
    pub fn time_us(&self) -> Option<u64> {
        super::wire::utc_us(self.buf.get(STAMP..STAMP + 10)?)
    }
    /// Block `k`: its time offset (us) and return sequence number (the E1R's: 0).
    pub fn block(&self, k: usize) -> (u16, u8) {
        self.block_of(self.model, k)
    }
    /// Block `k`, return `c`: its distance (raw) and intensity.
    pub fn channel(&self, k: usize, c: usize) -> (u16, u8) {
        self.channel_of(self.model, k, c)
    }
    /// Block `k`, return `c`: its point at distance `d` (raw) along the direction it carries.
    pub fn point(&self, k: usize, c: usize, d: u16) -> [f64; 3] {
        self.point_of(self.model, k, c, d)
    }
    // The readings with the model given: the decoder's loop passes it as a constant, so each
    // model's offsets fold into its own copy of the loop.
    #[inline(always)]
    fn block_of(&self, model: Model, k: usize) -> (u16, u8) {
        let at = BLOCKS_AT + k * model.block_len();
        match model {
            Model::M1 => (
                u16::from(self.buf.get(at).copied().unwrap_or(0)),
                self.buf.get(at + 1).copied().unwrap_or(0),
            ),
            Model::E1r => (be16(self.buf, at), 0),
        }
    }
    #[inline(always)]
    fn channel_at(model: Model, k: usize, c: usize) -> usize {
        BLOCKS_AT + k * model.block_len() + 2 + c * model.channel_len()
    }
    #[inline(always)]
    fn channel_of(&self, model: Model, k: usize, c: usize) -> (u16, u8) {
        let at = Self::channel_at(model, k, c);
        let intensity = self.buf.get(at + model.intensity_at()).copied();
        (be16(self.buf, at), intensity.unwrap_or(0))
    }
    #[inline(always)]
    fn point_of(&self, model: Model, k: usize, c: usize, d: u16) -> [f64; 3] {
        let at = Self::channel_at(model, k, c);
        match model {
            Model::M1 => m1_point(d, be16(self.buf, at + 2), be16(self.buf, at + 4)),
            Model::E1r => {
                let v = |i: usize| f64::from(be16(self.buf, at + i) as i16);
                let s = f64::from(d) * DISTANCE_RES_M / VECTOR_BASE;
                [v(2) * s, v(4) * s, v(6) * s]
            }
        }
    }
}

/// The point of an RS-M1 return: distance (raw), pitch and yaw (raw).
pub fn m1_point(distance: u16, pitch: u16, yaw: u16) -> [f64; 3] {
    let d = f64::from(distance) * DISTANCE_RES_M;
    let p = (f64::from(i32::from(pitch) - ANGLE_OFFSET) * 0.01).to_radians();
    let y = (f64::from(i32::from(yaw) - ANGLE_OFFSET) * 0.01).to_radians();
    let (sp, cp) = (libm::sin(p), libm::cos(p));
    [d * cp * libm::cos(y), d * cp * libm::sin(y), d * sp]
}

/// RS-M1 or E1R packets in, frames out: a frame begins when the sequence number starts again.
pub struct Decoder {
    model: Model,
    mode: Option<u8>,
    last_seq: Option<u16>,
    last_us: u64,
    frame_start_us: u64,
    asm: Assembly,
}

impl Decoder {
    /// A decoder of `model`'s packets.
    pub fn new(model: Model) -> Self {
        Self {
            model,
            mode: None,
            last_seq: None,
            last_us: 0,
            frame_start_us: 0,
            asm: Assembly::new(),
        }
    }

    /// The model it decodes.
    pub fn model(&self) -> Model {
        self.model
    }

    fn accept<S: SweepSink>(&mut self, bytes: &[u8], sink: &mut S) -> Result<Pushed, PacketError> {
        let p = Packet::new_checked(bytes, self.model)?;
        let mode = p.return_mode();
        if !matches!(mode, 0x00 | 0x04..=0x06) {
            return Err(PacketError::UnknownReturnMode);
        }
        // rs_driver reads no return order in the E1R's dual-return blocks.
        if mode == 0x00 && self.model == Model::E1r {
            return Err(PacketError::DualNotDecoded);
        }
        if *self.mode.get_or_insert(mode) != mode {
            return Err(PacketError::OtherSensor);
        }
        let t = p.time_us().ok_or(PacketError::DateTime)?;
        let seq = p.sequence();
        if let Some(last) = self.last_seq {
            // The same frame: later packets only (a repeat or one from before is late).
            let next_frame = seq < last && t > self.last_us;
            if !next_frame && (seq <= last || t < self.last_us) {
                return Err(PacketError::Late);
            }
            let gap = t.saturating_sub(self.frame_start_us).saturating_mul(1000) > GAP_NS;
            if self.asm.open.is_some() && (next_frame || gap) {
                let end = if next_frame {
                    SweepEnd::NextFrame
                } else {
                    SweepEnd::Gap
                };
                self.asm.end(sink, end);
                self.last_seq = None;
                return Ok(Pushed::Again);
            }
        }
        if self.asm.open.is_none() {
            self.asm.begin(sink, t.saturating_mul(1000), None);
            self.frame_start_us = t;
        }
        let lost = self
            .last_seq
            .map_or(0, |l| u32::from(seq.saturating_sub(l).saturating_sub(1)));
        let base = (t - self.frame_start_us) as f64 * 1e-6;
        match self.model {
            Model::M1 => self.push_returns(sink, &p, Model::M1, base, seq),
            Model::E1r => self.push_returns(sink, &p, Model::E1r, base, seq),
        }
        let stats = self.asm.stats();
        stats.packets = stats.packets.saturating_add(1);
        stats.lost_packets = stats.lost_packets.saturating_add(lost);
        self.last_seq = Some(seq);
        self.last_us = t;
        Ok(Pushed::Decoded)
    }

    /// Pushes packet `p`'s returns, `model` a constant at each call (one loop a model).
    #[inline(always)]
    fn push_returns<S: SweepSink>(
        &mut self,
        sink: &mut S,
        p: &Packet<'_>,
        model: Model,
        base: f64,
        seq: u16,
    ) {
        // Checked by `Packet::new_checked`; said again so the offsets' bounds fold away.
        if p.buf.len() != model.packet_len() {
            return;
        }
        let mode = p.return_mode();
        let single = match mode {
            0x05 => Return::Last,
            0x06 => Return::First,
            _ => Return::Strongest,
        };
        let (blocks, channels, range) = (model.blocks(), model.channels(), model.range_m());
        for k in 0..blocks {
            let (offset_us, return_seq) = p.block_of(model, k);
            let ret = match (mode, return_seq) {
                (0x00, 0) => Return::First,
                (0x00, _) => Return::Second,
                _ => single,
            };
            let time = base + f64::from(offset_us) * 1e-6;
            for c in 0..channels {
                let (d, intensity) = p.channel_of(model, k, c);
                let m = f64::from(d) * DISTANCE_RES_M;
                if d == 0 || m < range.0 || m > range.1 {
                    continue;
                }
                let point = p.point_of(model, k, c, d);
                let meta = PointMeta {
                    ring: c as u16,
                    column: (usize::from(seq) * blocks + k).min(usize::from(u16::MAX)) as u16,
                    ret,
                    intensity: u16::from(intensity),
                };
                self.asm.push(sink, point, time, meta);
            }
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
