//! The models decoded, their published timing, the per-channel [`Calibration`] (Hesai's angle
//! correction file) and the decoder's [`Config`].

pub use super::firetimes::PANDAR128_NEAR_M;
use super::firetimes::{NONE, OT128_NS, PANDAR128_NS, QT128_NS};
use super::timing::Timing;
use super::wire::field;
use super::wire_fixed::{self, Format};
use crate::error::ConfigError;
use crate::sweep::Return;

/// Channels of the PandarXT-32.
pub const CHANNELS: usize = field::CHANNELS;
/// Channels of the largest model decoded (QT128, Pandar128, OT128).
pub const MAX_CHANNELS: usize = 128;
/// Metres per distance unit (the header's 4 mm).
pub const DISTANCE_UNIT_M: f64 = 0.004;
/// Time from one firing to the next, ns (PandarXT-32).
pub const FIRING_NS: i64 = 50_000;

/// The Hesai sensors decoded, by their UDP protocol.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Model {
    /// PandarXT-32 (also XT32M; protocol 6.1): nominal angles built in.
    #[default]
    Xt32,
    /// PandarQT128 (protocol 3.2): needs its angle correction file.
    Qt128,
    /// Pandar128 (protocol 1.4): needs its angle correction file.
    Pandar128,
    /// OT128 (protocol 1.4): needs its angle correction file.
    Ot128,
    /// Pandar40P (no header; 10 blocks of 40 channels): needs its angle correction file.
    Pandar40P,
    /// Pandar64 (8-byte header; 6 blocks of 64 channels): needs its angle correction file.
    Pandar64,
    /// PandarQT64 (protocol 3.1; 4 blocks of 64 channels): needs its angle correction file.
    PandarQT64,
    /// PandarXT16 (protocol 6.1; 8 blocks of 16 channels): nominal angles built in.
    Xt16,
    /// PandarXT32M (protocol 6.1; 6 blocks of 32 channels): needs its angle correction file.
    Xt32m,
    /// PandarAT128 (protocol 4.3; 2 blocks of 128 channels): needs its mirror-frame angle
    /// correction file (`.dat`, [`super::At128Correction`]).
    At128,
}

/// What a packet says about its firings, for [`Model::point_offset_ns`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Firing {
    /// Returns a firing reports (blocks per firing).
    pub returns: usize,
    /// Protocol 3.2's mode flag: which firing loop comes first.
    pub mode_flag: u8,
    /// Protocol 1.4's operational state (0 high resolution, 2 standard).
    pub operational_state: u8,
    /// Protocol 1.4: the block's azimuth state.
    pub azimuth_state: u8,
    /// The return is nearer than [`PANDAR128_NEAR_M`]: the Pandar128's channels fire at other
    /// times for it. The other models ignore it.
    pub near: bool,
}

impl Firing {
    /// Blocks a firing fills: its returns, at least one.
    const fn blocks(&self) -> usize {
        if self.returns == 0 {
            1
        } else {
            self.returns
        }
    }
}

impl Model {
    /// Every model decoded.
    pub const ALL: [Self; 10] = [
        Self::Xt32,
        Self::Qt128,
        Self::Pandar128,
        Self::Ot128,
        Self::Pandar40P,
        Self::Pandar64,
        Self::PandarQT64,
        Self::Xt16,
        Self::Xt32m,
        Self::At128,
    ];
    /// The packet format and firing times of a fixed-layout model ([`wire_fixed`]).
    pub(super) const fn fixed(self) -> Option<(&'static Format, Timing)> {
        Some(match self {
            Self::Pandar40P => (&wire_fixed::PANDAR40P, Timing::Pandar40P),
            Self::Pandar64 => (&wire_fixed::PANDAR64, Timing::Pandar64),
            Self::PandarQT64 => (&wire_fixed::PANDARQT64, Timing::PandarQT64),
            Self::Xt16 => (&wire_fixed::PANDARXT16, Timing::Xt16),
            Self::Xt32m => (&wire_fixed::PANDARXT32M, Timing::Xt32m),
            Self::At128 => (&wire_fixed::PANDARAT128, Timing::At128),
            _ => return None,
        })
    }
    /// The packet format of a fixed-layout model ([`wire_fixed`]), `None` for the XT32 and
    /// the 128-channel models of protocols 3.2 and 1.4.
    pub const fn fixed_format(self) -> Option<&'static Format> {
        match self.fixed() {
            Some((f, _)) => Some(f),
            None => None,
        }
    }
    /// Channels a block holds.
    pub const fn channels(self) -> usize {
        match self.fixed() {
            Some((f, _)) => f.lasers,
            None if matches!(self, Self::Xt32) => CHANNELS,
            None => MAX_CHANNELS,
        }
    }
    /// Blocks a packet holds.
    pub const fn blocks(self) -> usize {
        match self.fixed() {
            Some((f, _)) => f.blocks,
            None if matches!(self, Self::Xt32) => field::BLOCKS,
            None => super::wire128::BLOCKS,
        }
    }
    /// The angles to use without an angle correction file: the XT32's and XT16's nominal
    /// ones; the other models have none (each unit needs its own file).
    pub const fn nominal_calibration(self) -> Option<Calibration> {
        match self {
            Self::Xt32 => Some(Calibration::nominal()),
            Self::Xt16 => Some(Calibration::nominal_xt16()),
            _ => None,
        }
    }
    /// The model's name, as its manual spells it.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Xt32 => "Hesai PandarXT-32",
            Self::Qt128 => "Hesai PandarQT128",
            Self::Pandar128 => "Hesai Pandar128",
            Self::Ot128 => "Hesai OT128",
            Self::Pandar40P => "Hesai Pandar40P",
            Self::Pandar64 => "Hesai Pandar64",
            Self::PandarQT64 => "Hesai PandarQT64",
            Self::Xt16 => "Hesai PandarXT-16",
            Self::Xt32m => "Hesai PandarXT32M",
            Self::At128 => "Hesai PandarAT128",
        }
    }
    /// Time from one firing to the next, ns (1.4: in the packet's operational state).
    pub fn firing_ns(self, operational_state: u8) -> i64 {
        if let Some((_, t)) = self.fixed() {
            return t.firing_ns();
        }
        match self {
            Self::Xt32 => FIRING_NS,
            Self::Qt128 => 111_110,
            Self::Pandar128 | Self::Ot128 if operational_state == 0 => 27_778,
            _ => 55_556,
        }
    }

    /// Time of block `block`, channel `channel` (from 0) after the packet time, ns.
    ///
    /// - XT32: [`point_offset_ns`] (the packet time stamps the last firing).
    /// - QT128: the packet time stamps its start; firing `f` begins 9 + 111.11 f us later,
    ///   and its channels fire in one of two loops (the mode flag and `f` pick which), at the
    ///   times of Hesai's firing-time file for the QT128C2X.
    /// - Pandar128 and OT128: the packet time stamps its last firing; firings are 27.778 us
    ///   apart in high resolution and 55.556 us otherwise; the Pandar128's firing starts
    ///   3.148 us after it. Their channels fire at the times of Hesai's firing-time file for
    ///   the operational and azimuth state, and on the Pandar128 for the return's distance
    ///   ([`Firing::near`]).
    /// - The fixed-layout models: their firing-time tables (see `timing.rs`).
    pub fn point_offset_ns(self, block: usize, channel: usize, f: &Firing) -> i64 {
        let returns = f.blocks();
        if let Some((format, t)) = self.fixed() {
            return t.offset_ns(format.blocks, block, channel, returns);
        }
        let channel_ns = match self.table_entry(block, channel, f) {
            Some(ns) if ns != NONE => i64::from(ns),
            _ => 0,
        };
        match self {
            Self::Xt32 => point_offset_ns(block, channel, returns),
            Self::Qt128 => 9_000 + 111_110 * (block / returns) as i64 + channel_ns,
            _ => {
                let later = (self.blocks().saturating_sub(block + 1) / returns) as i64;
                let start = if self == Self::Pandar128 { 3_148 } else { 0 };
                start - self.firing_ns(f.operational_state) * later + channel_ns
            }
        }
    }

    /// The earliest and the latest of block `block`'s channel times after the packet time,
    /// near and far, ns ([`Model::point_offset_ns`]): where the firing's points begin and end.
    pub fn firing_span_ns(self, block: usize, f: &Firing) -> (i64, i64) {
        [false, true]
            .iter()
            .flat_map(|&near| {
                let f = Firing { near, ..*f };
                (0..self.channels()).map(move |c| self.point_offset_ns(block, c, &f))
            })
            .fold((i64::MAX, i64::MIN), |(lo, hi), t| (lo.min(t), hi.max(t)))
    }

    /// Whether channel `channel` fires in block `block`: the QT128's channels 1-32 do not in
    /// loop 1 nor 33-64 in loop 2, and a quarter of the OT128's and Pandar128's do not in each
    /// azimuth state of high resolution (their firing-time files list no time for them). A channel that does
    /// not fire has no return.
    pub fn fires(self, block: usize, channel: usize, f: &Firing) -> bool {
        self.table_entry(block, channel, f) != Some(NONE)
    }

    /// The firing-time file's entry for the channel in this block, if the model has one.
    fn table_entry(self, block: usize, channel: usize, f: &Firing) -> Option<u32> {
        let column = match (self, f.operational_state) {
            (Self::Qt128, _) => {
                let lp = (usize::from(f.mode_flag) + block / f.blocks() + 1) % 2;
                return QT128_NS[lp].get(channel).copied();
            }
            (Self::Ot128, 0) => usize::from(f.azimuth_state),
            (Self::Ot128, 2) if f.azimuth_state < 2 => 4 + usize::from(f.azimuth_state),
            (Self::Pandar128, 0) if f.azimuth_state < 4 => {
                return pandar128_entry(usize::from(f.azimuth_state), channel, f.near)
            }
            (Self::Pandar128, s @ (2 | 3)) if f.azimuth_state < 2 => {
                let column = 4 + 2 * usize::from(s - 2) + usize::from(f.azimuth_state);
                return pandar128_entry(column, channel, f.near);
            }
            _ => return None,
        };
        OT128_NS.get(column).and_then(|c| c.get(channel)).copied()
    }
}

/// The Pandar128's firing-time entry for a (state) column of its file, far or near.
fn pandar128_entry(column: usize, channel: usize, near: bool) -> Option<u32> {
    let column = 2 * column + usize::from(near);
    PANDAR128_NS
        .get(column)
        .and_then(|c| c.get(channel))
        .copied()
}

/// Time from a channel's firing to the next channel's within a firing, ns.
pub const CHANNEL_NS: i64 = 1_512;

/// Time of block `block`, channel `channel` after the packet time, ns, for a packet of
/// `returns` returns (the XT32 manual's timing: the last firing starts 5.632 us after the
/// packet time, the firings 50 us apart, and channel `c` fires 0.368 + 1.512 c us after its
/// firing starts). Negative: the packet time stamps its last firing.
pub const fn point_offset_ns(block: usize, channel: usize, returns: usize) -> i64 {
    let returns = if returns == 0 { 1 } else { returns };
    let firings_after = (field::BLOCKS - 1 - block) / returns;
    5_632 - FIRING_NS * firings_after as i64 + 368 + CHANNEL_NS * channel as i64
}

/// How the sensor reports its returns: the return-mode byte.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ReturnMode {
    /// One return per firing.
    Single(Return),
    /// Two returns per firing, in two consecutive blocks: which each of the pair holds.
    Dual(Return, Return),
}

impl ReturnMode {
    /// The mode a return-mode byte names for `model`, with the return each block of a dual
    /// pair holds. The evidence for each order is in the comments: nebula's recorded captures
    /// (`bench/hesai/return_order.py` counts, in every firing whose two blocks differ, which
    /// block is the nearer), the models' manuals and nebula's decoders.
    pub const fn from_byte(model: Model, b: u8) -> Option<Self> {
        // The modes each model lists (nebula's `return_mode_from_string_hesai`): the 40P, 64
        // and AT128 strongest, last and dual last + strongest (the AT128's also Hesai's SDK,
        // `HS_LIDAR_TAIL_ST_V3` of protocol 4.3); the QT64 first, last and dual first + last.
        let listed = match model {
            Model::Pandar40P | Model::Pandar64 | Model::At128 => matches!(b, 0x37..=0x39),
            Model::PandarQT64 => matches!(b, 0x33 | 0x38 | 0x3B),
            _ => true,
        };
        if !listed {
            return None;
        }
        Some(match (b, model) {
            (0x33, _) => Self::Single(Return::First),
            (0x37, _) => Self::Single(Return::Strongest),
            (0x38, _) => Self::Single(Return::Last),
            // The XT32 sends the strongest (or second strongest) before the last: on nebula's
            // XT32 capture block 0 is the nearer in all 8,829 differing pairs and the weaker in
            // 7,511 (the last is mostly the strongest). The manuals' order, last first, holds
            // on the 40P (9,147 of 9,147 pairs farther), 64 (14,744) and XT16 (4,192).
            (0x39, Model::Xt32) => Self::Dual(Return::Strongest, Return::Last),
            (0x39, _) => Self::Dual(Return::Last, Return::Strongest),
            // The QT64 sends the first before the last: block 0 the nearer in all 6,099
            // differing pairs of its capture.
            (0x3B, Model::PandarQT64) => Self::Dual(Return::First, Return::Last),
            // The others the last first: the XT16 manual's table ("0x3B: odd block last
            // return, even block first return"), nebula's XT16 and XT32 decoders (which swap
            // its default first-last order for them) and the Pandar128 manual ("Last Return in
            // 0x39 or 0x3B mode"); the XT32M follows the XT table where its capture shows
            // (0x3C, below). No recorded capture is in 0x3B mode.
            (0x3B, _) => Self::Dual(Return::Last, Return::First),
            // First before strongest: the XT32M's capture has block 0 the nearer in all 5,436
            // differing pairs.
            (0x3C, _) => Self::Dual(Return::First, Return::Strongest),
            _ => return None,
        })
    }
    /// Returns per firing: blocks per firing.
    pub const fn returns(self) -> usize {
        match self {
            Self::Single(_) => 1,
            Self::Dual(..) => 2,
        }
    }
}

/// Each channel's angles, from Hesai's angle correction file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration {
    /// Channels the file gives: the first this many entries below are used.
    pub channels: usize,
    /// Elevation of each channel, degrees (positive up), channel 1 first.
    pub elevation_deg: [f64; MAX_CHANNELS],
    /// Added to the block azimuth for each channel, degrees.
    pub azimuth_deg: [f64; MAX_CHANNELS],
}

impl Calibration {
    /// The nominal angles: channel `c` (from 0) at `15 - c` degrees, no azimuth offset (the
    /// XT32 manual's channel table; its lasers fire in one vertical line).
    pub const fn nominal() -> Self {
        let mut elevation_deg = [0.0; MAX_CHANNELS];
        let mut c = 0;
        while c < CHANNELS {
            elevation_deg[c] = 15.0 - c as f64;
            c += 1;
        }
        Self {
            channels: CHANNELS,
            elevation_deg,
            azimuth_deg: [0.0; MAX_CHANNELS],
        }
    }

    /// The PandarXT-16's nominal angles: channel `c` (from 0) at `15 - 2 c` degrees, no
    /// azimuth offset (its manual's channel table; nebula's `PandarXT16.csv`).
    pub const fn nominal_xt16() -> Self {
        let mut elevation_deg = [0.0; MAX_CHANNELS];
        let mut c = 0;
        while c < 16 {
            elevation_deg[c] = 15.0 - 2.0 * c as f64;
            c += 1;
        }
        Self {
            channels: 16,
            elevation_deg,
            azimuth_deg: [0.0; MAX_CHANNELS],
        }
    }

    /// Whether it has 1 to [`MAX_CHANNELS`] channels, every angle finite, elevations within
    /// +-90 degrees and azimuth offsets within +-45.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let n = self.channels;
        let ok = (1..=MAX_CHANNELS).contains(&n)
            && self.elevation_deg[..n]
                .iter()
                .all(|e| e.is_finite() && libm::fabs(*e) <= 90.0)
            && self.azimuth_deg[..n]
                .iter()
                .all(|a| a.is_finite() && libm::fabs(*a) <= 45.0);
        if ok {
            Ok(())
        } else {
            Err(ConfigError::Calibration)
        }
    }
}

impl Default for Calibration {
    fn default() -> Self {
        Self::nominal()
    }
}

/// Decoder settings.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Config {
    /// The sensor: its packets' protocol and timing.
    pub model: Model,
    /// Channel angles, one per channel of the model; `None` uses the nominal ones, which only
    /// the PandarXT-32 has.
    pub calibration: Option<Calibration>,
    /// Azimuth (degrees, `[0, 360)`) at which sweeps end; `None` ends a sweep once it covers
    /// a full turn from wherever the previous one ended. Sweeps are whole packets.
    pub cut_angle_deg: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn firings_are_50_us_apart_and_the_last_is_stamped() {
        // Single return: block 7 is the stamped firing, block 0 seven firings earlier.
        assert_eq!(point_offset_ns(7, 0, 1), 6_000);
        assert_eq!(point_offset_ns(0, 0, 1), 6_000 - 350_000);
        assert_eq!(point_offset_ns(7, 31, 1), 6_000 + 31 * 1_512);
        // Dual: blocks come in pairs of one firing.
        assert_eq!(point_offset_ns(6, 3, 2), point_offset_ns(7, 3, 2));
        assert_eq!(point_offset_ns(0, 0, 2), 6_000 - 150_000);
        assert_eq!(point_offset_ns(0, 0, 0), point_offset_ns(0, 0, 1));
    }

    #[test]
    fn mode_bytes_and_calibration_checks() {
        assert_eq!(
            ReturnMode::from_byte(Model::Xt32, 0x37),
            Some(ReturnMode::Single(Return::Strongest))
        );
        assert_eq!(
            ReturnMode::from_byte(Model::Xt32, 0x3C).map(ReturnMode::returns),
            Some(2)
        );
        assert_eq!(ReturnMode::from_byte(Model::Xt32, 0x3A), None);
        assert_eq!(
            ReturnMode::from_byte(Model::Xt32, 0x3B),
            Some(ReturnMode::Dual(Return::Last, Return::First))
        );
        assert_eq!(
            ReturnMode::from_byte(Model::PandarQT64, 0x3B),
            Some(ReturnMode::Dual(Return::First, Return::Last))
        );
        assert_eq!(
            ReturnMode::from_byte(Model::Xt32, 0x39),
            Some(ReturnMode::Dual(Return::Strongest, Return::Last))
        );
        assert_eq!(
            ReturnMode::from_byte(Model::Xt16, 0x39),
            Some(ReturnMode::Dual(Return::Last, Return::Strongest))
        );
        assert_eq!(ReturnMode::from_byte(Model::At128, 0x3B), None);
        assert_eq!(ReturnMode::from_byte(Model::At128, 0x3D), None);
        assert_eq!(
            ReturnMode::from_byte(Model::Qt128, 0x3B),
            Some(ReturnMode::Dual(Return::Last, Return::First))
        );
        let nominal = Calibration::nominal();
        assert_eq!(nominal.elevation_deg[0], 15.0);
        assert_eq!(nominal.elevation_deg[31], -16.0);
        assert!(nominal.validate().is_ok());
        let mut bad = nominal;
        bad.elevation_deg[3] = f64::NAN;
        assert_eq!(bad.validate(), Err(ConfigError::Calibration));
        let mut bad = nominal;
        bad.azimuth_deg[3] = 50.0;
        assert_eq!(bad.validate(), Err(ConfigError::Calibration));
        // Entries beyond the file's channels are not looked at; no channels is an error.
        let mut beyond = nominal;
        beyond.azimuth_deg[40] = f64::NAN;
        assert!(beyond.validate().is_ok());
        beyond.channels = 0;
        assert_eq!(beyond.validate(), Err(ConfigError::Calibration));
        beyond.channels = MAX_CHANNELS + 1;
        assert_eq!(beyond.validate(), Err(ConfigError::Calibration));
    }

    #[test]
    fn qt128_firings_follow_the_loops_of_the_firing_time_file() {
        let single = |mode_flag| Firing {
            returns: 1,
            mode_flag,
            ..Firing::default()
        };
        // Channel 99 fires first in loop 1 (0.6 us), channel 65 first in loop 2.
        let m = Model::Qt128;
        assert_eq!(m.point_offset_ns(0, 98, &single(1)), 9_000 + 600);
        assert_eq!(m.point_offset_ns(0, 64, &single(0)), 9_000 + 600);
        // The second firing uses the other loop, 111.11 us later.
        assert_eq!(m.point_offset_ns(1, 64, &single(1)), 9_000 + 111_110 + 600);
        // Channels 1 to 32 do not fire in loop 1, 33 to 64 not in loop 2.
        assert_eq!(m.point_offset_ns(0, 5, &single(1)), 9_000);
        assert!(!m.fires(0, 5, &single(1)) && m.fires(0, 98, &single(1)));
        assert!(!m.fires(0, 40, &single(0)) && m.fires(0, 5, &single(0)));
        // Dual: both blocks are one firing.
        let dual = Firing {
            returns: 2,
            ..single(1)
        };
        assert_eq!(m.point_offset_ns(1, 98, &dual), 9_000 + 600);
    }

    #[test]
    fn firings_of_protocol_1_4_end_at_the_packet_time() {
        let f = |operational_state, azimuth_state, returns| Firing {
            returns,
            operational_state,
            azimuth_state,
            ..Firing::default()
        };
        // Pandar128: block 1 is the stamped firing, block 0 one firing earlier; channel 8
        // fires 32.564 us into a standard firing in azimuth state 0.
        let p = Model::Pandar128;
        assert_eq!(p.point_offset_ns(1, 7, &f(2, 0, 1)), 3_148 + 32_564);
        assert_eq!(
            p.point_offset_ns(0, 7, &f(2, 0, 1)),
            3_148 - 55_556 + 32_564
        );
        assert_eq!(p.point_offset_ns(0, 7, &f(2, 0, 2)), 3_148 + 32_564);
        // High resolution: channel 8 does not fire in azimuth state 0, in state 1 at 4.786 us.
        assert!(!p.fires(0, 7, &f(0, 0, 1)) && p.fires(0, 7, &f(0, 1, 1)));
        assert_eq!(p.point_offset_ns(0, 7, &f(0, 1, 1)), 3_148 - 27_778 + 4_786);
        // A near return of channel 1 fires later: 5.201 us, not 4.436 us; energy saving
        // (state 3), azimuth state 1, channel 6: 30.209 us.
        let near = Firing {
            near: true,
            ..f(0, 0, 1)
        };
        assert_eq!(p.point_offset_ns(1, 0, &f(0, 0, 1)), 3_148 + 4_436);
        assert_eq!(p.point_offset_ns(1, 0, &near), 3_148 + 5_201);
        assert_eq!(p.point_offset_ns(1, 5, &f(3, 1, 1)), 3_148 + 30_209);
        // The span covers near returns: channel 47's 55.184 us in standard state 0.
        assert_eq!(p.firing_span_ns(1, &f(2, 0, 1)).1, 3_148 + 55_184);
        // OT128, standard mode, azimuth state 0: channel 1 at 46.645 us, state 1 the same;
        // high resolution state 1: 18.867 us; channel 3 does not fire in high-res state 1.
        let o = Model::Ot128;
        assert_eq!(o.point_offset_ns(1, 0, &f(2, 0, 1)), 46_645);
        assert_eq!(o.point_offset_ns(1, 0, &f(2, 1, 1)), 46_645);
        assert_eq!(o.point_offset_ns(1, 0, &f(0, 1, 1)), 18_867);
        assert_eq!(o.point_offset_ns(1, 2, &f(0, 1, 1)), 0);
        assert!(!o.fires(1, 2, &f(0, 1, 1)) && o.fires(1, 2, &f(0, 0, 1)));
        // Standard mode: every channel fires, channel 128 at the firing's start.
        assert!((0..128).all(|c| o.fires(0, c, &f(2, 1, 1))));
        assert_eq!(o.point_offset_ns(1, 127, &f(2, 0, 1)), 0);
        assert!(p.fires(0, 5, &f(2, 0, 1)) && Model::Xt32.fires(0, 5, &f(0, 0, 1)));
        assert_eq!(o.point_offset_ns(0, 0, &f(2, 3, 1)), -55_556);
    }
}
