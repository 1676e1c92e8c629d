//! The Robosense spinning models decoded here and their published facts: packet layout,
//! distance unit, firing times within a block, lens centre.
//!
//! Source of every number: Robosense's rs_driver (github.com/RoboSense-LiDAR/rs_driver, commit
//! 4eeadace, `src/rs_driver/driver/decoder/decoder_<MODEL>.hpp`: `getConstParam` and
//! `calcParam`), which carries the firing tables of the user manuals' appendix "time stamp
//! calculation"; nebula's `nebula_robosense_decoders` (Helios, Bpearl) has the same.

/// Lasers of the largest model decoded here (RS-Ruby).
pub const MAX_LASERS: usize = 128;

/// A supported model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Model {
    /// RS-LiDAR-16: 16 lasers, two firing sequences a block (single return).
    Rs16,
    /// RS-LiDAR-32.
    Rs32,
    /// RS-Bpearl (hemispherical, 32 lasers; the YMD-stamped packets).
    Bpearl,
    /// RS-Helios 5515 (32 lasers, 2.5 mm ranges, UTC-stamped packets).
    Helios,
    /// RS-Helios-16P: the Helios packet with 16 lasers, two sequences a block.
    Helios16p,
    /// RS-Ruby (RS-LiDAR-128): three 128-channel blocks a packet.
    Ruby,
}

/// How the packet stamps its time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stamp {
    /// Year since 2000, month, day, hour, minute, second, ms (u16 BE), us (u16 BE): 10 bytes.
    Ymd,
    /// Seconds (48-bit BE) and microseconds (32-bit BE): 10 bytes.
    Utc,
}

/// A model's MSOP packet layout (every MSOP and DIFOP packet is 1248 bytes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// The packet's first bytes.
    pub id: &'static [u8],
    /// Where the timestamp is and how it reads.
    pub stamp: (usize, Stamp),
    /// Header bytes before the first block.
    pub header: usize,
    /// Blocks a packet.
    pub blocks: usize,
    /// The block's flag bytes (`FF EE`, or the RS-Ruby's `FE` and a return id).
    pub block_id: &'static [u8],
    /// Bytes before the block's azimuth (the flag, and the RS-Ruby's return id).
    pub azimuth_at: usize,
    /// Channels a block.
    pub channels: usize,
}

impl Layout {
    /// Bytes of a block: its flag, azimuth and channels of 3 bytes.
    pub fn block_len(&self) -> usize {
        self.azimuth_at + 2 + 3 * self.channels
    }
}

/// MSOP ids: the RS-16, RS-32 and Bpearl's 8 bytes; the Helios and Ruby's 4.
const ID_V1: [u8; 8] = [0x55, 0xAA, 0x05, 0x0A, 0x5A, 0xA5, 0x50, 0xA0];
const ID_V2: [u8; 4] = [0x55, 0xAA, 0x05, 0x5A];

// Firing times within a block, microseconds (rs_driver `calcParam` / `getConstParam`).
const RS16_FIRING: [f64; 32] = [
    0.00, 2.80, 5.60, 8.40, 11.20, 14.00, 16.80, 19.60, 22.40, 25.20, 28.00, 30.80, 33.60, 36.40,
    39.20, 42.00, 55.50, 58.30, 61.10, 63.90, 66.70, 69.50, 72.30, 75.10, 77.90, 80.70, 83.50,
    86.30, 89.10, 91.90, 94.70, 97.50,
];
const RS32_FIRING: [f64; 32] = [
    0.00, 2.88, 5.76, 8.64, 11.52, 14.40, 17.28, 20.16, 23.04, 25.92, 28.80, 31.68, 34.56, 37.44,
    40.32, 44.64, 1.44, 4.32, 7.20, 10.08, 12.96, 15.84, 18.72, 21.60, 24.48, 27.36, 30.24, 33.12,
    36.00, 38.88, 41.76, 46.08,
];
const BPEARL_FIRING: [f64; 32] = [
    0.00, 2.56, 5.12, 7.68, 10.24, 12.80, 15.36, 17.92, 25.68, 28.24, 30.80, 33.36, 35.92, 38.48,
    41.04, 43.60, 1.28, 3.84, 6.40, 8.96, 11.52, 14.08, 16.64, 19.20, 26.96, 29.52, 32.08, 34.64,
    37.20, 39.76, 42.32, 44.88,
];
/// Helios: every 1.73 us (the Helios-16P's second sequence starts at 27.68 us).
const HELIOS_FIRING_US: f64 = 1.73;
/// Ruby: groups of four every 3.236 us, channels 64-127 with 0-63.
const RUBY_FIRING_US: f64 = 3.236;

impl Model {
    /// Every supported model.
    pub const ALL: [Self; 6] = [
        Self::Rs16,
        Self::Rs32,
        Self::Bpearl,
        Self::Helios,
        Self::Helios16p,
        Self::Ruby,
    ];

    /// The name Robosense gives the model.
    pub fn name(self) -> &'static str {
        match self {
            Self::Rs16 => "RS-LiDAR-16",
            Self::Rs32 => "RS-LiDAR-32",
            Self::Bpearl => "RS-Bpearl",
            Self::Helios => "RS-Helios",
            Self::Helios16p => "RS-Helios-16P",
            Self::Ruby => "RS-Ruby",
        }
    }

    /// Lasers the model fires.
    pub fn lasers(self) -> usize {
        match self {
            Self::Rs16 | Self::Helios16p => 16,
            Self::Rs32 | Self::Bpearl | Self::Helios => 32,
            Self::Ruby => 128,
        }
    }

    /// The MSOP layout (rs_driver's `RS16MsopPkt`, `RSHELIOSMsopPkt`, `RS128MsopPkt`).
    pub fn layout(self) -> Layout {
        match self {
            Self::Rs16 | Self::Rs32 | Self::Bpearl => Layout {
                id: &ID_V1,
                stamp: (20, Stamp::Ymd),
                header: 42,
                blocks: 12,
                block_id: &[0xFF, 0xEE],
                azimuth_at: 2,
                channels: 32,
            },
            Self::Helios | Self::Helios16p => Layout {
                id: &ID_V2,
                stamp: (20, Stamp::Utc),
                header: 42,
                blocks: 12,
                block_id: &[0xFF, 0xEE],
                azimuth_at: 2,
                channels: 32,
            },
            Self::Ruby => Layout {
                id: &ID_V2,
                stamp: (10, Stamp::Utc),
                header: 80,
                blocks: 3,
                block_id: &[0xFE],
                azimuth_at: 2,
                channels: 128,
            },
        }
    }

    /// Whether `packet` reads as this model's MSOP packet (its id and first block's flag) of
    /// another layout than `other`: another Robosense model's packet.
    pub(super) fn lays_out(self, packet: &[u8], other: Layout) -> bool {
        let l = self.layout();
        l != other
            && packet.starts_with(l.id)
            && packet
                .get(l.header..)
                .is_some_and(|b| b.starts_with(l.block_id))
    }

    /// Metres per distance unit.
    pub fn distance_resolution_m(self) -> f64 {
        match self {
            Self::Helios | Self::Helios16p => 0.0025,
            _ => 0.005,
        }
    }

    /// Distance range the model measures, metres (`distance min`/`max`): returns outside it
    /// are no returns.
    pub fn range_m(self) -> (f64, f64) {
        match self {
            Self::Rs16 | Self::Rs32 => (0.4, 230.0),
            Self::Bpearl => (0.1, 150.0),
            Self::Helios | Self::Helios16p => (0.1, 180.0),
            Self::Ruby => (0.4, 250.0),
        }
    }

    /// The lens centre's offset from the sensor axis along the beam's azimuth (RX) and its
    /// height (RZ), metres.
    pub fn lens_m(self) -> (f64, f64) {
        match self {
            Self::Rs16 => (0.03825, 0.0),
            Self::Rs32 => (0.03997, 0.0),
            Self::Bpearl => (0.01473, 0.09427),
            Self::Helios | Self::Helios16p => (0.03498, 0.0),
            Self::Ruby => (0.03615, 0.0),
        }
    }

    /// Time of one firing sequence (`blk_ts`), microseconds.
    pub fn sequence_us(self) -> f64 {
        match self {
            Self::Rs16 => 55.50,
            Self::Rs32 | Self::Bpearl => 55.52,
            Self::Helios | Self::Helios16p => 55.56,
            Self::Ruby => 55.55,
        }
    }

    /// Whether a single-return block holds two firing sequences of the 16 lasers (channels
    /// 16-31 the second); in dual-return mode it holds one sequence's two returns.
    pub fn two_sequences(self) -> bool {
        matches!(self, Self::Rs16 | Self::Helios16p)
    }

    /// Channel `c`'s firing time after its block's first firing, microseconds. In dual-return
    /// mode the 16-laser models' channel `c` is laser `c % 16`'s return of one sequence.
    pub fn firing_us(self, c: usize, dual: bool) -> f64 {
        let c = if self.two_sequences() && dual {
            c % 16
        } else {
            c
        };
        match self {
            Self::Rs16 => RS16_FIRING.get(c).copied().unwrap_or(0.0),
            Self::Rs32 => RS32_FIRING.get(c).copied().unwrap_or(0.0),
            Self::Bpearl => BPEARL_FIRING.get(c).copied().unwrap_or(0.0),
            Self::Helios | Self::Helios16p => HELIOS_FIRING_US * c as f64,
            Self::Ruby => RUBY_FIRING_US * ((c % 64) / 4) as f64,
        }
    }

    /// Time a block stands for, microseconds: two sequences for a 16-laser model in single
    /// return mode, one otherwise.
    pub fn block_us(self, dual: bool) -> f64 {
        if self.two_sequences() && !dual {
            2.0 * self.sequence_us()
        } else {
            self.sequence_us()
        }
    }

    /// Blocks a firing holds (2 in dual-return mode, where a block holds each return, except
    /// the 16-laser models whose block holds both).
    pub fn blocks_per_firing(self, dual: bool) -> usize {
        if dual && !self.two_sequences() {
            2
        } else {
            1
        }
    }

    /// Time from one MSOP packet to the next, microseconds.
    pub fn packet_us(self, dual: bool) -> f64 {
        let firings = self.layout().blocks / self.blocks_per_firing(dual);
        self.block_us(dual) * firings as f64
    }

    /// The laser a channel of a block is.
    pub fn laser(self, c: usize) -> usize {
        c % self.lasers()
    }

    /// Where the DIFOP packet keeps the angles: the vertical table's offset, the horizontal
    /// table's (none for the RS-16, whose 16 vertical angles are 3-byte values in 0.0001
    /// degree), and the return-mode byte's (rs_driver `RS32DifopPkt`, `RSHELIOSDifopPkt`,
    /// `RS128DifopPkt`, `RS16DifopPkt`).
    pub fn difop(self) -> Difop {
        match self {
            Self::Rs16 => Difop {
                vertical: 1165,
                horizontal: None,
                return_mode: 300,
            },
            Self::Ruby => Difop {
                vertical: 468,
                horizontal: Some(852),
                return_mode: 300,
            },
            _ => Difop {
                vertical: 468,
                horizontal: Some(564),
                return_mode: 300,
            },
        }
    }

    /// The DIFOP return-mode byte's meaning: `Some(true)` dual, `Some(false)` single.
    pub fn dual_mode(self, byte: u8) -> Option<bool> {
        match (self, byte) {
            // Ruby: 0x03 dual, 0x01 last, 0x02 strongest.
            (Self::Ruby, 0x03) => Some(true),
            (Self::Ruby, 0x01 | 0x02) => Some(false),
            (Self::Ruby, _) => None,
            // Helios: 0x00 dual, 0x04 strongest, 0x05 last, 0x06 nearest.
            (Self::Helios | Self::Helios16p, 0x00) => Some(true),
            (Self::Helios | Self::Helios16p, 0x04..=0x06) => Some(false),
            (Self::Helios | Self::Helios16p, _) => None,
            // RS-16, RS-32, Bpearl: 0x00 dual, 0x01 strongest, 0x02 last.
            (_, 0x00) => Some(true),
            (_, 0x01 | 0x02) => Some(false),
            _ => None,
        }
    }
}

/// Where a model's DIFOP packet keeps its calibration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Difop {
    /// Offset of the vertical angle table.
    pub vertical: usize,
    /// Offset of the horizontal angle table, if the model has one.
    pub horizontal: Option<usize>,
    /// Offset of the return-mode byte.
    pub return_mode: usize,
}
