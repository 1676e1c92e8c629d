//! The Robosense RS-M1 (MEMS): 1210-byte MSOP packets whose every return carries its own
//! direction, frames cut by the packet sequence number.
//!
//! ```text
//! header (32 bytes): id 55 AA 5A A5 | pkt_seq u16 at 4 | protocol u16 | return mode at 8 |
//!                    time mode | UTC s (48-bit) + us (32-bit) at 10..20 | ... | temperature
//! 25 blocks of 47 bytes at 32: time offset u8 (us after the packet time) | return seq u8 |
//!     5 channels x (distance u16, pitch u16, yaw u16, intensity, attribute, elongation)
//! ```
//! Big-endian; distance in 5 mm, pitch and yaw in 0.01 degree offset by 32768; a point is
//! `d (cos p cos y, cos p sin y, sin p)`. The packet sequence starts again at 1 with each
//! frame (630 packets a 10 Hz frame in single return). Source: rs_driver `decoder_RSM1.hpp`
//! (`RSM1MsopPkt`, `decodeMsopPkt`, `SplitStrategyBySeq`), commit 4eeadace. The M1's DIFOP
//! packets (256 bytes) carry no angles its points need: they are not read.

use crate::error::PacketError;
use crate::sweep::{Assembly, Decode, PointMeta, Pushed, Return, SweepEnd, SweepSink, SweepStats};

/// Bytes of an MSOP packet.
pub const LEN: usize = 1210;
/// The MSOP packet's first bytes.
pub const ID: [u8; 4] = [0x55, 0xAA, 0x5A, 0xA5];
const SEQ: usize = 4;
const RETURN_MODE: usize = 8;
const STAMP: usize = 10;
const BLOCKS_AT: usize = 32;
/// Blocks a packet, channels a block, bytes of each.
pub const BLOCKS: usize = 25;
const CHANNELS: usize = 5;
const BLOCK_LEN: usize = 2 + CHANNELS * CHANNEL_LEN;
const CHANNEL_LEN: usize = 9;
/// Metres per distance unit.
pub const DISTANCE_RES_M: f64 = 0.005;
/// Distance range, metres (rs_driver's `distance min`/`max`).
pub const RANGE_M: (f64, f64) = (0.2, 200.0);
/// Angle offset of pitch and yaw, hundredths of a degree.
const ANGLE_OFFSET: i32 = 32768;
/// A frame whose packets span more than this (sensor time) ends.
pub const GAP_NS: u64 = 300_000_000;

fn be16(b: &[u8], at: usize) -> u16 {
    match (b.get(at), b.get(at + 1)) {
        (Some(&h), Some(&l)) => u16::from_be_bytes([h, l]),
        _ => 0,
    }
}

/// A checked RS-M1 MSOP packet.
#[derive(Clone, Copy, Debug)]
pub struct Packet<'a> {
    buf: &'a [u8; LEN],
}

impl<'a> Packet<'a> {
    /// Checks length, id and time.
    pub fn new_checked(bytes: &'a [u8]) -> Result<Self, PacketError> {
        let buf: &[u8; LEN] = match bytes.try_into() {
            Ok(b) => b,
            Err(_) if bytes.len() < LEN => return Err(PacketError::Truncated),
            Err(_) => return Err(PacketError::Length),
        };
        if !buf.starts_with(&ID) {
            return Err(PacketError::StartBytes);
        }
        let p = Self { buf };
        p.time_us().ok_or(PacketError::DateTime)?;
        Ok(p)
    }
    /// The packet's sequence number in its frame (from 1).
    pub fn sequence(&self) -> u16 {
        be16(self.buf, SEQ)
    }
    /// The return-mode byte (0x00 dual; 0x04 strongest, 0x05 last, 0x06 first).
    pub fn return_mode(&self) -> u8 {
        self.buf[RETURN_MODE]
    }
    /// The packet time, microseconds since the Unix epoch (`None` past what a `u64` holds or
    /// for microseconds of a second or more).
    pub fn time_us(&self) -> Option<u64> {
        super::wire::utc_us(&self.buf[STAMP..STAMP + 10])
    }
    /// Block `k`: its time offset (us) and return sequence number.
    pub fn block(&self, k: usize) -> (u8, u8) {
        let at = BLOCKS_AT + k * BLOCK_LEN;
        (self.buf[at], self.buf[at + 1])
    }
    /// Block `k`, channel `c`: distance, pitch and yaw (raw), intensity.
    pub fn channel(&self, k: usize, c: usize) -> (u16, u16, u16, u8) {
        let at = BLOCKS_AT + k * BLOCK_LEN + 2 + c * CHANNEL_LEN;
        let intensity = self.buf.get(at + 6).copied().unwrap_or(0);
        (
            be16(self.buf, at),
            be16(self.buf, at + 2),
            be16(self.buf, at + 4),
            intensity,
        )
    }
}

/// The point of a return: distance (raw), pitch and yaw (raw).
pub fn point(distance: u16, pitch: u16, yaw: u16) -> [f64; 3] {
    let d = f64::from(distance) * DISTANCE_RES_M;
    let p = (f64::from(i32::from(pitch) - ANGLE_OFFSET) * 0.01).to_radians();
    let y = (f64::from(i32::from(yaw) - ANGLE_OFFSET) * 0.01).to_radians();
    let (sp, cp) = (libm::sin(p), libm::cos(p));
    [d * cp * libm::cos(y), d * cp * libm::sin(y), d * sp]
}

/// RS-M1 packets in, frames out: a frame begins when the sequence number starts again.
pub struct Decoder {
    mode: Option<u8>,
    last_seq: Option<u16>,
    last_us: u64,
    frame_start_us: u64,
    asm: Assembly,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Decoder {
    /// A decoder.
    pub fn new() -> Self {
        Self {
            mode: None,
            last_seq: None,
            last_us: 0,
            frame_start_us: 0,
            asm: Assembly::new(),
        }
    }

    fn accept<S: SweepSink>(&mut self, bytes: &[u8], sink: &mut S) -> Result<Pushed, PacketError> {
        let p = Packet::new_checked(bytes)?;
        let mode = p.return_mode();
        if !matches!(mode, 0x00 | 0x04..=0x06) {
            return Err(PacketError::UnknownReturnMode);
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
        let single = match mode {
            0x05 => Return::Last,
            0x06 => Return::First,
            _ => Return::Strongest,
        };
        for k in 0..BLOCKS {
            let (offset_us, return_seq) = p.block(k);
            let ret = match (mode, return_seq) {
                (0x00, 0) => Return::First,
                (0x00, _) => Return::Second,
                _ => single,
            };
            let time = base + f64::from(offset_us) * 1e-6;
            for c in 0..CHANNELS {
                let (d, pitch, yaw, intensity) = p.channel(k, c);
                let m = f64::from(d) * DISTANCE_RES_M;
                if d == 0 || m < RANGE_M.0 || m > RANGE_M.1 {
                    continue;
                }
                let meta = PointMeta {
                    ring: c as u16,
                    column: (usize::from(seq) * BLOCKS + k).min(usize::from(u16::MAX)) as u16,
                    ret,
                    intensity: u16::from(intensity),
                };
                self.asm.push(sink, point(d, pitch, yaw), time, meta);
            }
        }
        let stats = self.asm.stats();
        stats.packets = stats.packets.saturating_add(1);
        stats.lost_packets = stats.lost_packets.saturating_add(lost);
        self.last_seq = Some(seq);
        self.last_us = t;
        Ok(Pushed::Decoded)
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
