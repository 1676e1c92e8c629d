//! The Livox Avia as the simulator fires it: a non-repetitive 70.4 x 77.2 degree rosette
//! written as Livox SDK 1 point packets.
//!
//! The Avia looks out through two wedge prisms turning in opposite directions (Risley
//! prisms). Each bends the beam by a fixed angle in the direction it faces, so the beam's
//! direction is the sum of two vectors turning at [`PRISM_HZ`]: a rosette of petals through
//! the centre. Its petal tips advance by a turn times `f1 / (f1 + f2)` from one to the next;
//! with `f1 / f2` near the golden ratio, the ratio farthest from every ratio of small integers,
//! each frame's petals fall between the last frame's and the field fills in over time as the
//! sensor's does. Six lasers in a vertical line 1.36 degrees apart (the Livox ROS driver's six
//! lines) fire in turn, 240,000 points a second, through the same prisms: six copies of a
//! circular rosette 70.4 degrees across, stacked into the 70.4 x 77.2 degree field (a model:
//! Livox publishes the field, not how its lasers sit). A packet
//! holds 96 points (0.4 ms), data type 2 (x, y, z in mm, reflectivity, tag), stamped with its
//! first point's time in ns since the sensor started (timestamp type 0); a frame is every
//! packet whose first point falls in its period, as the decoder cuts them.

use super::{unit, Packet, PacketSim, Timing, Truth};
use kiss_odom_sensors::livox::sdk1::{self, field};
use nalgebra::Vector3;

/// The data type written: Cartesian x, y, z in mm, reflectivity and tag.
const DATA_TYPE: u8 = 2;
/// Points a second (Livox SDK 1: the Horizon's, Tele-15's and Avia's).
const POINTS_PER_S: u64 = 240_000;
/// Points per packet of [`DATA_TYPE`].
pub const POINTS: usize = 96;
/// Time a packet spans, ns.
pub const PACKET_NS: u64 = POINTS as u64 * 1_000_000_000 / POINTS_PER_S;
/// The points' timing.
pub(super) const TIMING: Timing = Timing {
    points: POINTS,
    packet_ns: PACKET_NS,
    point_ns: 1e9 / POINTS_PER_S as f64,
};
/// The field of view, degrees: horizontal, vertical.
const FIELD_DEG: (f64, f64) = (70.4, 77.2);
/// Lasers, firing in turn.
const LASERS: usize = 6;
/// The rosette's radius, degrees: the horizontal field.
const ROSETTE_DEG: f64 = 0.5 * FIELD_DEG.0;
/// Vertical distance between neighbouring lasers, degrees: the line of lasers makes the
/// vertical field.
const LASER_STEP_DEG: f64 = (FIELD_DEG.1 - FIELD_DEG.0) / (LASERS - 1) as f64;
/// Turns a second of the two prisms (turning in opposite directions).
const PRISM_HZ: (f64, f64) = (124.17, 76.79);
/// Slot and lidar id of the packets (a sensor connected directly).
const SENDER: (u8, u8) = (0, 1);

/// Direction of the point fired at trajectory time `t` (s) by laser `laser`, sensor frame.
fn direction(t: f64, laser: usize) -> Vector3<f64> {
    use core::f64::consts::TAU;
    let (a, b) = (TAU * PRISM_HZ.0 * t, TAU * PRISM_HZ.1 * t);
    let offset = (laser as f64 - 0.5 * (LASERS - 1) as f64) * LASER_STEP_DEG;
    let azimuth = (0.5 * ROSETTE_DEG * (libm::cos(a) + libm::cos(b))).to_radians();
    let elevation = (0.5 * ROSETTE_DEG * (libm::sin(a) - libm::sin(b)) + offset).to_radians();
    unit(azimuth, elevation)
}

impl PacketSim<'_> {
    pub(super) fn avia_packet(&self, p: u64) -> (Packet, Vec<Truth>) {
        let len = sdk1::packet_len(DATA_TYPE).unwrap_or(field::DATA);
        let mut buf = vec![0u8; len];
        buf[field::VERSION] = sdk1::VERSION;
        (buf[field::SLOT], buf[field::LIDAR]) = SENDER;
        buf[field::DATA_TYPE] = DATA_TYPE;
        buf[field::TIMESTAMP].copy_from_slice(&self.timed_stamp_ns(p).to_le_bytes());
        self.livox_packet(p, buf, field::DATA, |t, n| direction(t, n % LASERS))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::packets::LIVOX_POINT_LEN;
    use kiss_odom_sensors::livox;

    #[test]
    fn the_timing_is_the_decoders_and_a_packet_the_sdk_1_layout() {
        assert_eq!(Some(TIMING.point_ns), livox::Model::Horizon.firing_ns());
        assert_eq!(sdk1::layout(DATA_TYPE), Some((LIVOX_POINT_LEN, POINTS)));
        assert_eq!(PACKET_NS, 400_000);
    }

    #[test]
    fn the_rosette_fills_the_field_and_does_not_repeat_from_frame_to_frame() {
        let (width, height) = FIELD_DEG;
        // One frame's directions, and the next frame's at the same instants within it.
        let frame = |k: f64| -> Vec<Vector3<f64>> {
            (0..24_000)
                .map(|n| direction(k * 0.1 + n as f64 * TIMING.point_ns * 1e-9, n % LASERS))
                .collect()
        };
        let (a, b) = (frame(0.0), frame(1.0));
        let angles = |d: &Vector3<f64>| {
            let elevation = libm::asin(d.z).to_degrees();
            (libm::atan2(d.y, d.x).to_degrees(), elevation)
        };
        let (h, v) = a
            .iter()
            .map(angles)
            .fold((0.0f64, 0.0f64), |(h, v), (x, y)| {
                (h.max(x.abs()), v.max(y.abs()))
            });
        println!("half field reached: {h:.2} x {v:.2} deg (field {width} x {height})");
        assert!(h <= 0.5 * width + 1e-9 && v <= 0.5 * height + 1e-9);
        assert!(h > 0.49 * width && v > 0.49 * height, "the whole field");
        // Every 5-degree cell well inside the field (the inner 80 % of its ellipse) is hit.
        let mut hit = std::collections::HashSet::new();
        for d in &a {
            let (x, y) = angles(d);
            hit.insert(((x / 5.0).floor() as i32, (y / 5.0).floor() as i32));
        }
        let inner = (-8..8)
            .flat_map(|i| (-8..8).map(move |j| (i, j)))
            .filter(|&(i, j)| {
                let (x, y) = (5.0 * (i as f64 + 0.5), 5.0 * (j as f64 + 0.5));
                (x / (0.5 * width)).powi(2) + (y / (0.5 * height)).powi(2) < 0.64
            });
        let missed: Vec<_> = inner.filter(|c| !hit.contains(c)).collect();
        assert!(missed.is_empty(), "cells missed: {missed:?}");
        crate::packets::tests::assert_not_retraced(&a, &b);
    }
}
