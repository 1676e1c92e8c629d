//! How TIER IV nebula's Velodyne decoders (`vlp16_decoder.cpp`, `vlp32_decoder.cpp`,
//! `vls128_decoder.cpp`, commit 606ac41f) read a packet, written from their code's facts so
//! the comparison with nebula can say where and why nebula departs from the manuals; beside
//! it, the manuals' reading of the same return.
//!
//! Nebula interpolates each block's azimuth towards the next block's, in f32, and rounds the
//! corrected azimuth to 0.01 degree before its sine table. Three departures from the manuals'
//! precision azimuth (section 9.5) follow from its code:
//! - `OddBlock`: in dual-return mode a block's base azimuth is the previous block's
//!   `azimuth_next`, which for the second block of a pair is the next pair's azimuth, and its
//!   gap is then 0 (nebula's chain of `azimuth = azimuth_next`).
//! - `ZeroGap`: the block before the last firing block (VLP-16 single: block 11; dual: 10;
//!   VLP-32 and VLS-128 single: 11) gets a gap of 0, and the VLS-128's banks 1-3 of every
//!   sequence interpolate towards the same sequence's next bank (the same azimuth): gap 0.
//! - `ChannelTiming`: the VLP-32 moves channel `j` by `j` x 2.304 us, where the lasers fire in
//!   pairs (`j / 2` x 2.304 us, the manual's timing table and its note that "each pair shares
//!   the same azimuth").
//!
//! The manuals leave open the packet's last firing group, whose next azimuth is in the next
//! packet: nebula takes 0 or the step before, ours the packet's mean step (`LastGroup`).
//! Anything else is `F32Tie`: both reach an azimuth on a half hundredth and f32 rounding tips
//! nebula's the other way.

use std::f64::consts::PI;

/// A model whose nebula decoder is read here.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Neb {
    Vlp16,
    Vlp32,
    Vls128,
}

/// Why nebula's azimuth of a return differs from the manual's.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Departure {
    None,
    /// Nebula interpolates as the manual, but rounds to 0.01 degree after adding a laser's
    /// azimuth offset that is not a whole hundredth (ours rounds the interpolated azimuth,
    /// as velodyne-decoder, then adds the offset): two roundings of one exact azimuth, up to
    /// 0.01 degree apart.
    RoundsAfterOffset,
    OddBlock,
    ZeroGap,
    ChannelTiming,
    /// The packet's last firing group, whose next azimuth is in the next packet: nebula's
    /// gap (0, or the step before) where ours takes the packet's mean step.
    LastGroup,
    F32Tie,
}

/// One return as nebula and as the manual read it.
pub struct Reading {
    pub nebula: [f64; 3],
    pub manual: [f64; 3],
    pub departure: Departure,
    /// nebula's range after its distance correction (its range filter's input), metres.
    pub range: f64,
}

/// Per-laser calibration as nebula holds it: radians, f32.
pub struct Laser {
    pub vert: f32,
    pub rot: f32,
    pub dist: f32,
}

fn u16_at(p: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([p[at], p[at + 1]])
}

/// Nebula's table angle of azimuth index `a`: `from_degrees(0.01f * a)` stored as float.
fn table_rad(a: u16) -> f32 {
    (f64::from(0.01f32 * f32::from(a)) * PI / 180.0) as f32
}

/// Rounds `num / den` half up (both non-negative).
fn round_div(num: u64, den: u64) -> u64 {
    (2 * num + den) / (2 * den)
}

/// Every return of `packet` (1206 bytes) of `model`.
pub fn read(model: Neb, packet: &[u8], lasers: &[Laser], resolution: f32) -> Vec<Reading> {
    let dual = packet[1204] == 0x39;
    let az = |k: usize| u16_at(packet, 100 * k + 2);
    let blocks = if model == Neb::Vls128 && dual { 8 } else { 12 };
    let step = if dual { 2 } else { 1 };
    // The last block nebula gives a gap of 0 (`g_blocks_per_packet - dual - 1`, or
    // `- 4 * dual - 1`).
    let zero_block = match model {
        Neb::Vlp16 => 12 - usize::from(dual) - 1,
        _ => 12 - 4 * usize::from(dual) - 1,
    };
    let banks_per_group = if model == Neb::Vls128 { 4 * step } else { step };
    let mut out = Vec::new();
    let (mut next, mut last_gap) = (0u16, 0f32);
    for b in 0..blocks {
        // Nebula's chain.
        let base_n = if b == 0 { az(0) } else { next };
        let gap_n = if b < 12 - step {
            next = az(b + step);
            let g = ((36000 + i32::from(next) - i32::from(base_n)) % 36000) as f32;
            last_gap = g;
            g
        } else if b == zero_block {
            0.0
        } else {
            last_gap
        };
        // The manual's: this firing group's first block to the next group's.
        let group = b / banks_per_group;
        let first = group * banks_per_group;
        let groups = blocks / banks_per_group;
        let base_m = az(first);
        // The last group's next azimuth is in the next packet: the packet's mean step.
        let (gap_m, den) = if group + 1 < groups {
            let next = az(first + banks_per_group);
            ((36000 + u32::from(next) - u32::from(base_m)) % 36000, 1)
        } else if groups > 1 {
            let span = (36000 + u32::from(base_m) - u32::from(az(0))) % 36000;
            (span, groups as u64 - 1)
        } else {
            (0, 1)
        };
        let bank = match u16_at(packet, 100 * b) {
            0xEEFF => 0,
            0xDDFF => 1,
            0xCCFF => 2,
            0xBBFF => 3,
            _ => return out,
        };
        for c in 0..32 {
            let raw = u16_at(packet, 100 * b + 4 + 3 * c);
            if raw == 0 {
                continue;
            }
            if dual && b % 2 == 1 && raw == u16_at(packet, 100 * (b - 1) + 4 + 3 * c) {
                continue;
            }
            let (laser, frac_n, ticks, group_ticks) = match model {
                Neb::Vlp16 => {
                    let (dsr, firing) = (c % 16, c / 16);
                    let t = (dsr as f32 * 2.304f32) + (firing as f32 * 55.296f32);
                    (dsr, gap_n * t / 110.592f32, 24 * firing + dsr, 48)
                }
                Neb::Vlp32 => (c, gap_n * 2.304f32 / 55.296f32 * c as f32, c / 2, 24),
                Neb::Vls128 => {
                    let laser = 32 * bank + c;
                    let fo = laser / 8;
                    let cache = (2.665f32 / 53.3f32) * (fo + fo / 8) as f32;
                    (laser, gap_n * cache, laser / 8 + laser / 64, 20)
                }
            };
            let Some(l) = lasers.get(laser) else { continue };
            // Nebula: f32 sum, the rotation correction in double, back to f32, rounded.
            let rot_units = f64::from(l.rot) * 180.0 / PI * 100.0;
            let mut a = (f64::from(f32::from(base_n) + frac_n) - rot_units) as f32;
            if a < 0.0 {
                a += 36000.0;
            }
            let a_n = (a.round() as u32 % 36000) as u16;
            // The manual: exact, rounded half up to the hundredth, then the laser's offset.
            let scaled = u64::from(base_m) * group_ticks * den + u64::from(gap_m) * ticks as u64;
            let a_m = (round_div(scaled, group_ticks * den) % 36000) as u16;
            // What nebula would give interpolating as the manual.
            let exact = scaled as f64 / (group_ticks * den) as f64 - rot_units;
            let a_nm = ((exact.round() as i64).rem_euclid(36000)) as u16;
            // (to f32 precision: 1.4 degrees is 139.99999 hundredths in f32 radians)
            let whole_offset = (rot_units - rot_units.round()).abs() < 1e-3;
            let mut d = raw as f32 * resolution;
            if d > 1e-6 {
                d += l.dist;
            }
            let (cv, sv) = (l.vert.cos(), l.vert.sin());
            let xy = d * cv;
            let nebula = {
                let t = table_rad(a_n);
                [
                    f64::from(xy * t.cos()),
                    f64::from(-(xy * t.sin())),
                    f64::from(d * sv),
                ]
            };
            let manual = {
                let t =
                    f64::from(0.01f32 * f32::from(a_m) * (PI / 180.0) as f32) - f64::from(l.rot);
                let xy = f64::from(d) * f64::from(l.vert).cos();
                [
                    xy * t.cos(),
                    -xy * t.sin(),
                    f64::from(d) * f64::from(l.vert).sin(),
                ]
            };
            let departure = if a_n == a_nm && whole_offset {
                Departure::None
            } else if a_n == a_nm {
                Departure::RoundsAfterOffset
            } else if dual && b % 2 == 1 {
                Departure::OddBlock
            } else if gap_n == 0.0 && gap_m != 0 && den == 1 {
                Departure::ZeroGap
            } else if den > 1 {
                // The last group: nebula's gap of 0 (or the step before), where ours takes the
                // packet's mean step.
                Departure::LastGroup
            } else if gap_n == 0.0 && gap_m != 0 {
                Departure::ZeroGap
            } else if model == Neb::Vlp32 && c > 0 && gap_m != 0 {
                Departure::ChannelTiming
            } else {
                Departure::F32Tie
            };
            out.push(Reading {
                nebula,
                manual,
                departure,
                range: f64::from(d),
            });
        }
    }
    out
}
