//! The Livox Mid-360 as the simulator fires it: a non-repetitive 360 x 59 degree pattern
//! written as Livox SDK 2 point packets.
//!
//! The Mid-360 has four lasers on a rotor, each deflected up and down by a second, faster
//! optical element (Livox: "360 degrees horizontal, -7 to 52 degrees vertical, 200,000 points
//! a second", four lines). Modelled so: the lasers fire in turn every 5 us, 90 degrees apart on
//! a rotor turning [`ROTOR_HZ`] times a second, each nodding over the vertical field at
//! [`NOD_HZ`], a rate no whole number of turns repeats: each frame's zig-zags fall between the
//! last frame's, and the field fills in over time as the sensor's does. A packet holds 96
//! points (480 us, `time_interval` 4800), data type 1 (x, y, z in mm), stamped with its first
//! point's time in ns since the sensor started; a frame is every packet whose first point
//! falls in its period, as the decoder cuts them.

use super::{unit, Packet, PacketSim, Timing, Truth};
use kiss_odom_sensors::livox::sdk2::{self, field};
use nalgebra::Vector3;

/// Points per packet.
pub const POINTS: usize = sdk2::MID360_POINTS;
/// Time from one point to the next, ns (200,000 points a second).
pub const POINT_NS: u64 = 5_000;
/// Time a packet spans, ns.
pub const PACKET_NS: u64 = POINT_NS * POINTS as u64;
/// The points' timing.
pub(super) const TIMING: Timing = Timing {
    points: POINTS,
    packet_ns: PACKET_NS,
    point_ns: POINT_NS as f64,
};
/// Lasers, firing in turn.
const LASERS: usize = 4;
/// Rotor turns a second.
const ROTOR_HZ: f64 = 10.0;
/// Vertical sweeps a second, each laser: not a multiple of the rotor's rate.
const NOD_HZ: f64 = 1473.1;
/// The vertical field, degrees.
const ELEVATION_DEG: (f64, f64) = (-7.0, 52.0);

/// Direction of the point fired at trajectory time `t` (s) by laser `laser`, sensor frame.
fn direction(t: f64, laser: usize) -> Vector3<f64> {
    use core::f64::consts::{FRAC_PI_2, TAU};
    let azimuth = TAU * ROTOR_HZ * t + laser as f64 * FRAC_PI_2;
    let (lo, hi) = ELEVATION_DEG;
    let nod = libm::sin(TAU * NOD_HZ * t + laser as f64 * 0.9);
    let elevation = (0.5 * (lo + hi) + 0.5 * (hi - lo) * nod).to_radians();
    unit(azimuth, elevation)
}

impl PacketSim<'_> {
    pub(super) fn mid360_packet(&self, p: u64) -> (Packet, Vec<Truth>) {
        let len = sdk2::packet_len(1, POINTS).unwrap_or(field::DATA);
        let mut buf = vec![0u8; len];
        buf[field::LENGTH].copy_from_slice(&(len as u16).to_le_bytes());
        buf[field::TIME_INTERVAL].copy_from_slice(&((PACKET_NS / 100) as u16).to_le_bytes());
        buf[field::DOT_NUM].copy_from_slice(&(POINTS as u16).to_le_bytes());
        buf[field::UDP_CNT].copy_from_slice(&(p as u16).to_le_bytes());
        buf[field::DATA_TYPE] = 1;
        buf[field::TIMESTAMP].copy_from_slice(&self.timed_stamp_ns(p).to_le_bytes());
        let (mut packet, truth) =
            self.livox_packet(p, buf, field::DATA, |t, n| direction(t, n % LASERS));
        let crc = sdk2::crc32(&packet.payload[field::TIMESTAMP.start..]);
        packet.payload[field::CRC32].copy_from_slice(&crc.to_le_bytes());
        (packet, truth)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pattern_covers_the_field_and_does_not_repeat_from_frame_to_frame() {
        let (lo, hi) = ELEVATION_DEG;
        // One frame's directions, and the next frame's at the same instants within it.
        let frame = |k: f64| -> Vec<Vector3<f64>> {
            (0..20_000)
                .map(|n| direction(k * 0.1 + n as f64 * 5e-6, n % LASERS))
                .collect()
        };
        let (a, b) = (frame(0.0), frame(1.0));
        let elevation = |d: &Vector3<f64>| libm::asin(d.z).to_degrees();
        let (min, max) = a
            .iter()
            .map(elevation)
            .fold((90.0f64, -90.0f64), |(l, h), e| (l.min(e), h.max(e)));
        println!("elevations {min:.2}..{max:.2} deg (field {lo}..{hi})");
        assert!(min >= lo - 1e-9 && max <= hi + 1e-9);
        assert!(min < lo + 0.5 && max > hi - 0.5, "the whole vertical field");
        // Every 10-degree azimuth sector holds points in every 10-degree elevation band.
        let mut cells = [[0u32; 6]; 36];
        for d in &a {
            let az = libm::atan2(d.y, d.x).to_degrees().rem_euclid(360.0);
            let band = ((elevation(d) - lo) / 10.0) as usize;
            cells[(az / 10.0) as usize % 36][band.min(5)] += 1;
        }
        let empty = cells.iter().flatten().filter(|&&c| c == 0).count();
        assert_eq!(empty, 0, "{cells:?}");
        crate::packets::tests::assert_not_retraced(&a, &b);
    }
}
