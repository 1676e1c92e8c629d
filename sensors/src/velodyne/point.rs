//! One Velodyne return to a point: the precision azimuth between two firing groups and the
//! calibrated beam (elevation, azimuth offset, distance corrections, beam-origin offsets).

use super::calibration::Laser;
use super::wire::AZIMUTH_UNITS;

/// One laser, ready to use.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Beam {
    cos_v: f64,
    sin_v: f64,
    offset_rad: f64,
    distance_offset: f64,
    vertical_offset: f64,
    horizontal_offset: f64,
    /// The HDL-64E's near-point distance offsets (x, y), metres.
    near: Option<[f64; 2]>,
    /// Ring: 0 the lowest laser.
    pub ring: u16,
}

impl Beam {
    /// No laser.
    pub(super) const ZERO: Self = Self {
        cos_v: 0.0,
        sin_v: 0.0,
        offset_rad: 0.0,
        distance_offset: 0.0,
        vertical_offset: 0.0,
        horizontal_offset: 0.0,
        near: None,
        ring: 0,
    };

    pub(super) fn new(l: &Laser) -> Self {
        let v = l.vertical_deg.to_radians();
        Self {
            cos_v: libm::cos(v),
            sin_v: libm::sin(v),
            offset_rad: l.azimuth_offset_deg.to_radians(),
            distance_offset: l.distance_offset_m,
            vertical_offset: l.vertical_offset_m,
            horizontal_offset: l.horizontal_offset_m,
            near: l.near_distance_offset_m,
            ring: 0,
        }
    }

    /// A return in the sensor frame: x forward, y left, z up (the ROS convention).
    pub(super) fn point(&self, resolution: f64, raw: u16, az: u16) -> [f64; 3] {
        let r = f64::from(raw) * resolution;
        let theta = azimuth_rad(az) + self.offset_rad;
        let (s, c) = (libm::sin(theta), libm::cos(theta));
        let (dx, dy) = self.two_point(r, s, c);
        [
            (r + dy) * self.cos_v * c + self.horizontal_offset * s,
            -(r + dx) * self.cos_v * s + self.horizontal_offset * c,
            (r + dy) * self.sin_v + self.vertical_offset,
        ]
    }

    /// The distance corrections along Velodyne's x (our -y) and y (our x): the far point's
    /// offset, or for an HDL-64E laser with near points within the far point's 25.04 m, the
    /// offsets interpolated linearly between the near point (2.40 m along x, 1.93 m along y)
    /// and the far point by how far the return lies along each axis. HDL-64E S3 manual's
    /// two-point calibration, as velodyne-decoder applies it; z takes the y correction as the
    /// manual writes (velodyne-decoder averages x and y there).
    fn two_point(&self, r: f64, s: f64, c: f64) -> (f64, f64) {
        const FAR: f64 = 25.04;
        const NEAR_X: f64 = 2.40;
        const NEAR_Y: f64 = 1.93;
        let far = self.distance_offset;
        match self.near {
            Some([near_x, near_y]) if r < FAR => {
                let xy = (r + far) * self.cos_v;
                let (xx, yy) = ((xy * s).abs(), (xy * c).abs());
                let kx = (xx - NEAR_X) / (FAR - NEAR_X);
                let ky = (yy - NEAR_Y) / (FAR - NEAR_Y);
                (
                    kx * far + (1.0 - kx) * near_x,
                    ky * far + (1.0 - ky) * near_y,
                )
            }
            _ => (far, far),
        }
    }
}

/// A firing group's rotation: `turn` hundredths of a degree over `groups` firing groups.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Gap {
    pub turn: u32,
    pub groups: u32,
}

/// The azimuth `tick` ticks into a firing group of `group` ticks that turns `gap` from
/// `block_az`, rounded half up to the hundredth the sensor reports (the resolution nebula,
/// velodyne-decoder and the ROS driver also round to). Exact: integers.
pub(super) fn interpolate(block_az: u16, gap: Gap, tick: u32, group: u32) -> u16 {
    let den = u64::from(group.max(1)) * u64::from(gap.groups.max(1));
    let scaled = u64::from(block_az) * den + u64::from(gap.turn) * u64::from(tick);
    let rounded = (2 * scaled + den) / (2 * den);
    (rounded % u64::from(AZIMUTH_UNITS)) as u16
}

/// Azimuth units to radians through f32, as the sine tables of nebula and velodyne-decoder:
/// their angles are up to 2e-6 rad off the exact hundredth (a hundredth of the 0.01 degree
/// quantisation), which at 200 m moves a point by 3e-4 m; taking the same angle keeps them
/// within 1e-4 m.
fn azimuth_rad(az: u16) -> f64 {
    let deg2rad = (core::f64::consts::PI / 180.0) as f32;
    f64::from(0.01f32 * f32::from(az) * deg2rad)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_rounds_exact_halves_up_and_wraps() {
        let gap = |turn| Gap { turn, groups: 1 };
        // 20 hundredths over 48 ticks, 6 ticks in: 2.5 -> 3.
        assert_eq!(interpolate(100, gap(20), 6, 48), 103);
        assert_eq!(interpolate(100, gap(20), 5, 48), 102);
        assert_eq!(interpolate(35_999, gap(40), 24, 48), 19);
        assert_eq!(interpolate(500, gap(0), 47, 48), 500);
        // A mean step: 219 hundredths over 11 groups, half a group in: 9.95 -> 10.
        let mean = Gap {
            turn: 219,
            groups: 11,
        };
        assert_eq!(interpolate(100, mean, 24, 48), 110);
    }

    #[test]
    fn two_point_correction_reaches_the_far_offset_at_the_far_point() {
        let laser = Laser {
            distance_offset_m: 1.5,
            near_distance_offset_m: Some([1.4, 1.3]),
            ..Laser::default()
        };
        let b = Beam::new(&laser);
        // Along our x (Velodyne y) at the far point, the y correction is the far one.
        let (_, dy) = b.two_point(25.04 - 1.5, 0.0, 1.0);
        assert!((dy - 1.5).abs() < 1e-12);
        // At the near point along y, the near one.
        let (_, dy) = b.two_point(1.93 - 1.5, 0.0, 1.0);
        assert!((dy - 1.3).abs() < 1e-12);
        // Beyond the far point, the far offset on both axes.
        assert_eq!(b.two_point(30.0, 0.6, 0.8), (1.5, 1.5));
    }
}
