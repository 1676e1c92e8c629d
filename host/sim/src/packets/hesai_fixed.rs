//! The Hesai Pandar40P, Pandar64, PandarQT64, PandarXT16 and PandarXT32M as the simulator
//! fires them: each model's own packet layout ([`wire_fixed`]), firing times
//! ([`Model::point_offset_ns`]) and channel count, single return, 4 mm ranges, 10 Hz.
//!
//! Channel `c` of `n` looks at an elevation spread evenly over the model's vertical field
//! (nebula's `fov_mdeg`: 40P and 64 +15 to -25 degrees, QT64 +-52.1, XT32M +19.5 to -20.8; the
//! XT16 its nominal 15 to -15), with azimuth offsets of -1.5, -0.5, 0.5 and 1.5 degrees in turn
//! (none on the XT16); `simulate` writes them as the angle correction file beside the pcap
//! ([`PacketSensor::angle_file`]) for `run --calibration`. Every channel of a block is cast
//! along the block's azimuth as the packet reports it (0.01 degree) plus its offset, from the
//! pose at its own firing, as the decoders compute the point. Packets carry the UDP sequence
//! number where the model sends one by default (all but the 40P); the packet time is the
//! model's date and microseconds. A turn's last block is at azimuth 0 and the sweeps are cut
//! as the XT32's (`packets/xt32.rs`).

use super::xt32::CLOCK_ORIGIN_S;
use super::{Packet, PacketSensor, PacketSim, Truth};
use kiss_odom_sensors::hesai::wire_fixed::{self, Date, Format};
use kiss_odom_sensors::hesai::{Calibration, Firing, Model};

/// The rotor rate, Hz.
pub const RATE_HZ: f64 = 10.0;
/// Single return: the return-mode byte (the QT64 has no strongest mode: last).
fn mode_byte(model: Model) -> u8 {
    if model == Model::PandarQT64 {
        0x38
    } else {
        0x37
    }
}

/// The model a generated sensor is.
pub(super) fn model(sensor: PacketSensor) -> Model {
    match sensor {
        PacketSensor::Pandar40p => Model::Pandar40P,
        PacketSensor::Pandar64 => Model::Pandar64,
        PacketSensor::Qt64 => Model::PandarQT64,
        PacketSensor::Xt16 => Model::Xt16,
        _ => Model::Xt32m,
    }
}

fn format(sensor: PacketSensor) -> &'static Format {
    model(sensor)
        .fixed_format()
        .unwrap_or(&wire_fixed::PANDARXT32M)
}

/// Channel `c`'s elevation and azimuth offset, degrees.
pub(super) fn angle(sensor: PacketSensor, c: usize) -> [f64; 2] {
    let n = format(sensor).lasers;
    if sensor == PacketSensor::Xt16 {
        return [Calibration::nominal_xt16().elevation_deg[c], 0.0];
    }
    let (top, bottom) = match sensor {
        PacketSensor::Qt64 => (52.1, -52.1),
        PacketSensor::Xt32m => (19.5, -20.8),
        _ => (15.0, -25.0),
    };
    let e = top - (top - bottom) * c as f64 / (n - 1) as f64;
    [e, (c % 4) as f64 - 1.5]
}

/// The angle correction file of the generated unit.
pub(super) fn csv_text(sensor: PacketSensor) -> String {
    let mut s = String::from("Laser id,Elevation,Azimuth\n");
    for c in 0..format(sensor).lasers {
        let [e, a] = angle(sensor, c);
        s.push_str(&format!("{},{e},{a}\n", c + 1));
    }
    s
}

/// Time a packet spans, ns: its firings.
pub(super) fn packet_ns(sensor: PacketSensor) -> u64 {
    let m = model(sensor);
    (m.firing_ns(0) * m.blocks() as i64) as u64
}

const SINGLE: Firing = Firing {
    returns: 1,
    mode_flag: 0,
    operational_state: 0,
    azimuth_state: 0,
    near: false,
};

/// Trajectory time of packet `p`'s time stamp, ns: packet 0's earliest channel fires at 0.
fn stamp_ns(sensor: PacketSensor, p: u64) -> i64 {
    let first = model(sensor).firing_span_ns(0, &SINGLE).0;
    -first + (p * packet_ns(sensor)) as i64
}

/// Trajectory time of packet `p`'s last firing, s.
pub(super) fn last_offset(sensor: PacketSensor, p: u64) -> f64 {
    let m = model(sensor);
    let last = (0..m.blocks())
        .map(|b| m.firing_span_ns(b, &SINGLE).1)
        .max()
        .unwrap_or(0);
    (stamp_ns(sensor, p) + last) as f64 * 1e-9
}

impl PacketSim<'_> {
    pub(super) fn hesai_fixed_packet(&self, p: u64) -> (Packet, Vec<Truth>) {
        let sensor = self.sensor;
        let (m, f) = (model(sensor), format(sensor));
        let mut buf = vec![0u8; f.default_len()];
        match f.header {
            12 => {
                let v = f.version;
                buf[..12].copy_from_slice(&[
                    0xEE,
                    0xFF,
                    v.0,
                    v.1,
                    0,
                    0,
                    f.lasers as u8,
                    f.blocks as u8,
                    0,
                    4,
                    1,
                    1,
                ]);
            }
            8 => {
                buf[..8].copy_from_slice(&[0xEE, 0xFF, f.lasers as u8, f.blocks as u8, 0, 4, 0, 0])
            }
            _ => {}
        }
        let mut truth = Vec::new();
        let az_len = 2;
        for b in 0..f.blocks {
            let mut at = f.block_at(b);
            if f.block_start {
                buf[at..at + 2].copy_from_slice(&wire_fixed::BLOCK_START);
                at += 2;
            }
            let azimuth = self.hesai_azimuth(p * f.blocks as u64 + b as u64, f.blocks);
            buf[at..at + az_len].copy_from_slice(&azimuth.to_le_bytes());
            for c in 0..f.lasers {
                let u = at + az_len + c * f.unit_len;
                let t = stamp_ns(sensor, p) + m.point_offset_ns(b, c, &SINGLE);
                truth.extend(self.hesai_channel(
                    &mut buf[u..u + f.unit_len],
                    azimuth,
                    angle(sensor, c),
                    t as f64 * 1e-9,
                    [p, (b * f.lasers + c) as u64],
                ));
            }
        }
        let tail = f.tail_at();
        buf[tail + f.return_mode] = mode_byte(m);
        let rpm = libm::round(RATE_HZ * 60.0) as u16;
        buf[tail + f.motor..tail + f.motor + 2].copy_from_slice(&rpm.to_le_bytes());
        let start_us = libm::round(self.sim.params().start_time * 1e6) as i64;
        let unix_us = CLOCK_ORIGIN_S * 1_000_000 + start_us + stamp_ns(sensor, p) / 1000;
        let (mut date, us) = super::xt32::utc_fields(unix_us);
        if let Date::Civil(base) = f.date_kind {
            date[0] = (i64::from(date[0]) + 1900 - i64::from(base)) as u8;
        }
        buf[tail + f.date..tail + f.date + 6].copy_from_slice(&date);
        buf[tail + f.micros..tail + f.micros + 4].copy_from_slice(&us.to_le_bytes());
        if f.default_len() >= f.fixed_len() + 4 {
            let at = f.fixed_len();
            buf[at..at + 4].copy_from_slice(&(p as u32).to_le_bytes());
        }
        (
            Packet {
                offset: last_offset(sensor, p),
                payload: buf,
            },
            truth,
        )
    }
}
