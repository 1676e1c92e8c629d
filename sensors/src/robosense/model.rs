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
    /// RS-Airy (96 lasers, its 96-channel mode): eight blocks of 48 channels a packet, a
    /// firing's lasers 0-47 in its even block and 48-95 in its odd one.
    Airy,
}

/// The RS-Airy's firing table, which its DIFOP packet's install-mode byte picks (rs_driver
/// `decoder_RSAIRY.hpp`, `decodeMsopPkt`): 0 mounted normally, 1 on its side, 2 the Airy M. A
/// unit that does not say (0xFF), or angles from a file, fire as the Airy M: rs_driver's
/// default table.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AiryInstall {
    /// Install mode 0.
    Normal,
    /// Install mode 1.
    Side,
    /// Install mode 2, or not said.
    #[default]
    AiryM,
}

impl AiryInstall {
    /// The install-mode byte's table.
    pub fn from_byte(b: u8) -> Self {
        match b {
            0 => Self::Normal,
            1 => Self::Side,
            _ => Self::AiryM,
        }
    }

    /// The byte a DIFOP packet writes for it.
    pub fn byte(self) -> u8 {
        match self {
            Self::Normal => 0,
            Self::Side => 1,
            Self::AiryM => 2,
        }
    }
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
/// RS-Airy: its 96 lasers fire in 12 groups of eight (`firing_tss_normal`, `_side`,
/// `_airy_m`); the group's time, us.
const AIRY_NORMAL: [f64; 12] = [
    0.0, 5.712, 12.376, 19.040, 25.704, 33.320, 41.888, 50.456, 59.024, 70.448, 81.872, 93.296,
];
const AIRY_SIDE: [f64; 12] = [
    0.0, 11.424, 22.848, 34.272, 45.696, 54.264, 62.832, 71.400, 79.016, 85.680, 92.344, 99.008,
];
const AIRY_M: [f64; 12] = [
    0.0, 7.616, 16.184, 24.752, 33.320, 42.840, 52.360, 61.880, 71.400, 79.968, 88.536, 97.104,
];
/// RS-Airy: MSOP header bytes (`RSAIRYHeader`): the data type (0 for points), the return
/// mode (0x03 dual), the channel mode (0x02 the 96-channel mode decoded here).
pub const AIRY_DATA_TYPE: usize = 16;
/// See [`AIRY_DATA_TYPE`].
pub const AIRY_RETURN_MODE: usize = 17;
/// See [`AIRY_DATA_TYPE`].
pub const AIRY_CHANNEL_MODE: usize = 32;
/// The RS-Airy's channel-mode byte for 96 channels.
pub const AIRY_96: u8 = 0x02;
/// The RS-Airy's DIFOP install-mode byte (`RSAIRYDifopPkt::install_mode`).
pub const AIRY_INSTALL: usize = 289;

impl Model {
    /// Every supported model.
    pub const ALL: [Self; 7] = [
        Self::Rs16,
        Self::Rs32,
        Self::Bpearl,
        Self::Helios,
        Self::Helios16p,
        Self::Ruby,
        Self::Airy,
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
            Self::Airy => "RS-Airy",
        }
    }

    /// Lasers the model fires.
    pub fn lasers(self) -> usize {
        match self {
            Self::Rs16 | Self::Helios16p => 16,
            Self::Rs32 | Self::Bpearl | Self::Helios => 32,
            Self::Ruby => 128,
            Self::Airy => 96,
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
            // `RSAIRYMsopPkt`: the Helios's header, id, stamp and block flags; 8 blocks of 48
            // channels, 22 tail bytes.
            Self::Airy => Layout {
                blocks: 8,
                channels: 48,
                ..Self::Helios.layout()
            },
        }
    }

    /// Whether `packet` reads as this model's MSOP packet of another layout than `other`:
    /// another Robosense model's packet.
    pub(super) fn lays_out(self, packet: &[u8], other: Layout) -> bool {
        self.layout() != other && self.writes(packet)
    }

    /// Whether `packet` has this model's MSOP id and every block's flag where its layout puts
    /// them.
    pub(super) fn writes(self, packet: &[u8]) -> bool {
        let l = self.layout();
        packet.starts_with(l.id)
            && (0..l.blocks).all(|k| {
                packet
                    .get(l.header + k * l.block_len()..)
                    .is_some_and(|b| b.starts_with(l.block_id))
            })
    }

    /// Metres per distance unit.
    pub fn distance_resolution_m(self) -> f64 {
        match self {
            Self::Helios | Self::Helios16p => 0.0025,
            _ => 0.005,
        }
    }

    /// The distance field's bits that are the distance (the RS-Airy's top two are a feature
    /// flag, rs_driver's `& 0x3FFF`).
    pub fn distance_mask(self) -> u16 {
        match self {
            Self::Airy => 0x3FFF,
            _ => u16::MAX,
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
            Self::Airy => (0.1, 60.0),
        }
    }

    /// The lens centre's offset from the sensor axis along the beam's azimuth (RX; the
    /// RS-Airy's `sqrt(RX^2 + RY^2)`, as rs_driver) and its height (RZ), metres.
    pub fn lens_m(self) -> (f64, f64) {
        match self {
            Self::Airy => (libm::sqrt(0.0075 * 0.0075 + 0.00664 * 0.00664), 0.04532),
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
            Self::Airy => 111.08,
        }
    }

    /// Whether a single-return block holds two firing sequences of the 16 lasers (channels
    /// 16-31 the second); in dual-return mode it holds one sequence's two returns.
    pub fn two_sequences(self) -> bool {
        matches!(self, Self::Rs16 | Self::Helios16p)
    }

    /// Blocks one firing's lasers fill (the RS-Airy's 96 in two blocks of 48).
    pub fn halves(self) -> usize {
        match self {
            Self::Airy => 2,
            _ => 1,
        }
    }

    /// Channel `c` of the `k`-th block of a firing's return, numbered over the firing's
    /// blocks: the RS-Airy's odd blocks hold channels 48-95.
    pub fn channel(self, k: usize, c: usize) -> usize {
        (k % self.halves()) * self.layout().channels + c
    }

    /// Channel `c`'s (see [`Self::channel`]) firing time after its block's first firing,
    /// microseconds. In dual-return mode the 16-laser models' channel `c` is laser `c % 16`'s
    /// return of one sequence. `install` picks the RS-Airy's table; the others ignore it.
    pub fn firing_us(self, c: usize, dual: bool, install: AiryInstall) -> f64 {
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
            Self::Airy => {
                let table = match install {
                    AiryInstall::Normal => &AIRY_NORMAL,
                    AiryInstall::Side => &AIRY_SIDE,
                    AiryInstall::AiryM => &AIRY_M,
                };
                table.get(c / 8).copied().unwrap_or(0.0)
            }
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

    /// Blocks a firing holds: its [`Self::halves`], twice in dual-return mode, where blocks
    /// hold each return (the 16-laser models' block holds both).
    pub fn blocks_per_firing(self, dual: bool) -> usize {
        if dual && !self.two_sequences() {
            2 * self.halves()
        } else {
            self.halves()
        }
    }

    /// Time from one MSOP packet to the next, microseconds (on average: the RS-Ruby's
    /// dual-return packets hold one and a half firings).
    pub fn packet_us(self, dual: bool) -> f64 {
        let firings = self.layout().blocks as f64 / self.blocks_per_firing(dual) as f64;
        self.block_us(dual) * firings
    }

    /// The laser a channel (see [`Self::channel`]) is.
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
            Self::Airy => Difop {
                vertical: 468,
                horizontal: Some(756),
                return_mode: 300,
            },
            _ => Difop {
                vertical: 468,
                horizontal: Some(564),
                return_mode: 300,
            },
        }
    }

    /// The DIFOP return-mode byte's meaning: `Some(true)` dual, `Some(false)` single (the
    /// RS-Airy says it in each MSOP packet instead, [`AIRY_RETURN_MODE`]: `None`).
    pub fn dual_mode(self, byte: u8) -> Option<bool> {
        match (self, byte) {
            (Self::Airy, _) => None,
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
