//! The fixed-layout Hesai packets the tests decode: the PandarAT128's, with the mirror-frame
//! correction of a made-up unit, and those of the Pandar40P, Pandar64, PandarQT64, PandarXT16
//! and PandarXT32M.

use kiss_odom_sensors::hesai::wire_fixed::{
    Date, AT128_SEQUENCE, BLOCK_START, PANDARAT128, PANDARXT32M,
};
use kiss_odom_sensors::hesai::{self, At128Correction, Model};

/// Seconds since the epoch in the packets: 2024-01-01 00:00:00 UTC.
pub const EPOCH_S: u64 = 1_704_067_200;
/// AT128 azimuth units a degree.
pub const DEG: u32 = 25_600;

/// Three frames from 20, 140 and 260 degrees of motor; channel `c` at azimuth `-2.4` or
/// `0.65` degrees (even, odd), elevation `12.9 - 0.2 c`; adjustments that vary with the motor
/// angle; resolution 2.
pub fn correction() -> At128Correction {
    let mut c = At128Correction::empty();
    c.frames = 3;
    c.start[..3].copy_from_slice(&[20 * DEG, 140 * DEG, 260 * DEG]);
    c.end[..3].copy_from_slice(&[140 * DEG, 260 * DEG, 20 * DEG]);
    for ch in 0..128 {
        c.azimuth[ch] = if ch % 2 == 0 { -61_440 } else { 16_640 };
        c.elevation[ch] = 330_240 - 5_120 * ch as i32;
        for i in 0..180 {
            c.azimuth_adjust[ch][i] = ((i * 7 + ch) % 41) as i8 - 20;
            c.elevation_adjust[ch][i] = ((i * 3 + ch) % 11) as i8 - 5;
        }
    }
    c.adjust_unit = 2;
    c
}

/// An AT128 packet, for [`packet`].
pub struct Spec {
    /// Motor angle of block 0 (units) and the step to block 1.
    pub motor: u32,
    pub step: u32,
    /// Microseconds after `EPOCH_S`.
    pub us: u64,
    pub mode: u8,
    pub returns: u8,
    pub sequence: u32,
}

impl Spec {
    pub fn new(motor: u32, us: u64, sequence: u32) -> Self {
        Self {
            motor,
            step: 1_280,
            us,
            mode: 0x37,
            returns: 1,
            sequence,
        }
    }
}

/// A packet whose channel `c` returns `(1000 + c) x 4 mm` in block 0 and `(2000 + c) x 4 mm`
/// in block 1, except channel 9, which returns nothing.
pub fn packet(s: &Spec) -> Vec<u8> {
    let f = &PANDARAT128;
    let mut b = vec![0u8; f.default_len()];
    b[..12].copy_from_slice(&[0xEE, 0xFF, 4, 3, 0, 0, 128, 2, 0, 4, s.returns, 1]);
    for k in 0..2 {
        let at = f.block_at(k);
        let motor = s.motor + s.step * k as u32;
        b[at..at + 2].copy_from_slice(&((motor >> 8) as u16).to_le_bytes());
        b[at + 2] = motor as u8;
        for c in 0..128 {
            let d: u16 = if c == 9 {
                0
            } else {
                (1000 * (k + 1) + c) as u16
            };
            let u = at + 3 + 4 * c;
            b[u..u + 2].copy_from_slice(&d.to_le_bytes());
            b[u + 2] = c as u8;
        }
    }
    let tail = f.tail_at();
    b[tail + f.motor..tail + f.motor + 2].copy_from_slice(&200u16.to_le_bytes());
    let (sec, us) = (EPOCH_S + s.us / 1_000_000, (s.us % 1_000_000) as u32);
    b[tail + f.micros..tail + f.micros + 4].copy_from_slice(&us.to_le_bytes());
    b[tail + f.return_mode] = s.mode;
    b[tail + f.date + 1..tail + f.date + 6].copy_from_slice(&sec.to_be_bytes()[3..]);
    let q = tail + AT128_SEQUENCE;
    b[q..q + 4].copy_from_slice(&s.sequence.to_le_bytes());
    b
}

/// An AT128 decoder with [`correction`].
pub fn decoder() -> hesai::Decoder<hesai::MirrorAngles> {
    hesai::Decoder::at128(&correction()).unwrap()
}

/// A packet of fixed-layout `model` (not the AT128: [`packet`]) of return mode `mode` and
/// header return count `count`, turning at 600 rpm, every channel of block `k` at `500 + k`
/// distance units, dated 2024-01-01 00:00:00 UTC, with the sequence number the model sends by
/// default.
pub fn fixed(model: Model, mode: u8, count: u8) -> Vec<u8> {
    let f = model.fixed_format().unwrap_or(&PANDARXT32M);
    let returns = match mode {
        0x3D => 3,
        0x39 | 0x3B | 0x3C => 2,
        _ => 1,
    };
    let mut b = vec![0u8; f.default_len()];
    let (lasers, blocks) = (f.lasers as u8, f.blocks as u8);
    match f.header {
        12 => b[..12].copy_from_slice(&[
            0xEE,
            0xFF,
            f.version.0,
            f.version.1,
            0,
            0,
            lasers,
            blocks,
            1,
            4,
            count,
            1,
        ]),
        8 => b[..8].copy_from_slice(&[0xEE, 0xFF, lasers, blocks, 0, 4, 0, 0]),
        _ => {}
    }
    // 0.01 degree from firing to firing at 600 rpm.
    let step = (model.firing_ns(0) as f64 * 600.0 / 60.0 * 36_000.0 * 1e-9).round() as u16;
    for k in 0..f.blocks {
        let mut at = f.block_at(k);
        if f.block_start {
            b[at..at + 2].copy_from_slice(&BLOCK_START);
            at += 2;
        }
        let az = 1000 + step * (k as u16 / returns);
        b[at..at + 2].copy_from_slice(&az.to_le_bytes());
        for c in 0..f.lasers {
            let u = at + 2 + f.unit_len * c;
            b[u..u + 2].copy_from_slice(&(500 + k as u16).to_le_bytes());
        }
    }
    let tail = f.tail_at();
    b[tail + f.return_mode] = mode;
    b[tail + f.motor..tail + f.motor + 2].copy_from_slice(&600u16.to_le_bytes());
    let year = match f.date_kind {
        Date::Civil(base) => (2024 - base) as u8,
        Date::EpochSeconds => 124,
    };
    b[tail + f.date..tail + f.date + 6].copy_from_slice(&[year, 1, 1, 0, 0, 0]);
    b
}
