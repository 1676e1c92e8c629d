//! The Hesai PandarXT-32 as the simulator fires it: 32 channels in one vertical line on a
//! rotor, written as UDP protocol 6.1 packets.
//!
//! Channel `c` looks `15 - c` degrees up, with no azimuth offset (the manual's nominal angles,
//! [`hesai::Calibration::nominal`]). A packet holds eight firings 50 us apart, a block of the
//! 32 channels each; channel `c` fires 0.368 + 1.512 c us into its firing and the packet time
//! stamps the last firing ([`hesai::point_offset_ns`]). Every channel of a block is cast along
//! the block's azimuth as the packet reports it (0.01 degree), from the pose at its own firing:
//! the decoders (Hesai's SDK, nebula, ours) give a block's points one azimuth, so the exact
//! point lies on the decoded ray. Ranges are in 4 mm units, strongest return; the packet time
//! is a UTC date and microseconds ([`CLOCK_ORIGIN_S`] plus the sequence time); each packet
//! carries its UDP sequence number (flag bit 0): 1080 bytes. At 5, 10 or 20 Hz a turn is 500,
//! 250 or 125 packets and the blocks step by 0.09, 0.18 or 0.36 degrees (the manual's
//! horizontal resolutions).
//!
//! A turn's last block fires at azimuth 0. A decoder without a cut angle ends a sweep with the
//! packet whose last azimuth wraps past the one where the sweep before ended (the first sweep:
//! past its first packet's), so its first sweep is a turn and the packet before it, and every
//! later one a turn, (0, 360] degrees; a cut at 0 degrees gives the same sweeps.
//!
//! The header, the block azimuths, the channel cast and the tail's time fields are written
//! here for the 128-channel sensors too (`packets/hesai128.rs`): their protocols share them.

use super::{in_units, unit, Firing, Packet, PacketSim, Truth};
use kiss_odom_sensors::hesai::{self, wire, wire::field, wire128};
use nalgebra::Vector3;

/// The rates the motor runs at, Hz.
pub const RATES_HZ: [f64; 3] = [5.0, 10.0, 20.0];
/// Time a packet spans, ns: its eight firings.
pub const PACKET_NS: u64 = hesai::FIRING_NS as u64 * field::BLOCKS as u64;
/// The sensor's UTC clock at sequence time 0, s since the Unix epoch: 2024-01-01 00:00:00.
pub const CLOCK_ORIGIN_S: i64 = 1_704_067_200;
/// Trajectory time of packet 0's time stamp, ns: its first channel fires at 0.
const FIRST_STAMP_NS: i64 = -hesai::point_offset_ns(0, 0, 1);
/// The return-mode byte of strongest return.
const STRONGEST: u8 = 0x37;
/// Where the XT32's tail would begin were it protocol 3.2's or 1.4's: the return mode, motor
/// speed and packet time lie at the same places from there ([`wire128::field`]).
const TAIL: usize = field::RETURN_MODE - wire128::field::RETURN_MODE;
const _: () = assert!(
    TAIL + wire128::field::MOTOR_SPEED.start == field::MOTOR_SPEED.start
        && TAIL + wire128::field::DATE_TIME.start == field::DATE_TIME.start
        && TAIL + wire128::field::MICROSECONDS.start == field::MICROSECONDS.start
);

/// Trajectory time of packet `p`'s time stamp, ns.
fn stamp_ns(p: u64) -> i64 {
    FIRST_STAMP_NS + (p * PACKET_NS) as i64
}

/// Trajectory time of packet `p`'s block `block`, channel `channel`.
fn offset(p: u64, block: usize, channel: usize) -> f64 {
    (stamp_ns(p) + hesai::point_offset_ns(block, channel, 1)) as f64 * 1e-9
}

/// Trajectory time of packet `p`'s last firing.
pub(super) fn last_offset(p: u64) -> f64 {
    offset(p, field::BLOCKS - 1, field::CHANNELS - 1)
}

/// The date of `days` since 1970-01-01: year, month, day (H. Hinnant's `civil_from_days`).
fn civil_from_days(days: i64) -> (i64, u8, u8) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    (
        yoe + era * 400 + i64::from(month <= 2),
        month as u8,
        day as u8,
    )
}

/// The packet time's fields at `unix_us` (microseconds since the Unix epoch): year - 1900,
/// month, day, hour, minute, second, and the microseconds within the second.
pub(super) fn utc_fields(unix_us: i64) -> ([u8; 6], u32) {
    let (s, us) = (unix_us.div_euclid(1_000_000), unix_us.rem_euclid(1_000_000));
    let (days, t) = (s.div_euclid(86_400), s.rem_euclid(86_400));
    let (year, month, day) = civil_from_days(days);
    let date = [
        (year - 1900) as u8,
        month,
        day,
        (t / 3600) as u8,
        (t / 60 % 60) as u8,
        (t % 60) as u8,
    ];
    (date, us as u32)
}

/// Writes the header all three Hesai protocols share: `lasers` channels a block, `blocks`
/// blocks a packet, 4 mm units, single return, the header `flags`.
pub(super) fn write_header(
    buf: &mut [u8],
    version: (u8, u8),
    (lasers, blocks): (usize, usize),
    flags: u8,
) {
    buf[field::START].copy_from_slice(&wire::START);
    (buf[field::VERSION_MAJOR], buf[field::VERSION_MINOR]) = version;
    buf[field::LASERS] = lasers as u8;
    buf[field::BLOCK_COUNT] = blocks as u8;
    buf[field::DISTANCE_UNIT] = libm::round(hesai::DISTANCE_UNIT_M * 1000.0) as u8;
    buf[field::RETURNS] = 1;
    buf[field::FLAGS] = flags;
}

impl PacketSim<'_> {
    /// Azimuth of block `g` (counted from packet 0's first) of a Hesai sending `blocks` blocks
    /// a packet, 0.01 degree: a turn's last block at 0.
    pub(super) fn hesai_azimuth(&self, g: u64, blocks: usize) -> u16 {
        let turn = self.per_sweep * blocks as u64;
        let from_last = (g + turn - (blocks as u64 - 1)) % turn;
        (from_last * u64::from(wire::AZIMUTH_UNITS) / turn) as u16
    }

    /// Casts a channel of `[elevation, azimuth offset]` (degrees) of a block at `azimuth`
    /// (0.01 degree), fired at trajectory time `offset`, along the ray the decoders compute
    /// from them; writes its distance and reflectivity into `unit_bytes` (none: left 0) and
    /// gives the exact point of a return.
    pub(super) fn hesai_channel(
        &self,
        unit_bytes: &mut [u8],
        azimuth: u16,
        [elevation_deg, azimuth_deg]: [f64; 2],
        offset: f64,
        ray: [u64; 2],
    ) -> Option<Truth> {
        // Clockwise seen from above.
        let theta = -(f64::from(azimuth) * 0.01 + azimuth_deg).to_radians();
        let firing = Firing {
            offset,
            origin: Vector3::zeros(),
            dir: unit(theta, elevation_deg.to_radians()),
        };
        let (echo, point) = self.cast(&firing, ray);
        let (raw, reflectivity) = in_units(echo, hesai::DISTANCE_UNIT_M)?;
        unit_bytes[field::DISTANCE].copy_from_slice(&raw.to_le_bytes());
        unit_bytes[field::REFLECTIVITY] = reflectivity;
        point
    }

    /// Writes the tail fields the three protocols share into the tail at `tail`: strongest
    /// return, the motor speed, and the packet time of trajectory time `stamp_ns` (whole
    /// microseconds) on the sensor's UTC clock.
    pub(super) fn hesai_tail(&self, buf: &mut [u8], tail: usize, stamp_ns: i64) {
        use wire128::field::{DATE_TIME, MICROSECONDS, MOTOR_SPEED, RETURN_MODE};
        let at = |r: core::ops::Range<usize>| tail + r.start..tail + r.end;
        buf[tail + RETURN_MODE] = STRONGEST;
        let rpm = libm::round(self.sim.params().sensor.rate_hz * 60.0) as u16;
        buf[at(MOTOR_SPEED)].copy_from_slice(&rpm.to_le_bytes());
        let start_us = libm::round(self.sim.params().start_time * 1e6) as i64;
        let unix_us = CLOCK_ORIGIN_S * 1_000_000 + start_us + stamp_ns / 1000;
        let (date, us) = utc_fields(unix_us);
        buf[at(DATE_TIME)].copy_from_slice(&date);
        buf[at(MICROSECONDS)].copy_from_slice(&us.to_le_bytes());
    }

    pub(super) fn xt32_packet(&self, p: u64) -> (Packet, Vec<Truth>) {
        let mut buf = vec![0u8; field::LEN_WITH_SEQUENCE];
        let shape = (field::CHANNELS, field::BLOCKS);
        write_header(&mut buf, wire::VERSION, shape, wire::FLAG_UDP_SEQUENCE);
        let elevation_deg = hesai::Calibration::nominal().elevation_deg;
        let mut truth = Vec::new();
        for b in 0..field::BLOCKS {
            let at = field::BODY + b * field::BLOCK_LEN;
            let azimuth = self.hesai_azimuth(p * field::BLOCKS as u64 + b as u64, field::BLOCKS);
            buf[at + field::AZIMUTH.start..at + field::AZIMUTH.end]
                .copy_from_slice(&azimuth.to_le_bytes());
            for (ch, e) in elevation_deg.iter().enumerate().take(field::CHANNELS) {
                let at = at + field::DATA.start + ch * field::CHANNEL_LEN;
                truth.extend(self.hesai_channel(
                    &mut buf[at..at + field::CHANNEL_LEN],
                    azimuth,
                    [*e, 0.0],
                    offset(p, b, ch),
                    [p, (b * field::CHANNELS + ch) as u64],
                ));
            }
        }
        self.hesai_tail(&mut buf, TAIL, stamp_ns(p));
        buf[field::UDP_SEQUENCE].copy_from_slice(&(p as u32).to_le_bytes());
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
pub(super) mod tests {
    use super::*;
    use crate::packets::PacketSensor;
    use crate::profile::Profile;
    use crate::simulation::{SimParams, Simulation};
    use kiss_odom_sensors::{Chunk, Decode, SweepSink, SweepStart, SweepStats};

    /// Points and packets of each sweep a decoder hands on.
    #[derive(Default)]
    struct Sweeps(Vec<(usize, u32)>);

    impl SweepSink for Sweeps {
        fn begin_sweep(&mut self, _: &SweepStart) {
            self.0.push((0, 0));
        }
        fn points(&mut self, c: Chunk<'_>) {
            if let Some(s) = self.0.last_mut() {
                s.0 += c.xyz.len();
            }
        }
        fn end_sweep(&mut self, stats: &SweepStats) {
            if let Some(s) = self.0.last_mut() {
                s.1 = stats.packets;
            }
        }
    }

    /// Every point, time, sweep start and packet count a decoder hands on.
    #[derive(Default)]
    pub(in crate::packets) struct Points {
        pub(in crate::packets) xyz: Vec<[f64; 3]>,
        pub(in crate::packets) times: Vec<f64>,
        pub(in crate::packets) starts: Vec<u64>,
        pub(in crate::packets) packets: Vec<u32>,
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

    /// Sweeps 0 and 1 of `ps` pushed through `dec`: the decoded points, checked against the
    /// simulated ones one by one (as many, in order, `ps`'s packets a sweep, each within the
    /// f32 truth's rounding at its range and 1 ns); returns how many.
    pub(in crate::packets) fn decodes_to_the_truth<D: kiss_odom_sensors::Decode>(
        ps: &PacketSim<'_>,
        dec: &mut D,
        what: &str,
    ) -> usize {
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
        assert!(!truth.is_empty(), "{what}: no points");
        assert_eq!(got.xyz.len(), truth.len(), "{what}");
        assert_eq!(got.packets, [ps.packets_per_sweep() as u32; 2], "{what}");
        let origin_ns = ps.sensor.clock_origin_s() * 1_000_000_000;
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
            // The truth is f32: half a unit in the last place of the largest coordinate.
            worst_ratio = worst_ratio.max(d / (r * f64::from(f32::EPSILON)).max(1e-9));
            let t = (got.starts[sweep] as i64 - origin_ns) as f64 * 1e-9 + got.times[i];
            worst_t = worst_t.max((t - stamps[i]).abs());
        }
        println!(
            "{what}: {} points; worst |dxyz| {worst:.2e} m ({worst_ratio:.2} of the f32 truth's \
             resolution at its range, tolerance 1), worst |dt| {worst_t:.2e} s (tolerance 1e-9 s)",
            truth.len()
        );
        assert!(worst_ratio <= 1.0 && worst <= 1e-4, "{what}");
        assert!(worst_t <= 1e-9, "{what}");
        truth.len()
    }

    /// A simulation of `sensor` at `rate_hz`, its sequence time starting at `start_time`.
    pub(in crate::packets) fn sim(
        sensor: PacketSensor,
        rate_hz: f64,
        start_time: f64,
    ) -> Simulation {
        let mut p = SimParams::new(Profile::Urban, 2, 4);
        p.sensor.rate_hz = sensor.rate_hz(rate_hz).unwrap();
        p.start_time = start_time;
        Simulation::new(p).unwrap()
    }

    /// Sweeps 0 to 2 of `ps`, after asserting that the decoder of `config` (with and without
    /// a cut at 0 degrees) hands on the same sweeps: the same points and packets in each.
    pub(in crate::packets) fn decoded_as_simulated(
        ps: &PacketSim<'_>,
        config: hesai::Config,
    ) -> Vec<crate::packets::Sweep> {
        let sweeps: Vec<_> = (0..3).map(|k| ps.sweep(k)).collect();
        let expected: Vec<_> = sweeps
            .iter()
            .map(|s| (s.frame.points.len(), s.packets.len() as u32))
            .collect();
        for cut in [None, Some(0.0)] {
            let config = hesai::Config {
                cut_angle_deg: cut,
                ..config
            };
            let mut dec = hesai::Decoder::new(config).unwrap();
            let mut got = Sweeps::default();
            for packet in sweeps.iter().flat_map(|s| &s.packets) {
                dec.push(&packet.payload, &mut got).unwrap();
            }
            dec.finish(&mut got);
            println!(
                "{:?}, cut {cut:?}: (points, packets) {:?}",
                config.model, got.0
            );
            assert_eq!(got.0, expected, "{:?}, cut {cut:?}", config.model);
        }
        sweeps
    }

    #[test]
    fn the_decoders_sweeps_with_or_without_a_cut_angle_are_the_simulators() {
        for rate in RATES_HZ {
            let sim = sim(PacketSensor::Xt32, rate, 0.0);
            let ps = PacketSim::new(&sim, PacketSensor::Xt32);
            let sweeps = decoded_as_simulated(&ps, hesai::Config::default());
            let per_turn = ps.packets_per_sweep();
            assert_eq!(per_turn, (2500.0 / rate) as u64);
            assert_eq!(sweeps[0].packets.len() as u64, per_turn + 1);
            // A turn's last block at azimuth 0, the blocks 360 degrees / blocks a turn apart.
            let last = &sweeps[1].packets[per_turn as usize - 1].payload;
            let block = |k: usize| {
                let at = field::BODY + k * field::BLOCK_LEN;
                u16::from_le_bytes([last[at], last[at + 1]])
            };
            assert_eq!(block(7), 0);
            assert_eq!(
                u64::from(block(0)) * per_turn * 8,
                36000 * (per_turn * 8 - 7)
            );
        }
    }

    #[test]
    fn packet_times_are_the_sequence_time_on_a_utc_clock_from_2024() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(CLOCK_ORIGIN_S / 86_400), (2024, 1, 1));
        assert_eq!(civil_from_days(19_782), (2024, 2, 29));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        assert_eq!(civil_from_days(-1), (1969, 12, 31));
        // Across midnight into a day, a leap day and a year: the second packet is past it.
        for day in [0.0f64, 1.0, 59.0, 366.0] {
            let start_time = (day * 86_400.0 - 0.0004).max(0.0);
            let sim = sim(PacketSensor::Xt32, 10.0, start_time);
            let ps = PacketSim::new(&sim, PacketSensor::Xt32);
            for packet in ps.sweep(0).packets.iter().take(3) {
                let p = wire::Packet::new_checked(&packet.payload).unwrap();
                let index = p.udp_sequence().unwrap();
                let us = CLOCK_ORIGIN_S * 1_000_000 + libm::round(start_time * 1e6) as i64;
                let ns = us * 1000 + stamp_ns(u64::from(index));
                assert_eq!(p.unix_ns(), Some(ns as u64), "start {start_time}");
                assert_eq!(p.motor_rpm(), 600);
            }
        }
    }
}
