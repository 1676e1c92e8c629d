//! The Velodyne models decoded here, their published beam angles and offsets, a per-laser
//! [`Calibration`] and the decoder's [`Config`].

use crate::error::ConfigError;

/// Lasers of the largest model decoded here.
pub const MAX_LASERS: usize = 32;

/// A supported model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Model {
    /// VLP-16 (Puck, Puck LITE): 16 lasers, -15 to +15 degrees.
    Vlp16,
    /// VLP-16 Hi-Res (Puck Hi-Res): 16 lasers, -10 to +10 degrees.
    PuckHiRes,
    /// VLP-32C (Ultra Puck): 32 lasers, -25 to +15 degrees, per-laser azimuth offsets.
    Vlp32c,
    /// HDL-32E: 32 lasers, -30.67 to +10.67 degrees.
    Hdl32e,
}

// Vertical angles in firing order, degrees (manuals; the VLP-32C's to the manual's 3 decimals).
const VLP16_VERTICAL: [f64; 16] = [
    -15.0, 1.0, -13.0, 3.0, -11.0, 5.0, -9.0, 7.0, -7.0, 9.0, -5.0, 11.0, -3.0, 13.0, -1.0, 15.0,
];
const PUCK_HIRES_VERTICAL: [f64; 16] = [
    -10.0, 0.667, -8.667, 2.0, -7.333, 3.333, -6.0, 4.667, -4.667, 6.0, -3.333, 7.333, -2.0, 8.667,
    -0.667, 10.0,
];
const VLP32C_VERTICAL: [f64; 32] = [
    -25.0, -1.0, -1.667, -15.639, -11.31, 0.0, -0.667, -8.843, -7.254, 0.333, -0.333, -6.148,
    -5.333, 1.333, 0.667, -4.0, -4.667, 1.667, 1.0, -3.667, -3.333, 3.333, 2.333, -2.667, -3.0,
    7.0, 4.667, -2.333, -2.0, 15.0, 10.333, -1.333,
];
const VLP32C_AZIMUTH_OFFSET: [f64; 32] = [
    1.4, -4.2, 1.4, -1.4, 1.4, -1.4, 4.2, -1.4, 1.4, -4.2, 1.4, -1.4, 4.2, -1.4, 4.2, -1.4, 1.4,
    -4.2, 1.4, -4.2, 4.2, -1.4, 1.4, -1.4, 1.4, -1.4, 1.4, -4.2, 4.2, -1.4, 1.4, -1.4,
];
const HDL32E_VERTICAL: [f64; 32] = [
    -30.67, -9.33, -29.33, -8.0, -28.0, -6.67, -26.67, -5.33, -25.33, -4.0, -24.0, -2.67, -22.67,
    -1.33, -21.33, 0.0, -20.0, 1.33, -18.67, 2.67, -17.33, 4.0, -16.0, 5.33, -14.67, 6.67, -13.33,
    8.0, -12.0, 9.33, -10.67, 10.67,
];

// Height of each beam's origin above the sensor's origin, mm, where the envelope drawings give
// it (HDL-32E 86-0106, Puck Hi-Res 86-0129); the other models' follow from their focal
// distance (see `Model::vertical_offset_m`).
const PUCK_HIRES_VERTICAL_OFFSET_MM: [f64; 16] = [
    7.4, -0.9, 6.5, -1.8, 5.5, -2.7, 4.6, -3.7, 3.7, -4.6, 2.7, -5.5, 1.8, -6.5, 0.9, -7.4,
];
const HDL32E_VERTICAL_OFFSET_MM: [f64; 32] = [
    17.17, 4.76, 16.27, 4.07, 15.4, 3.38, 14.54, 2.7, 13.71, 2.02, 12.89, 1.35, 12.09, 0.67, 11.31,
    0.0, 10.54, -0.67, 9.78, -1.35, 9.04, -2.02, 8.3, -2.7, 7.58, -3.38, 6.86, -4.07, 6.15, -4.76,
    5.45, -5.45,
];

impl Model {
    /// The model a packet's product-id byte names.
    pub fn from_product(byte: u8) -> Option<Self> {
        match byte {
            0x22 => Some(Self::Vlp16),
            0x24 => Some(Self::PuckHiRes),
            0x28 => Some(Self::Vlp32c),
            0x21 => Some(Self::Hdl32e),
            _ => None,
        }
    }
    /// The product-id byte the model writes.
    pub fn product(self) -> u8 {
        match self {
            Self::Vlp16 => 0x22,
            Self::PuckHiRes => 0x24,
            Self::Vlp32c => 0x28,
            Self::Hdl32e => 0x21,
        }
    }
    /// Lasers the model fires.
    pub fn lasers(self) -> usize {
        match self {
            Self::Vlp16 | Self::PuckHiRes => 16,
            Self::Vlp32c | Self::Hdl32e => 32,
        }
    }
    /// Metres per distance unit.
    pub fn distance_resolution_m(self) -> f64 {
        match self {
            Self::Vlp32c => 0.004,
            _ => 0.002,
        }
    }
    /// Nominal vertical angle of each laser (firing order), degrees.
    pub fn vertical_deg(self) -> &'static [f64] {
        match self {
            Self::Vlp16 => &VLP16_VERTICAL,
            Self::PuckHiRes => &PUCK_HIRES_VERTICAL,
            Self::Vlp32c => &VLP32C_VERTICAL,
            Self::Hdl32e => &HDL32E_VERTICAL,
        }
    }
    /// Azimuth offset of each laser (added to the block azimuth), degrees.
    pub fn azimuth_offset_deg(self, laser: usize) -> f64 {
        match self {
            Self::Vlp32c => VLP32C_AZIMUTH_OFFSET.get(laser).copied().unwrap_or(0.0),
            _ => 0.0,
        }
    }
    /// Height of laser `laser`'s beam origin above the sensor origin, metres. The beams of a
    /// VLP-16 (VLP-32C) cross the axis 41.91 mm (42.4 mm) from where they leave the optics, so a
    /// beam at elevation `v` starts `f tan(-v)` above the origin (the VLP-16 manual's table
    /// of vertical corrections, 11.2 mm to -11.2 mm, is this rounded); the HDL-32E's and the
    /// Puck Hi-Res's come from their envelope drawings. velodyne-decoder applies the same.
    pub fn vertical_offset_m(self, laser: usize) -> f64 {
        let focal = |f: f64| {
            let v = self.vertical_deg().get(laser).copied().unwrap_or(0.0);
            f * libm::tan(-v.to_radians())
        };
        let table = |t: &[f64]| t.get(laser).copied().unwrap_or(0.0) * 1e-3;
        match self {
            Self::Vlp16 => focal(41.91e-3),
            Self::Vlp32c => focal(42.4e-3),
            Self::PuckHiRes => table(&PUCK_HIRES_VERTICAL_OFFSET_MM),
            Self::Hdl32e => table(&HDL32E_VERTICAL_OFFSET_MM),
        }
    }
    /// Firing cycle and single firing, microseconds: a firing's time after the packet
    /// timestamp is `cycle * k + firing * p` for the `(k, p)` of [`Self::firing_index`].
    fn timing_us(self) -> (f64, f64) {
        match self {
            // 16 firings of 2.304 us plus recharge: 55.296 us a firing sequence.
            Self::Vlp16 | Self::PuckHiRes | Self::Vlp32c => (55.296, 2.304),
            // 32 firings of 1.152 us plus 9.216 us recharge: 46.080 us.
            Self::Hdl32e => (46.080, 1.152),
        }
    }
    /// Firing sequence `k` and position `p` in it of channel `c` of firing group `g` (the block
    /// in single-return mode, the block pair in dual mode).
    fn firing_index(self, g: usize, c: usize) -> (usize, usize) {
        match self {
            // Two sequences of 16 lasers a block.
            Self::Vlp16 | Self::PuckHiRes => (2 * g + c / 16, c % 16),
            // Two lasers fire at once.
            Self::Vlp32c => (g, c / 2),
            Self::Hdl32e => (g, c),
        }
    }
    /// Time of channel `c` of firing group `g` after the packet timestamp, seconds.
    pub fn firing_time_s(self, g: usize, c: usize) -> f64 {
        let (cycle, single) = self.timing_us();
        let (k, p) = self.firing_index(g, c);
        // Written as the manuals' tables (and velodyne-decoder) compute it.
        cycle * 1e-6 * k as f64 + single * 1e-6 * p as f64
    }
    /// Time from one data packet to the next, microseconds (12 firing groups, or 6 block
    /// pairs in dual-return mode).
    pub fn packet_us(self, dual: bool) -> f64 {
        let groups = if dual { 6.0 } else { 12.0 };
        self.group_us() * groups
    }
    /// The name the manuals give the model.
    pub fn name(self) -> &'static str {
        match self {
            Self::Vlp16 => "VLP-16",
            Self::PuckHiRes => "Puck Hi-Res",
            Self::Vlp32c => "VLP-32C",
            Self::Hdl32e => "HDL-32E",
        }
    }
    /// Every supported model.
    pub const ALL: [Self; 4] = [Self::Vlp16, Self::PuckHiRes, Self::Vlp32c, Self::Hdl32e];
    /// Time from one firing group to the next, microseconds.
    pub fn group_us(self) -> f64 {
        let (cycle, _) = self.timing_us();
        let (k, _) = self.firing_index(1, 0);
        cycle * k as f64
    }
}

/// One laser's corrections.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Laser {
    /// Elevation, degrees (positive up).
    pub vertical_deg: f64,
    /// Added to the block azimuth, degrees (Velodyne's XML `rotCorrection_` with its sign
    /// flipped; the ROS YAML's `-rot_correction` in degrees).
    pub azimuth_offset_deg: f64,
    /// Added to the distance, metres.
    pub distance_offset_m: f64,
    /// Added to z, metres.
    pub vertical_offset_m: f64,
    /// Offset across the beam in the horizontal plane, metres.
    pub horizontal_offset_m: f64,
}

/// Per-laser corrections for one sensor, in firing order.
#[derive(Clone, Debug, PartialEq)]
pub struct Calibration {
    /// One entry per laser.
    pub lasers: heapless::Vec<Laser, MAX_LASERS>,
    /// Metres per distance unit.
    pub distance_resolution_m: f64,
}

impl Calibration {
    /// The manuals' nominal values for `model`: vertical angles, azimuth offsets, beam-origin
    /// heights.
    pub fn nominal(model: Model) -> Self {
        let mut lasers = heapless::Vec::new();
        for (i, &v) in model.vertical_deg().iter().enumerate() {
            let laser = Laser {
                vertical_deg: v,
                azimuth_offset_deg: model.azimuth_offset_deg(i),
                vertical_offset_m: model.vertical_offset_m(i),
                ..Laser::default()
            };
            // The tables have at most MAX_LASERS entries.
            let _ = lasers.push(laser);
        }
        Self {
            lasers,
            distance_resolution_m: model.distance_resolution_m(),
        }
    }

    /// Whether every number is finite and the laser count is one a supported model fires.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let finite = self.distance_resolution_m.is_finite()
            && self.distance_resolution_m > 0.0
            && self.lasers.iter().all(|l| {
                [
                    l.vertical_deg,
                    l.azimuth_offset_deg,
                    l.distance_offset_m,
                    l.vertical_offset_m,
                    l.horizontal_offset_m,
                ]
                .iter()
                .all(|v| v.is_finite())
            });
        if !finite || !matches!(self.lasers.len(), 16 | 32) {
            return Err(ConfigError::Calibration);
        }
        Ok(())
    }
}

/// Decoder settings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Config {
    /// The model; `None` reads it from the first packet's product-id byte (needed for old
    /// HDL-32E firmware, which leaves the byte 0).
    pub model: Option<Model>,
    /// Per-laser corrections; `None` uses the model's nominal values.
    pub calibration: Option<Calibration>,
    /// Azimuth (degrees, `[0, 360)`) at which sweeps end; `None` ends a sweep once it covers
    /// a full turn from wherever the previous one ended (velodyne-decoder's default). Sweeps
    /// are whole packets: the packet whose last block passes the cut ends its sweep.
    pub cut_angle_deg: Option<f64>,
}
