//! The Hesai PandarAT128 as the simulator fires it: 128 channels turned by a three-faced
//! mirror, UDP protocol 4.3 packets (`wire_fixed::PANDARAT128`, 1086 bytes), single strongest
//! return, 4 mm ranges, ten frames a second; and the unit's angle correction file
//! ([`correction_file`], version 1.5, written beside the pcap as `packets.dat`).
//!
//! The motor turns at 1200 degrees a second (200 rpm), each face of the mirror is a frame of
//! 120 degrees of it and 0.1 s (frame `k` uses face `k mod 3`, whose frame begins at motor angle
//! `20 + 120 i` degrees). The unit fires only while its beams are in its field, from 15 to 75
//! degrees of motor into the frame (azimuths about 30 to 150 degrees): 1200 firings 41.666 us
//! apart, two a packet, so a frame is 600 packets over 50 ms and then 50 ms of none. A packet
//! is stamped in whole microseconds; its two firings begin 9.249 us plus one or two firing
//! periods before that, and channel `c` fires its table's time later (`timing.rs`,
//! [`Model::point_offset_ns`]). Each block's azimuth is the motor's at its firing's start, to
//! 1/25,600 degree (the hundredths and the fine byte).
//!
//! Every channel of a block is cast along the direction the correction gives for that motor
//! angle, frame and channel, computed here from the file's integers by the formula of
//! nebula's `AngleCorrectorCorrectionBased` (the adjustments interpolated, not rounded, as
//! Hesai's SDK does), from the pose at the channel's own firing. The decoders' frame: x forward
//! (azimuth 90 degrees), y left, z up. The body and tail CRCs are CRC-32/MPEG-2, as a recorded
//! QT128's (no AT128 capture confirms it; the decoder does not check them).

use super::xt32::CLOCK_ORIGIN_S;
use super::{in_units, Firing, Packet, PacketSim, Truth};
use kiss_odom_sensors::hesai::wire128::crc32_mpeg2;
use kiss_odom_sensors::hesai::wire_fixed::{AT128_SEQUENCE, PANDARAT128};
use kiss_odom_sensors::hesai::{self, Firing as Shot, Model, ADJUST_STEPS, ADJUST_STEP_UNITS};
use nalgebra::Vector3;
use sha2::{Digest, Sha256};

/// Frames a second.
pub const RATE_HZ: f64 = 10.0;
/// Packets a frame: 1200 firings, two a packet.
pub const PACKETS_PER_FRAME: u64 = 600;
/// Time from one frame's first firing to the next frame's, ns.
const FRAME_NS: i64 = 100_000_000;
/// Motor units (1/25,600 degree) a second: 1200 degrees.
const MOTOR_UNITS_PER_S: i64 = 1200 * 25_600;
/// The motor speed the tail reports, rpm.
const MOTOR_RPM: u16 = 200;
/// Where the first frame's face begins, units: 20 degrees; the others 120 degrees on.
const FIRST_START: i64 = 20 * 25_600;
/// The first firing of a frame, motor units into it: 15 degrees.
const FIRST_INTO: i64 = 15 * 25_600;
/// The file's resolution: every angle in it is stored in halves.
const RESOLUTION: i64 = 2;
/// Units in a turn.
const TURN: i64 = 360 * 25_600;

const SINGLE: Shot = Shot {
    returns: 1,
    mode_flag: 0,
    operational_state: 0,
    azimuth_state: 0,
    near: false,
};

/// The generated unit's correction, as the file stores it (before the resolution).
struct Tables {
    start: [i64; 3],
    azimuth: [i64; 128],
    elevation: [i64; 128],
    azimuth_adjust: Vec<[i8; ADJUST_STEPS]>,
    elevation_adjust: Vec<[i8; ADJUST_STEPS]>,
}

/// Channel `c`'s tables: azimuths alternating -2.4 and 0.65 degrees and elevations from 12.9 to
/// -12.5 degrees (as the correction nebula ships), adjustments of up to 0.8 and 0.3 degrees
/// varying with the motor angle and the channel.
fn tables() -> Tables {
    let stored = |deg: f64| libm::round(deg * 25_600.0 / RESOLUTION as f64) as i64;
    let adjust = |amplitude: f64, phase: f64| {
        (0..128)
            .map(|c| {
                let mut row = [0i8; ADJUST_STEPS];
                for (i, v) in row.iter_mut().enumerate() {
                    let x = 3.0 * i as f64 * core::f64::consts::TAU / ADJUST_STEPS as f64;
                    *v = libm::round(amplitude * libm::sin(x + phase + c as f64 * 0.1)) as i8;
                }
                row
            })
            .collect()
    };
    Tables {
        start: [0, 1, 2].map(|i| (FIRST_START + i * 120 * 25_600) / RESOLUTION),
        azimuth: core::array::from_fn(|c| stored(if c % 2 == 0 { -2.4 } else { 0.65 })),
        elevation: core::array::from_fn(|c| stored(12.9 - 25.4 * c as f64 / 127.0)),
        azimuth_adjust: adjust(40.0, 0.0),
        elevation_adjust: adjust(15.0, 1.0),
    }
}

/// The generated unit's angle correction file (`hesai_at128` in kiss-odom-io reads it).
pub(super) fn correction_file() -> Vec<u8> {
    let t = tables();
    let mut b = vec![
        0xEE,
        0xFF,
        1,
        5,
        128,
        3,
        3,
        1,
        2,
        4,
        0,
        0,
        0,
        0,
        0,
        RESOLUTION as u8,
    ];
    for i in 0..3 {
        b.extend((t.start[i] as u32).to_le_bytes());
    }
    for i in 0..3 {
        b.extend((t.start[(i + 1) % 3] as u32).to_le_bytes());
    }
    for v in t.azimuth.iter().chain(&t.elevation) {
        b.extend((*v as i32).to_le_bytes());
    }
    for row in t.azimuth_adjust.iter().chain(&t.elevation_adjust) {
        b.extend(row.iter().map(|v| *v as u8));
    }
    let sha = Sha256::digest(&b);
    b.extend(sha);
    b
}

/// Channel `c`'s (azimuth, elevation) in degrees at motor angle `motor` (units) in face
/// `face`, from the file's integers (the module doc's formula).
fn direction_deg(t: &Tables, motor: i64, face: usize, c: usize) -> (f64, f64) {
    let into = (motor - t.start[face] * RESOLUTION).rem_euclid(TURN);
    let i = (motor / i64::from(ADJUST_STEP_UNITS)) as usize;
    let k = (motor % i64::from(ADJUST_STEP_UNITS)) as f64 / f64::from(ADJUST_STEP_UNITS);
    let adjust = |row: &[i8; ADJUST_STEPS]| {
        let (a, b) = (row[i % ADJUST_STEPS], row[(i + 1) % ADJUST_STEPS]);
        ((1.0 - k) * f64::from(a) + k * f64::from(b)) * RESOLUTION as f64 * 0.01
    };
    let az =
        (2 * into - t.azimuth[c] * RESOLUTION) as f64 / 25_600.0 + adjust(&t.azimuth_adjust[c]);
    let el = (t.elevation[c] * RESOLUTION) as f64 / 25_600.0 + adjust(&t.elevation_adjust[c]);
    (az, el)
}

/// Trajectory time of packet `p`'s stamp, ns, whole microseconds: frame `p / 600`, its
/// firings `2 (p mod 600)` and the next, 9.249 us after the second ends.
fn stamp_ns(p: u64) -> i64 {
    let (k, i) = (
        (p / PACKETS_PER_FRAME) as i64,
        (p % PACKETS_PER_FRAME) as i64,
    );
    let last_start = k * FRAME_NS + (2 * i + 1) * Model::At128.firing_ns(0);
    let ns = last_start + Model::At128.firing_ns(0) + 9_249;
    (ns + 500).div_euclid(1000) * 1000
}

/// Trajectory time of packet `p`'s block `b`, channel `c`, ns.
fn fire_ns(p: u64, b: usize, c: usize) -> i64 {
    stamp_ns(p) + Model::At128.point_offset_ns(b, c, &SINGLE)
}

/// Trajectory time of packet `p`'s last firing, s.
pub(super) fn last_offset(p: u64) -> f64 {
    let last = (0..128).map(|c| fire_ns(p, 1, c)).max().unwrap_or(0);
    last as f64 * 1e-9
}

/// The motor angle at trajectory time `ns` (units, below a turn): 15 degrees into frame 0's
/// face at 0.
fn motor_units(ns: i64) -> i64 {
    let turned = (ns as i128 * MOTOR_UNITS_PER_S as i128).div_euclid(1_000_000_000) as i64;
    (FIRST_START + FIRST_INTO + turned).rem_euclid(TURN)
}

impl PacketSim<'_> {
    pub(super) fn at128_packet(&self, p: u64) -> (Packet, Vec<Truth>) {
        let f = &PANDARAT128;
        let t = tables();
        let face = ((p / PACKETS_PER_FRAME) % 3) as usize;
        let mut buf = vec![0u8; f.default_len()];
        // Header: EE FF 4 3, 128 lasers, 2 blocks, single return, 4 mm, flags: sequence number.
        buf[..12].copy_from_slice(&[0xEE, 0xFF, 4, 3, 0, 0, 128, 2, 0, 4, 1, 1]);
        let mut truth = Vec::new();
        for b in 0..f.blocks {
            let at = f.block_at(b);
            // The motor at the firing's start (its earliest channel).
            let motor = motor_units(stamp_ns(p) + Model::At128.firing_span_ns(b, &SINGLE).0);
            buf[at..at + 2].copy_from_slice(&((motor >> 8) as u16).to_le_bytes());
            buf[at + 2] = (motor & 0xFF) as u8;
            for c in 0..f.lasers {
                let (az, el) = direction_deg(&t, motor, face, c);
                let (az, el) = (az.to_radians(), el.to_radians());
                let firing = Firing {
                    offset: fire_ns(p, b, c) as f64 * 1e-9,
                    origin: Vector3::zeros(),
                    dir: Vector3::new(
                        libm::cos(el) * libm::sin(az),
                        libm::cos(el) * libm::cos(az),
                        libm::sin(el),
                    ),
                };
                let (echo, point) = self.cast(&firing, [p, (b * 128 + c) as u64]);
                let Some((raw, reflectivity)) = in_units(echo, hesai::DISTANCE_UNIT_M) else {
                    continue;
                };
                let u = at + 3 + c * f.unit_len;
                buf[u..u + 2].copy_from_slice(&raw.to_le_bytes());
                buf[u + 2] = reflectivity;
                truth.extend(point);
            }
        }
        let body_end = f.block_at(f.blocks);
        let crc = crc32_mpeg2(&buf[12..body_end]);
        buf[body_end..body_end + 4].copy_from_slice(&crc.to_le_bytes());
        let tail = f.tail_at();
        buf[tail + f.motor..tail + f.motor + 2].copy_from_slice(&MOTOR_RPM.to_le_bytes());
        let start_us = libm::round(self.sim.params().start_time * 1e6) as i64;
        let unix_us = CLOCK_ORIGIN_S * 1_000_000 + start_us + stamp_ns(p) / 1000;
        let (s, us) = (unix_us.div_euclid(1_000_000), unix_us.rem_euclid(1_000_000));
        buf[tail + f.micros..tail + f.micros + 4].copy_from_slice(&(us as u32).to_le_bytes());
        buf[tail + f.return_mode] = 0x37;
        buf[tail + f.return_mode + 1] = 0x42;
        // A zero byte, then the seconds since the Unix epoch, 5 bytes big-endian.
        buf[tail + f.date + 1..tail + f.date + 6].copy_from_slice(&(s as u64).to_be_bytes()[3..]);
        let seq = tail + AT128_SEQUENCE;
        buf[seq..seq + 4].copy_from_slice(&(p as u32).to_le_bytes());
        let crc = crc32_mpeg2(&buf[tail..seq + 4]);
        buf[seq + 4..seq + 8].copy_from_slice(&crc.to_le_bytes());
        (
            Packet {
                offset: last_offset(p),
                payload: buf,
            },
            truth,
        )
    }
}
