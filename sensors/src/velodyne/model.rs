//! The Velodyne models decoded here and their published beam angles and offsets (the
//! per-laser [`super::Calibration`] starts from these).

/// Lasers of the largest model decoded here (the VLS-128).
pub const MAX_LASERS: usize = 128;

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
    /// VLP-32A and VLP-32B (product id 0x23, which does not tell them apart): the VLP-32C's
    /// packet and timing with the unit's own angles, so its calibration file is needed.
    Vlp32ab,
    /// HDL-32E: 32 lasers, -30.67 to +10.67 degrees.
    Hdl32e,
    /// HDL-64E S2: 64 lasers in an upper and a lower block of 32; the unit's calibration file
    /// gives every laser's angles and distance corrections. No product id in its packets.
    Hdl64eS2,
    /// HDL-64E S3: the S2's packet with its own firing timing and a dual-return mode.
    Hdl64eS3,
    /// VLS-128 (Alpha Prime): 128 lasers in four banks of 32, fired in groups of eight; its
    /// calibration file gives the angles.
    Vls128,
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

/// The block flags (little-endian `FF EE`, `FF DD`, `FF CC`, `FF BB`) of the lasers 0-31,
/// 32-63, 64-95 and 96-127 (HDL-64E S3 manual: upper and lower block; VLS-128 manual
/// 63-9483 section 9.3.2: banks 1 to 4).
pub const BANK_FLAGS: [u16; 4] = [0xEEFF, 0xDDFF, 0xCCFF, 0xBBFF];

impl Model {
    /// The model a packet's product-id byte names (HDL-64E packets carry none).
    pub fn from_product(byte: u8) -> Option<Self> {
        // Factory byte table of the VLP-16 manual 63-9243 (Table 9-2); 0x23 and 0xA1 as
        // velodyne-decoder's PacketModelId (VLP-32A/B, VLS-128 Alpha Prime); 0x63 is the
        // VLS-128 manual's.
        match byte {
            0x22 => Some(Self::Vlp16),
            0x24 => Some(Self::PuckHiRes),
            0x28 => Some(Self::Vlp32c),
            0x23 => Some(Self::Vlp32ab),
            0x21 => Some(Self::Hdl32e),
            0xA1 | 0x63 => Some(Self::Vls128),
            _ => None,
        }
    }
    /// The product-id byte the model writes (`None` for the HDL-64E, whose bytes 1204 and
    /// 1205 are a status type and value instead).
    pub fn product(self) -> Option<u8> {
        match self {
            Self::Vlp16 => Some(0x22),
            Self::PuckHiRes => Some(0x24),
            Self::Vlp32c => Some(0x28),
            Self::Vlp32ab => Some(0x23),
            Self::Hdl32e => Some(0x21),
            Self::Vls128 => Some(0xA1),
            Self::Hdl64eS2 | Self::Hdl64eS3 => None,
        }
    }
    /// Lasers the model fires.
    pub fn lasers(self) -> usize {
        match self {
            Self::Vlp16 | Self::PuckHiRes => 16,
            Self::Vlp32c | Self::Vlp32ab | Self::Hdl32e => 32,
            Self::Hdl64eS2 | Self::Hdl64eS3 => 64,
            Self::Vls128 => 128,
        }
    }
    /// Banks of 32 lasers, each in a block of its own flag ([`BANK_FLAGS`]).
    pub fn banks(self) -> usize {
        self.lasers().div_ceil(32)
    }
    /// Metres per distance unit (the VLP-32C, VLP-32A/B and VLS-128 count 4 mm; the others 2
    /// mm, the HDL-64E's calibration file may say otherwise).
    pub fn distance_resolution_m(self) -> f64 {
        match self {
            Self::Vlp32c | Self::Vlp32ab | Self::Vls128 => 0.004,
            _ => 0.002,
        }
    }
    /// Whether the model needs the unit's calibration file (no nominal angles here).
    pub fn needs_calibration(self) -> bool {
        matches!(
            self,
            Self::Vlp32ab | Self::Hdl64eS2 | Self::Hdl64eS3 | Self::Vls128
        )
    }
    /// Whether the packets say the return mode (byte 1204); the HDL-64E's show it by their
    /// azimuths instead (a dual-return packet repeats each firing's azimuth over four blocks).
    pub fn has_mode_byte(self) -> bool {
        !matches!(self, Self::Hdl64eS2 | Self::Hdl64eS3)
    }
    /// Nominal vertical angle of each laser (firing order), degrees; empty for the models
    /// that need their calibration file.
    pub fn vertical_deg(self) -> &'static [f64] {
        match self {
            Self::Vlp16 => &VLP16_VERTICAL,
            Self::PuckHiRes => &PUCK_HIRES_VERTICAL,
            Self::Vlp32c => &VLP32C_VERTICAL,
            Self::Hdl32e => &HDL32E_VERTICAL,
            _ => &[],
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
            _ => 0.0,
        }
    }
    /// The name the manuals give the model.
    pub fn name(self) -> &'static str {
        match self {
            Self::Vlp16 => "VLP-16",
            Self::PuckHiRes => "Puck Hi-Res",
            Self::Vlp32c => "VLP-32C",
            Self::Vlp32ab => "VLP-32A/B",
            Self::Hdl32e => "HDL-32E",
            Self::Hdl64eS2 => "HDL-64E S2",
            Self::Hdl64eS3 => "HDL-64E S3",
            Self::Vls128 => "VLS-128",
        }
    }
    /// Every supported model.
    pub const ALL: [Self; 8] = [
        Self::Vlp16,
        Self::PuckHiRes,
        Self::Vlp32c,
        Self::Vlp32ab,
        Self::Hdl32e,
        Self::Hdl64eS2,
        Self::Hdl64eS3,
        Self::Vls128,
    ];
}
