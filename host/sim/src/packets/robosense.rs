//! The Robosense RS-Helios as the simulator fires it: 32 lasers on a rotor, MSOP packets of
//! twelve blocks (port 6699) and a DIFOP packet with the unit's angles (port 7788).
//!
//! Laser `i` looks [`vertical_deg`]`(i)` up and [`horizontal_deg`]`(i)` along the rotation from
//! its block's azimuth (angles in whole hundredths of a degree, as the DIFOP packet writes
//! them). A block fires every 55.56 us, its lasers 1.73 us apart (rs_driver's Helios timing);
//! the packet's UTC time stamps its first firing in whole microseconds. Each laser is cast from
//! the lens centre (34.98 mm off the axis, turning with the rotor) along the azimuth the
//! decoders interpolate from the packet's quantised block azimuths (the block's plus its share
//! of the rotation to the next block's; the last block the step before), so the exact point
//! lies on the decoded ray; it is the point at the range the packet writes (2.5 mm units).
//! The rotor turns a whole number of packets a turn, a turn starting 1.5 blocks after azimuth
//! 0, as the simulated Velodynes do: a cut at 0 degrees gives the simulator's sweeps.

use super::{Firing, Packet, PacketSim, Truth};
use kiss_odom_sensors::robosense::{wire, Model};
use nalgebra::Vector3;

/// The model simulated.
pub const MODEL: Model = Model::Helios;
/// Return-mode byte of the DIFOP packet: strongest (Helios).
const STRONGEST: u8 = 0x04;
/// Where the MSOP blocks begin, and their length.
const HEADER: usize = 42;
const BLOCK: usize = 100;

/// Laser `i`'s elevation, degrees: -55 to +15 in 31 steps, to 0.01 degree.
pub fn vertical_deg(i: usize) -> f64 {
    libm::round((-55.0 + 70.0 * i as f64 / 31.0) * 100.0) / 100.0
}

/// Laser `i`'s azimuth offset, degrees: +-0.5 in turn.
pub fn horizontal_deg(i: usize) -> f64 {
    if i % 2 == 0 {
        0.5
    } else {
        -0.5
    }
}

/// Time of a packet, us: its twelve blocks.
pub fn packet_us() -> f64 {
    MODEL.packet_us(false)
}

/// The DIFOP packet: its id, the rotation speed, strongest return, every laser's angles.
pub fn difop(rate_hz: f64) -> Vec<u8> {
    let mut b = vec![0u8; wire::LEN];
    b[..8].copy_from_slice(&wire::DIFOP_ID);
    let rpm = libm::round(rate_hz * 60.0) as u16;
    b[wire::DIFOP_RPM..wire::DIFOP_RPM + 2].copy_from_slice(&rpm.to_be_bytes());
    let at = MODEL.difop();
    b[at.return_mode] = STRONGEST;
    let entry = |b: &mut [u8], at: usize, deg: f64| {
        let v = libm::round(deg * 100.0) as i32;
        b[at] = u8::from(v < 0);
        b[at + 1..at + 3].copy_from_slice(&(v.unsigned_abs() as u16).to_be_bytes());
    };
    for i in 0..MODEL.lasers() {
        entry(&mut b, at.vertical + 3 * i, vertical_deg(i));
        if let Some(h) = at.horizontal {
            entry(&mut b, h + 3 * i, horizontal_deg(i));
        }
    }
    b
}

impl PacketSim<'_> {
    /// Trajectory time of packet `p`'s stamp: whole microseconds.
    fn robosense_stamp(&self, p: u64) -> f64 {
        libm::floor(p as f64 * packet_us()) * 1e-6
    }

    /// Trajectory time of packet `p`'s last firing.
    pub(super) fn robosense_last_offset(&self, p: u64) -> f64 {
        let blocks = MODEL.layout().blocks;
        self.robosense_stamp(p)
            + ((blocks - 1) as f64 * MODEL.block_us(false) + MODEL.firing_us(31, false)) * 1e-6
    }

    /// Rotor azimuth at trajectory time `t`, hundredths of a degree (unwrapped).
    fn robosense_rotor(&self, t: f64) -> f64 {
        let blocks = MODEL.layout().blocks as f64;
        let block = 36000.0 / (self.per_sweep as f64 * blocks);
        1.5 * block + 36000.0 * t * self.sim.params().sensor.rate_hz
    }

    pub(super) fn robosense_packet(&self, p: u64) -> (Packet, Vec<Truth>) {
        let l = MODEL.layout();
        let block_us = MODEL.block_us(false);
        let (rx, rz) = MODEL.lens_m();
        let unit = MODEL.distance_resolution_m();
        let (min, max) = MODEL.range_m();
        let t0 = self.robosense_stamp(p);
        let az: Vec<u16> = (0..l.blocks)
            .map(|k| {
                let a = libm::round(self.robosense_rotor(t0 + k as f64 * block_us * 1e-6));
                (a as i64).rem_euclid(36000) as u16
            })
            .collect();
        let mut buf = vec![0u8; wire::LEN];
        buf[..l.id.len()].copy_from_slice(l.id);
        let start_us = libm::round(self.sim.params().start_time * 1e6) as i64;
        let unix_us =
            super::xt32::CLOCK_ORIGIN_S * 1_000_000 + start_us + libm::round(t0 * 1e6) as i64;
        let (secs, us) = (unix_us.div_euclid(1_000_000), unix_us.rem_euclid(1_000_000));
        let (at, _) = l.stamp;
        buf[at..at + 6].copy_from_slice(&(secs as u64).to_be_bytes()[2..]);
        buf[at + 6..at + 10].copy_from_slice(&(us as u32).to_be_bytes());
        let mut truth = Vec::new();
        let mut gap = 0.0;
        for k in 0..l.blocks {
            let b = HEADER + k * BLOCK;
            buf[b..b + 2].copy_from_slice(l.block_id);
            buf[b + 2..b + 4].copy_from_slice(&az[k].to_be_bytes());
            if let Some(next) = az.get(k + 1) {
                gap = f64::from((i32::from(*next) - i32::from(az[k])).rem_euclid(36000));
            }
            for c in 0..l.channels {
                let fire = MODEL.firing_us(c, false);
                let offset = t0 + (k as f64 * block_us + fire) * 1e-6;
                // The decoders' azimuth, and the ray from the lens centre.
                let a = f64::from(az[k]) + gap * fire / block_us;
                let rotor = (a * 0.01).to_radians();
                let theta = rotor + horizontal_deg(c).to_radians();
                let v = vertical_deg(c).to_radians();
                let origin = Vector3::new(rx * libm::cos(rotor), -rx * libm::sin(rotor), rz);
                let dir = Vector3::new(
                    libm::cos(v) * libm::cos(theta),
                    -libm::cos(v) * libm::sin(theta),
                    libm::sin(v),
                );
                let firing = Firing {
                    offset,
                    origin,
                    dir,
                };
                let (echo, point) = self.cast(&firing, [p, (k * l.channels + c) as u64]);
                let (Some((range, intensity)), Some((_, _, surface))) = (echo, point) else {
                    continue;
                };
                let raw = libm::round(range / unit);
                let d = raw * unit;
                if !(min..=max).contains(&d) || raw > f64::from(u16::MAX) {
                    continue;
                }
                let at = b + 4 + 3 * c;
                buf[at..at + 2].copy_from_slice(&(raw as u16).to_be_bytes());
                buf[at + 2] = libm::roundf(intensity * 255.0) as u8;
                let q = origin + dir * d;
                truth.push((
                    [q.x as f32, q.y as f32, q.z as f32, intensity],
                    offset,
                    surface,
                ));
            }
        }
        buf[HEADER + l.blocks * BLOCK..HEADER + l.blocks * BLOCK + 4]
            .copy_from_slice(&(p as u32).to_be_bytes());
        (
            Packet {
                offset: self.robosense_last_offset(p),
                payload: buf,
            },
            truth,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::packets::xt32::tests::sim;
    use crate::packets::PacketSensor;
    use kiss_odom_sensors::robosense::{wire::Difop, Calibration, Config, Decoder};
    use kiss_odom_sensors::{Chunk, Decode, SweepSink, SweepStart, SweepStats};

    #[derive(Default)]
    struct Points {
        xyz: Vec<[f64; 3]>,
        times: Vec<f64>,
        starts: Vec<u64>,
        packets: Vec<u32>,
    }

    impl SweepSink for Points {
        fn begin_sweep(&mut self, s: &SweepStart) {
            self.starts.push(s.start_ns);
        }
        fn points(&mut self, c: Chunk<'_>) {
            self.xyz.extend_from_slice(c.xyz);
            self.times.extend_from_slice(c.times);
        }
        fn end_sweep(&mut self, s: &SweepStats) {
            self.packets.push(s.packets);
        }
    }

    #[test]
    fn generated_helios_packets_decode_to_the_simulated_points() {
        let sim = sim(PacketSensor::Helios, 10.0, 0.0);
        let ps = PacketSim::new(&sim, PacketSensor::Helios);
        let rate = sim.params().sensor.rate_hz;
        let difop = difop(rate);
        let calibration =
            Calibration::from_difop(MODEL, &Difop::new_checked(&difop).unwrap()).unwrap();
        assert_eq!(calibration.dual, Some(false));
        let mut dec = Decoder::new(Config {
            model: MODEL,
            calibration: Some(calibration),
            cut_angle_deg: Some(0.0),
        })
        .unwrap();
        let mut got = Points::default();
        let sweeps: Vec<_> = (0..2).map(|k| ps.sweep(k)).collect();
        for packet in sweeps.iter().flat_map(|s| &s.packets) {
            let mut r = dec.push(&packet.payload, &mut got);
            if r == Ok(kiss_odom_sensors::Pushed::Again) {
                r = dec.push(&packet.payload, &mut got);
            }
            r.unwrap();
        }
        dec.finish(&mut got);
        let truth: Vec<_> = sweeps.iter().flat_map(|s| s.frame.points.clone()).collect();
        let stamps: Vec<_> = sweeps.iter().flat_map(|s| s.frame.stamps.clone()).collect();
        assert_eq!(got.xyz.len(), truth.len());
        assert_eq!(got.packets, [ps.packets_per_sweep() as u32; 2]);
        let (mut worst, mut worst_ratio, mut worst_t) = (0f64, 0f64, 0f64);
        let origin_ns = super::super::xt32::CLOCK_ORIGIN_S * 1_000_000_000;
        let mut sweep = 0;
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
            // The truth is f32: half a unit in the last place of the largest coordinate.
            worst_ratio = worst_ratio.max(d / (r * f64::from(f32::EPSILON)).max(1e-9));
            let t = (got.starts[sweep] as i64 - origin_ns) as f64 * 1e-9 + got.times[i];
            worst_t = worst_t.max((t - stamps[i]).abs());
        }
        println!(
            "Helios: {} points; worst |dxyz| {worst:.2e} m ({worst_ratio:.2} of the f32 \
             truth's resolution at its range), worst |dt| {worst_t:.2e} s (tolerance 1e-9 s)",
            truth.len()
        );
        assert!(worst_ratio <= 1.0 && worst <= 1e-4);
        assert!(worst_t <= 1e-9);
    }
}
