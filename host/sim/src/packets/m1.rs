//! The Robosense RS-M1 (MEMS) as the simulator fires it: a raster of 126 lines over its 120 x
//! 25 degree field, written as MSOP packets whose every return carries its own pitch and yaw.
//!
//! Five lasers share one mirror, each sweeping its own 24-degree slice of the field (laser 0
//! the leftmost) line by line, top to bottom, back and forth (a model: Robosense publishes the
//! field, the lines and the packet layout, not the mirror's path). A 10 Hz frame is 630
//! packets of 25 blocks, a block one return of each laser (78,750 points, 125 a line), the
//! packets numbered from 1 in each frame, as the decoder cuts frames. A packet is stamped
//! with a UTC time in whole microseconds and its blocks [`BLOCK_US`] apart. Each return is
//! cast along the direction its packet writes (pitch and yaw in whole hundredths of a
//! degree) from the sensor's origin, and the exact point is the one at the range it writes
//! (5 mm), so a decoder gets it back to rounding.

use super::{Firing, Packet, PacketSim, Truth};
use kiss_odom_sensors::robosense::m1;
use nalgebra::Vector3;

/// The frame rate: the M1 runs at 10 Hz.
pub const RATE_HZ: f64 = 10.0;
/// Packets a frame (single return, rs_driver's `decoder_RSM1.hpp`).
pub const PACKETS_PER_FRAME: u64 = 630;
/// Time between two blocks of a packet, us.
const BLOCK_US: u8 = 6;
/// Lasers, each with its own slice of the field.
const LASERS: usize = 5;
/// The field, degrees: horizontal, vertical.
const FIELD_DEG: (f64, f64) = (120.0, 25.0);
/// Lines of the raster.
const LINES: usize = 126;
/// Returns of a laser in a frame, and in a line.
const PER_FRAME: usize = PACKETS_PER_FRAME as usize * m1::BLOCKS;
const PER_LINE: usize = PER_FRAME / LINES;
/// The header's bytes: sequence number, return mode, UTC time (rs_driver's `RSM1MsopHeader`).
const SEQ: usize = 4;
const RETURN_MODE: usize = 8;
const STAMP: usize = 10;
/// The first block, and a block's and a channel's bytes.
const BLOCKS_AT: usize = 32;
const BLOCK_LEN: usize = 2 + LASERS * CHANNEL_LEN;
const CHANNEL_LEN: usize = 9;
/// Return mode: strongest.
const STRONGEST: u8 = 0x04;

/// Pitch and yaw of laser `laser`'s `n`th return of a frame, hundredths of a degree (as the
/// packet writes them, before its offset of 32768).
fn angles(laser: usize, n: usize) -> (i32, i32) {
    let (line, along) = (n / PER_LINE, n % PER_LINE);
    // Back and forth: odd lines run right to left.
    let along = if line % 2 == 0 {
        along
    } else {
        PER_LINE - 1 - along
    };
    let slice = FIELD_DEG.0 / LASERS as f64;
    let left = 0.5 * FIELD_DEG.0 - laser as f64 * slice;
    let yaw = left - (along as f64 + 0.5) * slice / PER_LINE as f64;
    let pitch = 0.5 * FIELD_DEG.1 - (line as f64 + 0.5) * FIELD_DEG.1 / LINES as f64;
    (
        libm::round(pitch * 100.0) as i32,
        libm::round(yaw * 100.0) as i32,
    )
}

/// Trajectory time of packet `p`'s stamp: whole microseconds.
fn stamp_s(p: u64) -> f64 {
    libm::floor(p as f64 * 1e6 / (RATE_HZ * PACKETS_PER_FRAME as f64)) * 1e-6
}

/// Trajectory time of packet `p`'s last return.
pub(super) fn last_offset(p: u64) -> f64 {
    stamp_s(p) + f64::from(BLOCK_US) * (m1::BLOCKS - 1) as f64 * 1e-6
}

impl PacketSim<'_> {
    pub(super) fn m1_packet(&self, p: u64) -> (Packet, Vec<Truth>) {
        let t0 = stamp_s(p);
        let index = (p % PACKETS_PER_FRAME) as usize;
        let mut buf = vec![0u8; m1::LEN];
        buf[..4].copy_from_slice(&m1::ID);
        buf[SEQ..SEQ + 2].copy_from_slice(&(index as u16 + 1).to_be_bytes());
        buf[RETURN_MODE] = STRONGEST;
        let start_us = libm::round(self.sim.params().start_time * 1e6) as i64;
        let unix_us =
            super::xt32::CLOCK_ORIGIN_S * 1_000_000 + start_us + libm::round(t0 * 1e6) as i64;
        let (secs, us) = (unix_us.div_euclid(1_000_000), unix_us.rem_euclid(1_000_000));
        buf[STAMP..STAMP + 6].copy_from_slice(&(secs as u64).to_be_bytes()[2..]);
        buf[STAMP + 6..STAMP + 10].copy_from_slice(&(us as u32).to_be_bytes());
        let mut truth = Vec::new();
        for k in 0..m1::BLOCKS {
            let b = BLOCKS_AT + k * BLOCK_LEN;
            let time_us = BLOCK_US * k as u8;
            buf[b] = time_us;
            let offset = t0 + f64::from(time_us) * 1e-6;
            for laser in 0..LASERS {
                let (pitch, yaw) = angles(laser, index * m1::BLOCKS + k);
                let (pr, yr) = (
                    (f64::from(pitch) * 0.01).to_radians(),
                    (f64::from(yaw) * 0.01).to_radians(),
                );
                let dir = Vector3::new(
                    libm::cos(pr) * libm::cos(yr),
                    libm::cos(pr) * libm::sin(yr),
                    libm::sin(pr),
                );
                let firing = Firing {
                    offset,
                    origin: Vector3::zeros(),
                    dir,
                };
                let (echo, point) = self.cast(&firing, [p, (k * LASERS + laser) as u64]);
                let (Some((range, intensity)), Some((_, _, surface))) = (echo, point) else {
                    continue;
                };
                let raw = libm::round(range / m1::DISTANCE_RES_M);
                let d = raw * m1::DISTANCE_RES_M;
                if !(m1::RANGE_M.0..=m1::RANGE_M.1).contains(&d) || raw > f64::from(u16::MAX) {
                    continue;
                }
                let at = b + 2 + laser * CHANNEL_LEN;
                buf[at..at + 2].copy_from_slice(&(raw as u16).to_be_bytes());
                let offset_angle = |a: i32| ((a + 32768) as u16).to_be_bytes();
                buf[at + 2..at + 4].copy_from_slice(&offset_angle(pitch));
                buf[at + 4..at + 6].copy_from_slice(&offset_angle(yaw));
                buf[at + 6] = libm::roundf(intensity * 255.0) as u8;
                let q = dir * d;
                truth.push((
                    [q.x as f32, q.y as f32, q.z as f32, intensity],
                    offset,
                    surface,
                ));
            }
        }
        (
            Packet {
                offset: last_offset(p),
                payload: buf,
            },
            truth,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::packets::xt32::tests::{sim, Points};
    use crate::packets::PacketSensor;
    use kiss_odom_sensors::{Decode, Pushed};

    #[test]
    fn the_raster_covers_the_field_line_by_line() {
        let (mut pitch, mut yaw) = ((i32::MAX, i32::MIN), (i32::MAX, i32::MIN));
        for laser in 0..LASERS {
            for n in 0..PER_FRAME {
                let (p, y) = angles(laser, n);
                pitch = (pitch.0.min(p), pitch.1.max(p));
                yaw = (yaw.0.min(y), yaw.1.max(y));
            }
        }
        println!("pitch {pitch:?}, yaw {yaw:?} (0.01 degree)");
        assert!(pitch.0 >= -1250 && pitch.1 <= 1250 && pitch.1 - pitch.0 > 2400);
        assert!(yaw.0 >= -6000 && yaw.1 <= 6000 && yaw.1 - yaw.0 > 11_900);
        // A line runs one way, the next the other way back, one line lower.
        let (a, b) = (angles(2, PER_LINE - 1), angles(2, PER_LINE));
        assert_eq!(a.1, b.1);
        assert!(b.0 < a.0);
        assert_eq!(PER_FRAME % LINES, 0);
    }

    #[test]
    fn generated_m1_packets_decode_to_the_simulated_points() {
        let sim = sim(PacketSensor::M1, RATE_HZ, 0.0);
        let ps = PacketSim::new(&sim, PacketSensor::M1);
        assert_eq!(ps.packets_per_sweep(), PACKETS_PER_FRAME);
        let mut dec = m1::Decoder::new();
        let mut got = Points::default();
        let sweeps: Vec<_> = (0..2).map(|k| ps.sweep(k)).collect();
        for packet in sweeps.iter().flat_map(|s| &s.packets) {
            let mut r = dec.push(&packet.payload, &mut got);
            if r == Ok(Pushed::Again) {
                r = dec.push(&packet.payload, &mut got);
            }
            r.unwrap();
        }
        dec.finish(&mut got);
        let truth: Vec<_> = sweeps.iter().flat_map(|s| s.frame.points.clone()).collect();
        let stamps: Vec<_> = sweeps.iter().flat_map(|s| s.frame.stamps.clone()).collect();
        assert!(truth.len() > 10_000, "{} points", truth.len());
        assert_eq!(got.xyz.len(), truth.len());
        assert_eq!(got.packets, [PACKETS_PER_FRAME as u32; 2]);
        let origin_ns = super::super::xt32::CLOCK_ORIGIN_S * 1_000_000_000;
        let (mut worst, mut worst_ratio, mut worst_t, mut sweep) = (0f64, 0f64, 0f64, 0);
        for (i, (p, q)) in got.xyz.iter().zip(&truth).enumerate() {
            if i == sweeps[0].frame.points.len() {
                sweep = 1;
            }
            let d = (0..3)
                .map(|k| (p[k] - f64::from(q[k])).powi(2))
                .sum::<f64>()
                .sqrt();
            let r = (0..3).map(|k| p[k] * p[k]).sum::<f64>().sqrt();
            worst = worst.max(d);
            worst_ratio = worst_ratio.max(d / (r * f64::from(f32::EPSILON)).max(1e-9));
            let t = (got.starts[sweep] as i64 - origin_ns) as f64 * 1e-9 + got.times[i];
            worst_t = worst_t.max((t - stamps[i]).abs());
        }
        println!(
            "M1: {} points; worst |dxyz| {worst:.2e} m ({worst_ratio:.2} of the f32 truth's \
             resolution at its range, tolerance 1), worst |dt| {worst_t:.2e} s (tolerance \
             1e-9 s)",
            truth.len()
        );
        assert!(worst_ratio <= 1.0 && worst <= 1e-4);
        assert!(worst_t <= 1e-9);
    }
}
