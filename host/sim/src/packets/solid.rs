//! The Robosense models whose returns carry their directions, as the simulator fires them:
//! the MEMS RS-M1 (a raster of 126 lines over its 120 x 25 degree field) and the solid-state
//! E1R (192 x 144 returns over 120 x 90 degrees), written as MSOP packets.
//!
//! RS-M1: five lasers share one mirror, each sweeping its own 24-degree slice of the field
//! (laser 0 the leftmost) line by line, top to bottom, back and forth; a 10 Hz frame is 630
//! packets of 25 blocks, a block one return of each laser (78,750 points, 125 a line). E1R:
//! row by row from the top, left to right, 0.625 degrees apart; a 10 Hz frame is 288 packets
//! of 96 blocks of one return (27,648 points). Both are models: Robosense publishes the
//! fields, the resolutions and the packet layouts, not the order of the returns. The packets
//! are numbered from 1 in each frame, as the decoder cuts frames, stamped with a UTC time in
//! whole microseconds, their blocks a few microseconds apart. Each return is cast along the
//! direction its packet writes (M1: pitch and yaw in whole hundredths of a degree; E1R: a
//! vector in 32768ths) from the sensor's origin, and the exact point is the one the decoder
//! computes from the range it writes (5 mm), so a decoder gets it back to rounding.

use super::{Firing, Packet, PacketSim, Truth};
use kiss_odom_sensors::robosense::solid::{
    self, Model, BLOCKS_AT, RETURN_MODE, SEQ, STAMP, VECTOR_BASE,
};
use nalgebra::Vector3;

/// The frame rate: both run at 10 Hz.
pub const RATE_HZ: f64 = 10.0;
/// Return mode: strongest.
const STRONGEST: u8 = 0x04;

/// Packets a frame (single return, rs_driver's `decoder_RSM1.hpp`, `decoder_RSE1.hpp`).
pub const fn packets_per_frame(model: Model) -> u64 {
    match model {
        Model::M1 => 630,
        Model::E1r => 288,
    }
}

/// Time between two blocks of a packet, us.
const fn block_us(model: Model) -> u16 {
    match model {
        Model::M1 => 6,
        Model::E1r => 3,
    }
}

/// The RS-M1's raster: lasers, lines, the field (degrees) and returns a line.
mod m1 {
    use super::Model;
    pub const LASERS: usize = Model::M1.channels();
    pub const LINES: usize = 126;
    pub const FIELD_DEG: (f64, f64) = (120.0, 25.0);
    pub const PER_FRAME: usize = 630 * Model::M1.blocks();
    pub const PER_LINE: usize = PER_FRAME / LINES;
}

/// The E1R's grid: columns, rows, the field (degrees).
mod e1r {
    pub const COLUMNS: usize = 192;
    pub const ROWS: usize = 144;
    pub const FIELD_DEG: (f64, f64) = (120.0, 90.0);
}

/// Pitch and yaw of the RS-M1 laser `laser`'s `n`th return of a frame, hundredths of a
/// degree (as the packet writes them, before its offset of 32768).
fn m1_angles(laser: usize, n: usize) -> (i32, i32) {
    use m1::{FIELD_DEG, LASERS, LINES, PER_LINE};
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

/// The E1R's `n`th return of a frame: its direction as the packet writes it (32768ths).
fn e1r_vector(n: usize) -> [i16; 3] {
    use e1r::{COLUMNS, FIELD_DEG, ROWS};
    let (row, column) = (n / COLUMNS % ROWS, n % COLUMNS);
    let step = FIELD_DEG.0 / COLUMNS as f64;
    let yaw = (0.5 * FIELD_DEG.0 - (column as f64 + 0.5) * step).to_radians();
    let pitch = (0.5 * FIELD_DEG.1 - (row as f64 + 0.5) * step).to_radians();
    let unit = [
        libm::cos(pitch) * libm::cos(yaw),
        libm::cos(pitch) * libm::sin(yaw),
        libm::sin(pitch),
    ];
    unit.map(|u| libm::round(u * VECTOR_BASE).clamp(-32768.0, 32767.0) as i16)
}

/// Trajectory time of packet `p`'s stamp: whole microseconds.
fn stamp_s(model: Model, p: u64) -> f64 {
    let per_s = RATE_HZ * packets_per_frame(model) as f64;
    libm::floor(p as f64 * 1e6 / per_s) * 1e-6
}

/// Trajectory time of packet `p`'s last return.
pub(super) fn last_offset(model: Model, p: u64) -> f64 {
    let last = f64::from(block_us(model)) * (model.blocks() - 1) as f64;
    stamp_s(model, p) + last * 1e-6
}

impl PacketSim<'_> {
    pub(super) fn solid_packet(&self, model: Model, p: u64) -> (Packet, Vec<Truth>) {
        let t0 = stamp_s(model, p);
        let index = (p % packets_per_frame(model)) as usize;
        let mut buf = vec![0u8; model.packet_len()];
        buf[..4].copy_from_slice(&solid::ID);
        buf[SEQ..SEQ + 2].copy_from_slice(&(index as u16 + 1).to_be_bytes());
        buf[RETURN_MODE] = STRONGEST;
        let start_us = libm::round(self.sim.params().start_time * 1e6) as i64;
        let unix_us =
            super::xt32::CLOCK_ORIGIN_S * 1_000_000 + start_us + libm::round(t0 * 1e6) as i64;
        let (secs, us) = (unix_us.div_euclid(1_000_000), unix_us.rem_euclid(1_000_000));
        buf[STAMP..STAMP + 6].copy_from_slice(&(secs as u64).to_be_bytes()[2..]);
        buf[STAMP + 6..STAMP + 10].copy_from_slice(&(us as u32).to_be_bytes());
        let (min, max) = model.range_m();
        let mut truth = Vec::new();
        for k in 0..model.blocks() {
            let b = BLOCKS_AT + k * model.block_len();
            let time_us = block_us(model) * k as u16;
            match model {
                Model::M1 => buf[b] = time_us as u8,
                Model::E1r => buf[b..b + 2].copy_from_slice(&time_us.to_be_bytes()),
            }
            let offset = t0 + f64::from(time_us) * 1e-6;
            for c in 0..model.channels() {
                let n = index * model.blocks() + k;
                let at = b + 2 + c * model.channel_len();
                // The point of one distance unit along the direction written: the decoder's
                // point is the raw distance times it.
                let per_unit = match model {
                    Model::M1 => {
                        let (pitch, yaw) = m1_angles(c, n);
                        let raw_angle = |a: i32| (a + 32768) as u16;
                        buf[at + 2..at + 4].copy_from_slice(&raw_angle(pitch).to_be_bytes());
                        buf[at + 4..at + 6].copy_from_slice(&raw_angle(yaw).to_be_bytes());
                        Vector3::from(solid::m1_point(1, raw_angle(pitch), raw_angle(yaw)))
                    }
                    Model::E1r => {
                        let v = e1r_vector(n);
                        for (i, x) in v.iter().enumerate() {
                            let xi = at + 2 + 2 * i;
                            buf[xi..xi + 2].copy_from_slice(&x.to_be_bytes());
                        }
                        Vector3::from(v.map(f64::from)) * (solid::DISTANCE_RES_M / VECTOR_BASE)
                    }
                };
                let step = per_unit.norm();
                let firing = Firing {
                    offset,
                    origin: Vector3::zeros(),
                    dir: per_unit / step,
                };
                let (echo, point) = self.cast(&firing, [p, (k * model.channels() + c) as u64]);
                let (Some((range, intensity)), Some((_, _, surface))) = (echo, point) else {
                    continue;
                };
                let raw = libm::round(range / step);
                let d = raw * solid::DISTANCE_RES_M;
                if !(min..=max).contains(&d) || raw < 1.0 || raw > f64::from(u16::MAX) {
                    continue;
                }
                buf[at..at + 2].copy_from_slice(&(raw as u16).to_be_bytes());
                buf[at + model.intensity_at()] = libm::roundf(intensity * 255.0) as u8;
                let q = per_unit * raw;
                truth.push((
                    [q.x as f32, q.y as f32, q.z as f32, intensity],
                    offset,
                    surface,
                ));
            }
        }
        (
            Packet {
                offset: last_offset(model, p),
                payload: buf,
            },
            truth,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::packets::xt32::tests::{decodes_to_the_truth, sim};
    use crate::packets::PacketSensor;

    #[test]
    fn the_m1_raster_covers_the_field_line_by_line() {
        use m1::{LASERS, LINES, PER_FRAME, PER_LINE};
        let (mut pitch, mut yaw) = ((i32::MAX, i32::MIN), (i32::MAX, i32::MIN));
        for laser in 0..LASERS {
            for n in 0..PER_FRAME {
                let (p, y) = m1_angles(laser, n);
                pitch = (pitch.0.min(p), pitch.1.max(p));
                yaw = (yaw.0.min(y), yaw.1.max(y));
            }
        }
        println!("pitch {pitch:?}, yaw {yaw:?} (0.01 degree)");
        assert!(pitch.0 >= -1250 && pitch.1 <= 1250 && pitch.1 - pitch.0 > 2400);
        assert!(yaw.0 >= -6000 && yaw.1 <= 6000 && yaw.1 - yaw.0 > 11_900);
        // A line runs one way, the next the other way back, one line lower.
        let (a, b) = (m1_angles(2, PER_LINE - 1), m1_angles(2, PER_LINE));
        assert_eq!(a.1, b.1);
        assert!(b.0 < a.0);
        assert_eq!(PER_FRAME % LINES, 0);
    }

    #[test]
    fn the_e1r_grid_covers_its_field_once_a_frame() {
        use e1r::{COLUMNS, ROWS};
        assert_eq!(COLUMNS * ROWS, 288 * Model::E1r.blocks());
        let angles = |v: [i16; 3]| {
            let [x, y, z] = v.map(f64::from);
            let yaw = libm::atan2(y, x).to_degrees();
            (yaw, libm::atan2(z, libm::hypot(x, y)).to_degrees())
        };
        let (first, last) = (
            angles(e1r_vector(0)),
            angles(e1r_vector(COLUMNS * ROWS - 1)),
        );
        println!("first return yaw/pitch {first:?}, last {last:?} (degrees)");
        assert!((first.0 - 59.6875).abs() < 0.01 && (first.1 - 44.6875).abs() < 0.01);
        assert!((last.0 + 59.6875).abs() < 0.01 && (last.1 + 44.6875).abs() < 0.01);
        // Every written vector is a unit one to its 32768ths.
        for n in (0..COLUMNS * ROWS).step_by(97) {
            let len = e1r_vector(n)
                .map(f64::from)
                .iter()
                .map(|v| v * v)
                .sum::<f64>();
            assert!((len.sqrt() / VECTOR_BASE - 1.0).abs() < 1e-4, "{n}");
        }
    }

    #[test]
    fn generated_m1_and_e1r_packets_decode_to_the_simulated_points() {
        for (sensor, model) in [
            (PacketSensor::M1, Model::M1),
            (PacketSensor::E1r, Model::E1r),
        ] {
            let sim = sim(sensor, RATE_HZ, 0.0);
            let ps = PacketSim::new(&sim, sensor);
            assert_eq!(ps.packets_per_sweep(), packets_per_frame(model));
            let mut dec = solid::Decoder::new(model);
            let n = decodes_to_the_truth(&ps, &mut dec, model.name());
            assert!(n > 10_000, "{model:?}: {n} points");
        }
    }
}
