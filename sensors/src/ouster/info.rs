//! What the metadata says about an Ouster sensor ([`SensorInfo`]), checked against physics,
//! and the limits of what is decoded here.

use super::wire::{Layout, Profile};
use crate::error::ConfigError;

/// Beams of the largest sensor decoded here.
pub const MAX_BEAMS: usize = 128;
/// Columns per frame of the widest mode (2048x10).
pub const MAX_COLUMNS: usize = 2048;
/// Columns per packet, at most.
pub const MAX_COLUMNS_PER_PACKET: usize = 64;
/// Largest translation of `lidar_to_sensor_transform` taken, mm: the lidar sits inside the
/// sensor's housing (36 mm above its base on the OS sensors).
pub const MAX_OFFSET_MM: f64 = 500.0;
/// Largest distance of the beam origin from the lidar origin taken, mm (OS0 27.7 mm, OS1
/// 15.8 mm, OS2 13.8 mm).
pub const MAX_BEAM_ORIGIN_MM: f64 = 200.0;
/// Largest beam azimuth offset taken, degrees (a few degrees on every OS sensor).
pub const MAX_BEAM_AZIMUTH_DEG: f64 = 45.0;

/// What the decoder needs from a sensor's metadata, as plain numbers.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorInfo {
    /// Packet profile.
    pub profile: Profile,
    /// Columns in a full frame (`1024` in `1024x10`).
    pub columns_per_frame: u16,
    /// Columns in a packet (16 for the sensors here).
    pub columns_per_packet: u16,
    /// First and last column the sensor sends (inclusive; first > last wraps).
    pub column_window: (u16, u16),
    /// Beam elevation angles, degrees, one per beam (top first).
    pub beam_altitude_deg: heapless::Vec<f64, MAX_BEAMS>,
    /// Beam azimuth offsets, degrees, one per beam.
    pub beam_azimuth_deg: heapless::Vec<f64, MAX_BEAMS>,
    /// Destaggering shift of each row (for images; points do not need it).
    pub pixel_shift_by_row: heapless::Vec<i16, MAX_BEAMS>,
    /// Beam origin in the lidar frame, 4x4 row-major, mm (older metadata: identity with
    /// `lidar_origin_to_beam_origin_mm` at `[0][3]`).
    pub beam_to_lidar: [f64; 16],
    /// Lidar frame to sensor frame, 4x4 row-major, mm.
    pub lidar_to_sensor: [f64; 16],
    /// The metadata's `initialization_id`, checked against eUDP packets.
    pub initialization_id: Option<u32>,
    /// The metadata's serial number (`prod_sn`), checked against eUDP packets.
    pub serial: Option<u64>,
    /// Rotation rate, Hz (`lidar_mode`'s second number, `10` in `1024x10`), checked against
    /// the packets' column timestamps; `None`: any rate of an Ouster mode with
    /// `columns_per_frame` columns.
    pub frequency_hz: Option<u16>,
}

impl SensorInfo {
    /// Beams (pixels per column).
    pub fn beams(&self) -> usize {
        self.beam_altitude_deg.len()
    }

    /// The packet layout this metadata announces.
    pub fn layout(&self) -> Layout {
        Layout {
            profile: self.profile,
            beams: self.beams(),
            columns: usize::from(self.columns_per_packet),
        }
    }

    /// Column `column` of row `row` in the destaggered image (ouster-sdk's `destagger`).
    pub fn destaggered_column(&self, row: usize, column: u16) -> Option<u16> {
        let shift = i32::from(*self.pixel_shift_by_row.get(row)?);
        let w = i32::from(self.columns_per_frame);
        (w > 0).then(|| (i32::from(column) + shift).rem_euclid(w) as u16)
    }

    /// Whether the numbers describe a sensor this crate can decode.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let beams = self.beams();
        if beams == 0
            || self.beam_azimuth_deg.len() != beams
            || (!self.pixel_shift_by_row.is_empty() && self.pixel_shift_by_row.len() != beams)
        {
            return Err(ConfigError::Beams);
        }
        let w = usize::from(self.columns_per_frame);
        let cpp = usize::from(self.columns_per_packet);
        let (a, b) = self.column_window;
        if w == 0
            || w > MAX_COLUMNS
            || cpp == 0
            || cpp > MAX_COLUMNS_PER_PACKET
            || usize::from(a) >= w
            || usize::from(b) >= w
        {
            return Err(ConfigError::Columns);
        }
        let finite = self
            .beam_altitude_deg
            .iter()
            .chain(self.beam_azimuth_deg.iter())
            .chain(self.beam_to_lidar.iter())
            .chain(self.lidar_to_sensor.iter())
            .all(|v| v.is_finite());
        if !finite {
            return Err(ConfigError::NonFinite);
        }
        if self.beam_altitude_deg.iter().any(|a| a.abs() > 90.0) {
            return Err(ConfigError::BeamAltitude);
        }
        if self
            .beam_azimuth_deg
            .iter()
            .any(|a| a.abs() > MAX_BEAM_AZIMUTH_DEG)
        {
            return Err(ConfigError::BeamAzimuth);
        }
        if !rigid(&self.lidar_to_sensor, MAX_OFFSET_MM) {
            return Err(ConfigError::LidarToSensor);
        }
        if !rigid(&self.beam_to_lidar, MAX_BEAM_ORIGIN_MM) {
            return Err(ConfigError::BeamToLidar);
        }
        Ok(())
    }

    /// Whether columns `spacing_ns` apart fit the metadata: `columns_per_frame` columns a
    /// turn at its rate, or at a rate of an Ouster mode with that many columns (512x10,
    /// 512x20, 1024x10, 1024x20, 2048x10, 4096x5); any spacing when neither is known. Column
    /// times jitter by about 5 %; another mode is a factor of 2 or more away.
    pub fn column_spacing_fits(&self, spacing_ns: f64) -> bool {
        spacing_fits(self.columns_per_frame, self.frequency_hz, spacing_ns)
    }
}

/// [`SensorInfo::column_spacing_fits`] for `columns` columns a turn at `frequency_hz`.
pub(crate) fn spacing_fits(columns: u16, frequency_hz: Option<u16>, spacing_ns: f64) -> bool {
    let w = f64::from(columns);
    let fits = |hz: u16| {
        let expected = 1e9 / (w * f64::from(hz));
        (0.75..=1.0 / 0.75).contains(&(spacing_ns / expected))
    };
    match (frequency_hz, columns) {
        (Some(hz), _) => hz == 0 || fits(hz),
        (None, 512 | 1024) => fits(10) || fits(20),
        (None, 2048) => fits(10),
        (None, 4096) => fits(5),
        (None, _) => true,
    }
}

/// Whether a row-major 4x4 is a rigid transform: rotation rows orthonormal (to 1e-3, as
/// calibrations print them) without reflection, last row 0 0 0 1, translation within
/// `max_translation`.
fn rigid(m: &[f64; 16], max_translation: f64) -> bool {
    let row = |i: usize| [m[4 * i], m[4 * i + 1], m[4 * i + 2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let orthonormal = (0..3).all(|i| {
        (0..3).all(|j| {
            let want = if i == j { 1.0 } else { 0.0 };
            (dot(row(i), row(j)) - want).abs() <= 1e-3
        })
    });
    let (a, b, c) = (row(0), row(1), row(2));
    let det = dot(
        a,
        [
            b[1] * c[2] - b[2] * c[1],
            b[2] * c[0] - b[0] * c[2],
            b[0] * c[1] - b[1] * c[0],
        ],
    );
    let t = [m[3], m[7], m[11]];
    orthonormal
        && det > 0.0
        && m[12..16] == [0.0, 0.0, 0.0, 1.0]
        && libm::sqrt(dot(t, t)) <= max_translation
}
