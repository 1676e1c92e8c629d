//! Where each return of a Velodyne packet sits and when its laser fired: the firing groups of
//! a packet, the blocks of a group (one per bank of 32 lasers, two per bank in dual-return
//! mode) and each channel's firing time, per model.
//!
//! A firing group is what one block azimuth stands for: a block (VLP-16: two firing sequences;
//! VLP-32C, HDL-32E: one), an upper and lower block pair (HDL-64E) or four banks (VLS-128).
//! Firing times are whole multiples of a model's tick, so the precision azimuth between two
//! groups is an exact fraction.

use super::model::Model;
use crate::sweep::Return;

/// Where the returns of one bank of one firing group are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blocks {
    /// Single-return mode: the block, and which return the packets carry.
    Single(usize),
    /// Dual-return mode: the block holding the last return, and the strongest's.
    Dual {
        /// Block of the last return.
        last: usize,
        /// Block of the strongest return (the second strongest when the last is strongest).
        strongest: usize,
    },
}

/// A model's firing layout in one return mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// The model.
    pub model: Model,
    /// Dual-return mode.
    pub dual: bool,
}

impl Layout {
    /// Firing groups in a packet.
    pub fn groups(self) -> usize {
        // VLP-16 and VLP-32C manuals section 9.3.2; HDL-64E S3 manual (six upper/lower pairs,
        // three in dual mode, as velodyne-decoder's unpack_hdl64e); VLS-128 manual 63-9483
        // section 9.3.2 (three sequences, one in dual mode with blocks 8-11 unused).
        let single = match self.model {
            Model::Hdl64eS2 | Model::Hdl64eS3 => 6,
            Model::Vls128 => 3,
            _ => 12,
        };
        if self.dual {
            single / if self.model == Model::Vls128 { 3 } else { 2 }
        } else {
            single
        }
    }

    /// The block(s) of bank `b` in firing group `g`.
    pub fn blocks(self, g: usize, b: usize) -> Blocks {
        let banks = self.model.banks();
        if !self.dual {
            return Blocks::Single(g * banks + b);
        }
        match self.model {
            // HDL-64E S3: upper and lower strongest, then upper and lower last (as
            // velodyne-decoder's unpack_hdl64e reads it).
            Model::Hdl64eS2 | Model::Hdl64eS3 => Blocks::Dual {
                strongest: 4 * g + b,
                last: 4 * g + 2 + b,
            },
            // VLP-16, VLP-32C, HDL-32E, VLS-128 manuals: each bank's last return, then its
            // strongest, in adjacent blocks.
            _ => Blocks::Dual {
                last: 2 * (g * banks + b),
                strongest: 2 * (g * banks + b) + 1,
            },
        }
    }

    /// The first block of firing group `g`, whose azimuth the group's returns are
    /// interpolated from; `None` past the last group.
    pub fn group_block(self, g: usize) -> Option<usize> {
        (g < self.groups()).then(|| match self.blocks(g, 0) {
            Blocks::Single(k) => k,
            Blocks::Dual { last, strongest } => last.min(strongest),
        })
    }

    /// Microseconds from one packet to the next.
    pub fn packet_us(self) -> f64 {
        self.model.group_us() * self.groups() as f64
    }
}

impl Model {
    /// The firing tick (microseconds) and the ticks of one firing group: every firing time
    /// is a whole number of ticks.
    pub fn ticks(self) -> (f64, u32) {
        match self {
            // VLP-16 manual 63-9243 section 9.4: 16 firings of 2.304 us and a recharge, a
            // sequence of 55.296 us (24 ticks); a block holds two sequences.
            Self::Vlp16 | Self::PuckHiRes => (2.304, 48),
            // VLP-32C manual 63-9325 section 9.4: 16 firings of a laser pair, 55.296 us; the
            // VLP-32A/B as the VLP-32C (velodyne-decoder's buildTimings).
            Self::Vlp32c | Self::Vlp32ab => (2.304, 24),
            // HDL-32E application note 63-9277: 32 firings of 1.152 us plus 9.216 us recharge,
            // 46.08 us (40 ticks).
            Self::Hdl32e => (1.152, 40),
            // HDL-64E S2 manual's laser firing time table: upper and lower lasers fire
            // together, four at 0, 1.26, 2.46 and 3.66 us every 6 us, a firing 48 us
            // (velodyne-decoder's buildTimings); ticks of 0.01 us.
            Self::Hdl64eS2 => (0.01, 4800),
            // HDL-64E S3 manual: 0, 1.3, 2.5 and 3.7 us every 7.2 us, a firing 57.6 us.
            Self::Hdl64eS3 => (0.01, 5760),
            // VLS-128 manual 63-9483 section 9.4: groups of eight every 2.665 us, a sequence of
            // 16 groups and two maintenance periods (2.665 and 7.995 us), 53.3 us (20 ticks).
            Self::Vls128 => (2.665, 20),
        }
    }

    /// Ticks from a firing group's first firing to channel `c` of bank `b`.
    pub fn firing_ticks(self, b: usize, c: usize) -> u32 {
        let c32 = c as u32;
        match self {
            Self::Vlp16 | Self::PuckHiRes => 24 * (c32 / 16) + c32 % 16,
            Self::Vlp32c | Self::Vlp32ab => c32 / 2,
            Self::Hdl32e => c32,
            Self::Hdl64eS2 => 600 * (c32 / 4) + [0, 126, 246, 366][c % 4],
            Self::Hdl64eS3 => 720 * (c32 / 4) + [0, 130, 250, 370][c % 4],
            // FiringGroupIndex = laser / 8 + laser / 64 (the maintenance period after the
            // eighth group).
            Self::Vls128 => {
                let laser = 32 * b as u32 + c32;
                laser / 8 + laser / 64
            }
        }
    }

    /// The packet timestamp's lead over the first firing, microseconds: the VLS-128 stamps the
    /// packet at its fourth firing group and its manual puts every firing 8.7 us before
    /// `timestamp + offset`; the other models stamp the first firing.
    pub fn stamp_lead_us(self) -> f64 {
        match self {
            Self::Vls128 => 8.7,
            _ => 0.0,
        }
    }

    /// Time of channel `c` of bank `b` in firing group `g` after the packet's first firing
    /// (its timestamp less [`Self::stamp_lead_us`]), seconds.
    pub fn firing_s(self, g: usize, b: usize, c: usize) -> f64 {
        let (tick, group) = self.ticks();
        let ticks = f64::from(group) * g as f64 + f64::from(self.firing_ticks(b, c));
        tick * 1e-6 * ticks
    }

    /// [`Self::firing_s`] of bank 0 (the 16- and 32-laser models).
    pub fn firing_time_s(self, g: usize, c: usize) -> f64 {
        self.firing_s(g, 0, c)
    }

    /// Time from one firing group to the next, microseconds.
    pub fn group_us(self) -> f64 {
        let (tick, group) = self.ticks();
        tick * f64::from(group)
    }

    /// Time from one data packet to the next, microseconds.
    pub fn packet_us(self, dual: bool) -> f64 {
        Layout { model: self, dual }.packet_us()
    }
}

/// The return a single-return mode byte names (0x37 strongest, 0x38 last).
pub fn single_return(byte: u8) -> Option<Return> {
    match byte {
        0x37 => Some(Return::Strongest),
        0x38 => Some(Return::Last),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_block_is_read_once_per_packet() {
        for model in Model::ALL {
            for dual in [false, true] {
                let l = Layout { model, dual };
                let mut seen = [0u8; 12];
                for g in 0..l.groups() {
                    for b in 0..model.banks() {
                        match l.blocks(g, b) {
                            Blocks::Single(k) => seen[k] += 1,
                            Blocks::Dual { last, strongest } => {
                                seen[last] += 1;
                                seen[strongest] += 1;
                            }
                        }
                    }
                }
                let used = if model == Model::Vls128 && dual {
                    8
                } else {
                    12
                };
                assert!(seen[..used].iter().all(|&n| n == 1), "{model:?} {dual}");
                assert!(seen[used..].iter().all(|&n| n == 0), "{model:?} {dual}");
            }
        }
    }

    #[test]
    fn firing_times_follow_the_manuals_tables() {
        // VLP-16 single return, block 1 channel 17: sequence 3, point 1.
        let t = Model::Vlp16.firing_s(1, 0, 17);
        assert!((t - (3.0 * 55.296 + 2.304) * 1e-6).abs() < 1e-12);
        // VLS-128 laser 100 (bank 3, channel 4): group 12 + 1 maintenance.
        let t = Model::Vls128.firing_s(2, 3, 4);
        assert!((t - (2.0 * 53.3 + 13.0 * 2.665) * 1e-6).abs() < 1e-12);
        // HDL-64E S3 laser 6 of either block: 7.2 + 2.5 us into the firing.
        let t = Model::Hdl64eS3.firing_s(1, 1, 6);
        assert!((t - (57.6 + 9.7) * 1e-6).abs() < 1e-12);
        // Every firing ends before the next group begins.
        for model in Model::ALL {
            let (_, group) = model.ticks();
            for b in 0..model.banks() {
                for c in 0..32 {
                    assert!(model.firing_ticks(b, c) < group, "{model:?} {b} {c}");
                }
            }
        }
    }
}
