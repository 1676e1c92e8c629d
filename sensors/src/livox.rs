//! Livox sensors: packets to timed points, frames cut by time. SDK 1 (Mid-40, Mid-70, Horizon,
//! Tele-15, Avia: [`sdk1`]) and SDK 2 (Mid-360, HAP: [`sdk2`]).
//!
//! A Livox sensor does not spin: its prisms (or, on the Mid-360, its rotating mirror) draw a
//! non-repeating pattern, and the packets carry Cartesian (or spherical) points already in the
//! sensor frame, x forward, y left, z up. There is no sweep to end, so frames are cut by time,
//! every [`Config::frame_period_ns`] (the Livox ROS driver's 0.1 s by default) from the first
//! packet's time; a packet belongs to the frame its first point falls in. Each point's time is
//! the packet's timestamp (its first point's) plus its firing's index times the firing
//! interval: on SDK 1 the model's (Livox SDK 1 documentation: 10 us on the Mid-40/70, 100,000
//! points a second; 4.167 us on the Horizon, Tele-15 and Avia, 240,000), on SDK 2 the packet's
//! own `time_interval / dot_num` (5 us on the Mid-360, 200,000 points a second). Tags (the
//! noise flags) and return numbers are kept ([`crate::PointMeta`]); points at the origin (no
//! return) are dropped. IMU packets (SDK 1 data type 6, sent to the point port; SDK 2 data
//! type 0, sent to a port of their own) are not points: [`sdk1::Packet::imu`] and
//! [`sdk2::Packet::imu`] read them.

mod decoder;
pub mod sdk1;
pub mod sdk2;

pub use decoder::{Decoder, GAP_NS};

/// The model: which protocol, and on SDK 1 the firing interval.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Model {
    /// Mid-40 and Mid-70 (SDK 1): 100,000 firings a second.
    Mid40,
    /// Horizon, Tele-15 and Avia (SDK 1): 240,000 firings a second.
    #[default]
    Horizon,
    /// Mid-360 and HAP (SDK 2): each packet states the time its points span.
    Mid360,
}

impl Model {
    /// Time from one firing to the next on SDK 1, ns; `None` on SDK 2, whose packets say.
    pub const fn firing_ns(self) -> Option<f64> {
        match self {
            Self::Mid40 => Some(10_000.0),
            Self::Horizon => Some(1e9 / 240_000.0),
            Self::Mid360 => None,
        }
    }
}

/// Decoder settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// The model (its protocol and firing interval).
    pub model: Model,
    /// Length of a frame, ns.
    pub frame_period_ns: u64,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            model: Model::default(),
            frame_period_ns: 100_000_000,
        }
    }
}

/// One return of either protocol: metres in the sensor frame (x forward, y left, z up),
/// reflectivity and tag; `None` where the sensor saw nothing (all zero).
pub type Return = Option<([f64; 3], u8, u8)>;

/// One IMU sample, as both protocols send it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ImuSample {
    /// Angular rate, rad/s.
    pub gyro: [f32; 3],
    /// Specific force, in g (standard gravities) as the sensor sends it.
    pub accel_g: [f32; 3],
}

impl ImuSample {
    /// The sample at `from`: six little-endian f32, gyroscope x, y, z then accelerometer.
    fn read(b: &[u8], from: usize) -> Self {
        let f = |i: usize| f32::from_le_bytes(at(b, from + 4 * i));
        Self {
            gyro: [f(0), f(1), f(2)],
            accel_g: [f(3), f(4), f(5)],
        }
    }
}

/// `N` bytes from `from`, zeros where the buffer ends (lengths are checked before any read).
fn at<const N: usize>(b: &[u8], from: usize) -> [u8; N] {
    let mut out = [0u8; N];
    if let Some(s) = b.get(from..from + N) {
        out.copy_from_slice(s);
    }
    out
}

fn byte(b: &[u8], i: usize) -> u8 {
    b.get(i).copied().unwrap_or(0)
}

fn u16_at(b: &[u8], from: usize) -> u16 {
    u16::from_le_bytes(at(b, from))
}

/// A spherical point (metres, zenith and azimuth in degrees) in the sensor frame.
fn spherical(depth: f64, zenith_deg: f64, azimuth_deg: f64) -> [f64; 3] {
    let (st, ct) = (
        libm::sin(zenith_deg.to_radians()),
        libm::cos(zenith_deg.to_radians()),
    );
    let (sp, cp) = (
        libm::sin(azimuth_deg.to_radians()),
        libm::cos(azimuth_deg.to_radians()),
    );
    [depth * st * cp, depth * st * sp, depth * ct]
}
