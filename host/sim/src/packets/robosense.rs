//! The Robosense spinning models as the simulator fires them (RS-LiDAR-16, RS-LiDAR-32,
//! RS-Bpearl, RS-Helios, RS-Helios-16P, RS-Ruby, RS-Airy): MSOP packets of the model's blocks
//! (port 6699) and a DIFOP packet with the unit's angles (port 7788; the Airy's mounted
//! normally).
//!
//! Laser `i` looks [`vertical_deg`] up and [`horizontal_deg`] along the rotation from its
//! block's azimuth (angles in whole hundredths of a degree, as the DIFOP packet writes them).
//! Firings (the Airy's two blocks each) and channels fire at the model's times (rs_driver's,
//! `Model::firing_us`); the
//! packet stamps its first firing in whole microseconds (a UTC count, or the RS-16, RS-32 and
//! Bpearl's calendar date). Each laser is cast from the lens centre (off the axis, turning
//! with the rotor) along the azimuth the decoders interpolate from the packet's quantised
//! block azimuths (the block's plus its share of the rotation to the next block's; the last
//! block the step before), so the exact point lies on the decoded ray; it is the point at the
//! range the packet writes. The rotor turns a whole number of packets a turn, a turn starting
//! 1.5 blocks after azimuth 0, as the simulated Velodynes do: a cut at 0 degrees gives the
//! simulator's sweeps.

use super::{Firing, Packet, PacketSim, Truth};
use kiss_odom_sensors::robosense::{
    wire, AiryInstall, Model, Stamp, AIRY_96, AIRY_CHANNEL_MODE, AIRY_INSTALL, AIRY_RETURN_MODE,
};
use nalgebra::Vector3;

/// How the simulated Airy is mounted (its DIFOP packet says so).
const INSTALL: AiryInstall = AiryInstall::Normal;

/// The return-mode byte of the DIFOP packet for single strongest return.
fn strongest(model: Model) -> u8 {
    match model {
        Model::Helios | Model::Helios16p => 0x04,
        Model::Ruby => 0x02,
        _ => 0x01,
    }
}

/// Laser `i`'s elevation, degrees: spread evenly over the model's field of view, to 0.01
/// degree (the RS-16's lasers 0-7 below the horizon, as its DIFOP packet has them).
pub fn vertical_deg(model: Model, i: usize) -> f64 {
    let (low, high) = match model {
        Model::Rs16 | Model::Helios16p => (-15.0, 15.0),
        Model::Rs32 | Model::Ruby => (-25.0, 15.0),
        Model::Bpearl => (0.0, 89.0),
        Model::Helios => (-55.0, 15.0),
        // 90 degrees (the Airy's field), tilted to see the ground.
        Model::Airy => (-45.0, 45.0),
    };
    let n = (model.lasers() - 1) as f64;
    libm::round((low + (high - low) * i as f64 / n) * 100.0) / 100.0
}

/// Laser `i`'s azimuth offset, degrees: +-0.5 in turn (0 for the RS-16, whose DIFOP packet
/// has no horizontal angles).
pub fn horizontal_deg(model: Model, i: usize) -> f64 {
    match model {
        Model::Rs16 => 0.0,
        _ if i % 2 == 0 => 0.5,
        _ => -0.5,
    }
}

/// Time of a packet, us: its blocks.
pub fn packet_us(model: Model) -> f64 {
    model.packet_us(false)
}

/// The DIFOP packet: its id, the rotation speed, strongest return, every laser's angles.
pub fn difop(model: Model, rate_hz: f64) -> Vec<u8> {
    let mut b = vec![0u8; wire::LEN];
    b[..8].copy_from_slice(&wire::DIFOP_ID);
    let rpm = libm::round(rate_hz * 60.0) as u16;
    b[wire::DIFOP_RPM..wire::DIFOP_RPM + 2].copy_from_slice(&rpm.to_be_bytes());
    let at = model.difop();
    b[at.return_mode] = strongest(model);
    if model == Model::Airy {
        b[AIRY_INSTALL] = INSTALL.byte();
    }
    let entry = |b: &mut [u8], at: usize, deg: f64| {
        let v = libm::round(deg * 100.0) as i32;
        b[at] = u8::from(v < 0);
        b[at + 1..at + 3].copy_from_slice(&(v.unsigned_abs() as u16).to_be_bytes());
    };
    for i in 0..model.lasers() {
        let v = vertical_deg(model, i);
        match at.horizontal {
            Some(h) => {
                entry(&mut b, at.vertical + 3 * i, v);
                entry(&mut b, h + 3 * i, horizontal_deg(model, i));
            }
            // RS-16: |elevation| in 0.0001 degree, 3 bytes (the sign from the laser's index).
            None => {
                let u = libm::round(v.abs() * 1e4) as u32;
                b[at.vertical + 3 * i..at.vertical + 3 * i + 3]
                    .copy_from_slice(&u.to_be_bytes()[1..]);
            }
        }
    }
    b
}

/// The 10 stamp bytes of `unix_us` in the model's format.
fn stamp(model: Model, unix_us: i64) -> [u8; 10] {
    let (secs, us) = (unix_us.div_euclid(1_000_000), unix_us.rem_euclid(1_000_000));
    let mut t = [0u8; 10];
    match model.layout().stamp.1 {
        Stamp::Utc => {
            t[..6].copy_from_slice(&(secs as u64).to_be_bytes()[2..]);
            t[6..].copy_from_slice(&(us as u32).to_be_bytes());
        }
        Stamp::Ymd => {
            let (days, s) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
            let (y, m, d) = civil_from_days(days);
            t[..6].copy_from_slice(&[
                (y - 2000) as u8,
                m,
                d,
                (s / 3600) as u8,
                (s / 60 % 60) as u8,
                (s % 60) as u8,
            ]);
            t[6..8].copy_from_slice(&((us / 1000) as u16).to_be_bytes());
            t[8..].copy_from_slice(&((us % 1000) as u16).to_be_bytes());
        }
    }
    t
}

/// The calendar date of a day count since 1970-01-01 (Hinnant's `civil_from_days`).
fn civil_from_days(z: i64) -> (i64, u8, u8) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u8;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u8;
    (yoe + era * 400 + i64::from(m <= 2), m, d)
}

/// The latest firing of a block after its first, us.
fn last_firing_us(model: Model) -> f64 {
    (0..model.halves() * model.layout().channels)
        .map(|c| model.firing_us(c, false, INSTALL))
        .fold(0.0, f64::max)
}

/// Firings a packet holds.
fn firings(model: Model) -> usize {
    model.layout().blocks / model.blocks_per_firing(false)
}

impl PacketSim<'_> {
    /// The Robosense model simulated.
    fn robosense_model(&self) -> Model {
        self.sensor.robosense().unwrap_or(Model::Helios)
    }

    /// Trajectory time of packet `p`'s stamp: whole microseconds.
    fn robosense_stamp(&self, p: u64) -> f64 {
        libm::floor(p as f64 * packet_us(self.robosense_model())) * 1e-6
    }

    /// Trajectory time of packet `p`'s last firing.
    pub(super) fn robosense_last_offset(&self, p: u64) -> f64 {
        let model = self.robosense_model();
        let f = firings(model);
        self.robosense_stamp(p)
            + ((f - 1) as f64 * model.block_us(false) + last_firing_us(model)) * 1e-6
    }

    /// Rotor azimuth at trajectory time `t`, hundredths of a degree (unwrapped).
    fn robosense_rotor(&self, t: f64) -> f64 {
        let blocks = firings(self.robosense_model()) as f64;
        let block = 36000.0 / (self.per_sweep as f64 * blocks);
        1.5 * block + 36000.0 * t * self.sim.params().sensor.rate_hz
    }

    pub(super) fn robosense_packet(&self, p: u64) -> (Packet, Vec<Truth>) {
        let model = self.robosense_model();
        let l = model.layout();
        let block_us = model.block_us(false);
        let (rx, rz) = model.lens_m();
        let unit = model.distance_resolution_m();
        let (min, max) = model.range_m();
        let t0 = self.robosense_stamp(p);
        let per = model.blocks_per_firing(false);
        let az: Vec<u16> = (0..firings(model))
            .map(|f| {
                let a = libm::round(self.robosense_rotor(t0 + f as f64 * block_us * 1e-6));
                (a as i64).rem_euclid(36000) as u16
            })
            .collect();
        let mut buf = vec![0u8; wire::LEN];
        buf[..l.id.len()].copy_from_slice(l.id);
        if model == Model::Airy {
            buf[AIRY_CHANNEL_MODE] = AIRY_96;
            buf[AIRY_RETURN_MODE] = 0x01;
        }
        let start_us = libm::round(self.sim.params().start_time * 1e6) as i64;
        let unix_us =
            super::xt32::CLOCK_ORIGIN_S * 1_000_000 + start_us + libm::round(t0 * 1e6) as i64;
        let (at, _) = l.stamp;
        buf[at..at + 10].copy_from_slice(&stamp(model, unix_us));
        let mut truth = Vec::new();
        let mut gap = 0.0;
        for k in 0..l.blocks {
            let f = k / per;
            let b = l.header + k * l.block_len();
            buf[b..b + l.block_id.len()].copy_from_slice(l.block_id);
            buf[b + l.azimuth_at..b + l.azimuth_at + 2].copy_from_slice(&az[f].to_be_bytes());
            if let Some(next) = az.get(f + 1) {
                gap = f64::from((i32::from(*next) - i32::from(az[f])).rem_euclid(36000));
            }
            for c in 0..l.channels {
                let ch = model.channel(k, c);
                let fire = model.firing_us(ch, false, INSTALL);
                let laser = model.laser(ch);
                let offset = t0 + (f as f64 * block_us + fire) * 1e-6;
                // The decoders' azimuth, and the ray from the lens centre.
                let a = f64::from(az[f]) + gap * fire / block_us;
                let rotor = (a * 0.01).to_radians();
                let theta = rotor + horizontal_deg(model, laser).to_radians();
                let v = vertical_deg(model, laser).to_radians();
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
                let at = b + l.azimuth_at + 2 + 3 * c;
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
        // The Helios's tail: the packet's sequence number.
        let tail = l.header + l.blocks * l.block_len();
        if matches!(model, Model::Helios | Model::Helios16p) {
            buf[tail..tail + 4].copy_from_slice(&(p as u32).to_be_bytes());
        }
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
    use crate::packets::xt32::tests::{decodes_to_the_truth, sim};
    use crate::packets::PacketSensor;
    use kiss_odom_sensors::robosense::{wire::Difop, Calibration, Config, Decoder};

    #[test]
    fn generated_robosense_packets_decode_to_the_simulated_points() {
        for sensor in PacketSensor::ROBOSENSE {
            decodes_to_the_simulated_points(sensor);
        }
    }

    fn decodes_to_the_simulated_points(sensor: PacketSensor) {
        let model = sensor.robosense().unwrap();
        let sim = sim(sensor, 10.0, 0.0);
        let ps = PacketSim::new(&sim, sensor);
        let rate = sim.params().sensor.rate_hz;
        let difop = difop(model, rate);
        let calibration =
            Calibration::from_difop(model, &Difop::new_checked(&difop).unwrap()).unwrap();
        // The Airy says its return mode in each MSOP packet instead.
        assert_eq!(calibration.dual, (model != Model::Airy).then_some(false));
        let mut dec = Decoder::new(Config {
            model,
            calibration: Some(calibration),
            cut_angle_deg: Some(0.0),
        })
        .unwrap();
        decodes_to_the_truth(&ps, &mut dec, &format!("{sensor:?}"));
    }
}
