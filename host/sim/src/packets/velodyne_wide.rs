//! The Velodyne HDL-64E S2 and S3 and VLS-128 as the simulator fires them: banks of 32 lasers in
//! blocks of their own flag, the models' firing tables ([`velodyne::Model::firing_s`]) and a
//! unit calibration the simulator makes up and writes beside the capture (the ROS YAML the
//! decoder reads with `--calibration`).
//!
//! Each laser is cast along the azimuth the decoders compute from the packet: its firing
//! group's block azimuth plus the rotation to the next group's in proportion to its firing
//! time, rounded to 0.01 degree (the packet's last group: the packet's mean step), plus the
//! laser's offset, and from its beam origin (vertical and horizontal offsets); the exact point
//! is the one at the range the packet writes. The rotor turns a whole number of packets a
//! turn, starting 1.5 firing groups after azimuth 0, as the 16- and 32-laser Velodynes.

use super::{Firing, Packet, PacketSim, Truth};
use kiss_odom_sensors::velodyne::{self, wire::field, Blocks, Calibration, Laser, Layout, Model};
use nalgebra::Vector3;

/// The made-up calibration of a simulated `model`: elevations spread over the model's field
/// of view in whole thousandths of a degree, azimuth offsets of +-1.4 or +-4.2 degrees in
/// turn, beam origins a few centimetres off the axis.
pub fn calibration(model: Model) -> Calibration {
    let n = model.lasers();
    let (low, high) = match model {
        Model::Hdl64eS2 | Model::Hdl64eS3 => (-24.8, 2.0),
        _ => (-25.0, 15.0),
    };
    let mut lasers = kiss_odom_sensors::heapless::Vec::new();
    for i in 0..n {
        // Interleaved as the real units fire: every other laser from the top half.
        let rank = if i % 2 == 0 { i / 2 } else { n / 2 + i / 2 };
        let v = low + (high - low) * rank as f64 / (n - 1) as f64;
        let laser = Laser {
            vertical_deg: libm::round(v * 1000.0) / 1000.0,
            azimuth_offset_deg: [1.4, -1.4, 4.2, -4.2][i % 4],
            vertical_offset_m: 0.01 * (i % 3) as f64,
            horizontal_offset_m: if i % 2 == 0 { 0.026 } else { -0.026 },
            ..Laser::default()
        };
        let _ = lasers.push(laser);
    }
    Calibration {
        lasers,
        distance_resolution_m: model.distance_resolution_m(),
    }
}

/// The calibration as the ROS YAML Velodyne's drivers read (radians, metres; the azimuth
/// correction with the opposite sign).
pub fn yaml(c: &Calibration) -> String {
    let mut s = format!(
        "distance_resolution: {}\nnum_lasers: {}\nlasers:\n",
        c.distance_resolution_m,
        c.lasers.len()
    );
    for (i, l) in c.lasers.iter().enumerate() {
        s += &format!(
            "  - {{laser_id: {i}, rot_correction: {:e}, vert_correction: {:e}, \
             vert_offset_correction: {}, horiz_offset_correction: {}}}\n",
            -l.azimuth_offset_deg.to_radians(),
            l.vertical_deg.to_radians(),
            l.vertical_offset_m,
            l.horizontal_offset_m
        );
    }
    s
}

/// Azimuth units to radians as the decoder takes them (through f32).
fn azimuth_rad(az: u16) -> f64 {
    let deg2rad = (core::f64::consts::PI / 180.0) as f32;
    f64::from(0.01f32 * f32::from(az) * deg2rad)
}

impl PacketSim<'_> {
    /// Trajectory time of packet `p`'s first firing; its stamp is `lead` later, in whole
    /// microseconds. The stamps begin at the lead rounded up, so the first firing is not
    /// before the sequence starts (nor the sweep's time origin before the sensor's hour).
    pub(super) fn wide_start(&self, p: u64) -> f64 {
        let lead = self.model.stamp_lead_us();
        let us = libm::floor(p as f64 * self.model.packet_us(false)) + libm::ceil(lead);
        (us - lead) * 1e-6
    }

    pub(super) fn wide_packet(&self, p: u64) -> (Packet, Vec<Truth>) {
        let model = self.model;
        let l = Layout { model, dual: false };
        let (_, group_ticks) = model.ticks();
        let t0 = self.wide_start(p);
        let rate = self.sim.params().sensor.rate_hz;
        let group_deg = 360.0 / (self.per_sweep as f64 * l.groups() as f64);
        let rotor = |t: f64| 1.5 * group_deg + 360.0 * t * rate;
        let az: Vec<u16> = (0..l.groups())
            .map(|g| {
                let a = libm::round(rotor(t0 + model.firing_s(g, 0, 0)) * 100.0);
                (a as i64).rem_euclid(36000) as u16
            })
            .collect();
        let step = |a: u16, b: u16| (i32::from(b) - i32::from(a)).rem_euclid(36000) as u64;
        let mut buf = vec![0u8; field::LEN];
        let mut truth = Vec::new();
        for g in 0..l.groups() {
            // (turn, groups) of this group's rotation.
            let (turn, den) = match az.get(g + 1) {
                Some(&next) => (step(az[g], next), 1),
                None => (step(az[0], az[g]), (l.groups() - 1) as u64),
            };
            for b in 0..model.banks() {
                let Blocks::Single(k) = l.blocks(g, b) else {
                    continue;
                };
                let block = &mut buf[k * field::BLOCK_LEN..(k + 1) * field::BLOCK_LEN];
                block[field::FLAG].copy_from_slice(&velodyne::BANK_FLAGS[b].to_le_bytes());
                block[field::AZIMUTH].copy_from_slice(&az[g].to_le_bytes());
                for c in 0..field::CHANNELS {
                    let laser = &self.calib.lasers[32 * b + c];
                    let ticks = u64::from(model.firing_ticks(b, c));
                    let d = u64::from(group_ticks) * den;
                    let scaled = u64::from(az[g]) * d + turn * ticks;
                    let a = (((2 * scaled + d) / (2 * d)) % 36000) as u16;
                    let theta = azimuth_rad(a) + laser.azimuth_offset_deg.to_radians();
                    let (s, co) = (libm::sin(theta), libm::cos(theta));
                    let v = laser.vertical_deg.to_radians();
                    let h = laser.horizontal_offset_m;
                    let origin = Vector3::new(h * s, h * co, laser.vertical_offset_m);
                    let dir = Vector3::new(libm::cos(v) * co, -libm::cos(v) * s, libm::sin(v));
                    let offset = t0 + model.firing_s(g, b, c);
                    let firing = Firing {
                        offset,
                        origin,
                        dir,
                    };
                    let ray = [p, (k * field::CHANNELS + c) as u64];
                    let (echo, point) = self.cast(&firing, ray);
                    let (Some((range, intensity)), Some((_, _, surface))) = (echo, point) else {
                        continue;
                    };
                    let unit = self.calib.distance_resolution_m;
                    let raw = libm::round(range / unit);
                    if !(1.0..=f64::from(u16::MAX)).contains(&raw) {
                        continue;
                    }
                    let at = field::DATA.start + c * field::CHANNEL_LEN;
                    block[at..at + 2].copy_from_slice(&(raw as u16).to_le_bytes());
                    block[at + 2] = libm::roundf(intensity * 255.0) as u8;
                    let q = origin + dir * (raw * unit);
                    truth.push((
                        [q.x as f32, q.y as f32, q.z as f32, intensity],
                        offset,
                        surface,
                    ));
                }
            }
        }
        let start_us = libm::round(self.sim.params().start_time * 1e6) as i64;
        let stamp_us = libm::round((t0 * 1e6) + model.stamp_lead_us()) as i64;
        let stamp = (start_us + stamp_us).rem_euclid(i64::from(velodyne::wire::HOUR_US));
        buf[field::TIMESTAMP].copy_from_slice(&(stamp as u32).to_le_bytes());
        if let Some(product) = model.product() {
            buf[field::RETURN_MODE] = 0x37;
            buf[field::PRODUCT] = product;
        }
        let last = t0 + model.firing_s(l.groups() - 1, model.banks() - 1, field::CHANNELS - 1);
        (
            Packet {
                offset: last,
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
    fn generated_hdl64e_s2_s3_and_vls128_packets_decode_to_the_simulated_points() {
        for sensor in [
            PacketSensor::Hdl64e,
            PacketSensor::Hdl64eS2,
            PacketSensor::Vls128,
        ] {
            let sim = sim(sensor, 10.0, 0.0);
            let ps = PacketSim::new(&sim, sensor);
            let model = sensor.model();
            let mut dec = velodyne::Decoder::new(velodyne::Config {
                model: Some(model),
                calibration: Some(calibration(model)),
                cut_angle_deg: Some(0.0),
            })
            .unwrap();
            decodes_to_the_truth(&ps, &mut dec, &format!("{sensor:?}"));
        }
    }
}
