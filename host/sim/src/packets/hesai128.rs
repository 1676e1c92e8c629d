//! The Hesai PandarQT128 (UDP protocol 3.2) and OT128 (protocol 1.4) as the simulator fires
//! them: 128 channels on a rotor, two firings a packet, strongest return, 4 mm ranges, 10 Hz.
//!
//! Channel `c` looks along its row of the angle correction file: the QT128's is a real unit's
//! ([`QT128_ANGLES`], elevations -52.6 to 52.6 degrees, azimuth offsets up to 10 degrees),
//! the OT128's one made for it ([`OT128_ANGLES`], +15 to -25 degrees, finest around the
//! horizon, offsets near -3, -1, 1 and 3 degrees); `simulate` writes it beside the pcap
//! ([`PacketSensor::angle_file`]) for `run --calibration`. Every channel of a block is cast
//! along the block's azimuth as the packet reports it (0.01 degree) plus its offset, at its
//! elevation, from the pose at its own firing ([`Model::point_offset_ns`]), as the decoders
//! compute the point.
//!
//! - QT128: firings 111.11 us apart, 900 a turn (0.4 degrees, 450 packets); the packet time
//!   stamps the packet's start and the first firing begins 9 us later. Firings alternate
//!   between two loops, the first firing of every packet in loop 1 (mode flag 1): channels 1
//!   to 32 are silent in loop 1 and 33 to 64 in loop 2 (distance 0, as the sensor writes them).
//!   Flags 0x1D, as the sensor sends by default: UDP sequence, functional safety, signature
//!   and a confidence byte a channel (1,127 bytes).
//! - OT128: standard operational state, firings 55.556 us apart, 1800 a turn (0.2 degrees,
//!   900 packets); the packet time stamps the last firing. The blocks' azimuth states are 0
//!   and 1, in which every channel fires (8 of them at the firing's start). Flags 0x07: UDP
//!   sequence, IMU and functional safety (861 bytes).
//!
//! Packets are spread evenly over the turn, stamped to the microsecond; the body, functional
//! safety and tail CRCs are the sensors' (CRC-32/MPEG-2); the signature and the IMU sample
//! are zero. A turn's last block is at azimuth 0 and the sweeps are cut as the XT32's
//! (`packets/xt32.rs`).

use super::xt32::write_header;
use super::{Packet, PacketSensor, PacketSim, Truth};
use kiss_odom_sensors::hesai::{wire128, wire128::field, Firing, Model};

/// The rotor rate, Hz.
pub const RATE_HZ: f64 = 10.0;

/// A 128-channel sensor: its protocol, packet layout, firing states and angles.
struct Spec {
    model: Model,
    version: (u8, u8),
    flags: u8,
    /// The channels' elevation and azimuth offset, degrees, channel 1 first.
    angles: &'static [[f64; 2]; wire128::LASERS],
}

const QT128: Spec = Spec {
    model: Model::Qt128,
    version: wire128::VERSION_QT,
    flags: wire128::flag::SEQUENCE
        | wire128::flag::SAFETY
        | wire128::flag::SIGNATURE
        | wire128::flag::CONFIDENCE,
    angles: &QT128_ANGLES,
};

const OT128: Spec = Spec {
    model: Model::Ot128,
    version: wire128::VERSION_128,
    flags: wire128::flag::SEQUENCE | wire128::flag::IMU | wire128::flag::SAFETY,
    angles: &OT128_ANGLES,
};

/// The functional safety part of a sensor without faults (version 1 and the state byte a
/// recorded QT128 sends), before its CRC.
const SAFETY: [u8; field::SAFETY_LEN - 4] = [1, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0];

impl Spec {
    fn of(sensor: PacketSensor) -> &'static Self {
        match sensor {
            PacketSensor::Ot128 => &OT128,
            _ => &QT128,
        }
    }
    /// Block `block`'s firing state: the QT128's first firing in loop 1, the OT128 in standard
    /// state with the blocks in azimuth states 0 and 1.
    fn firing(&self, block: usize) -> Firing {
        match self.model {
            Model::Qt128 => Firing {
                returns: 1,
                mode_flag: 1,
                ..Firing::default()
            },
            _ => Firing {
                returns: 1,
                operational_state: 2,
                azimuth_state: block as u8,
                ..Firing::default()
            },
        }
    }
    /// Where the packet's parts lie.
    fn layout(&self) -> wire128::Layout {
        wire128::Layout::of(self.version, self.flags)
    }
    /// Time from packet time to block `block`, channel `channel`'s firing, ns.
    fn channel_ns(&self, block: usize, channel: usize) -> i64 {
        self.model
            .point_offset_ns(block, channel, &self.firing(block))
    }
    /// Trajectory time of packet 0's time stamp, ns: whole microseconds, its first firing
    /// at or just after 0.
    fn first_stamp_ns(&self) -> i64 {
        let (start, _) = self.model.firing_span_ns(0, &self.firing(0));
        -start.div_euclid(1000) * 1000
    }
}

/// Time a packet spans, ns: its two firings.
pub(super) fn packet_ns(sensor: PacketSensor) -> u64 {
    let spec = Spec::of(sensor);
    (spec.model.firing_ns(spec.firing(0).operational_state) * wire128::BLOCKS as i64) as u64
}

/// The sensor's angle correction file: `Laser id,Elevation,Azimuth`, a row per channel from
/// 1, each angle written so that it reads back exactly.
pub(super) fn csv_text(sensor: PacketSensor) -> String {
    let mut s = String::from("Laser id,Elevation,Azimuth\n");
    for (c, [e, a]) in Spec::of(sensor).angles.iter().enumerate() {
        s.push_str(&format!("{},{e},{a}\n", c + 1));
    }
    s
}

/// Writes the CRC-32/MPEG-2 of `buf[range]` just after it.
fn put_crc(buf: &mut [u8], range: core::ops::Range<usize>) {
    let crc = wire128::crc32_mpeg2(&buf[range.clone()]);
    buf[range.end..range.end + 4].copy_from_slice(&crc.to_le_bytes());
}

impl PacketSim<'_> {
    /// Trajectory time of 128-channel packet `p`'s time stamp, ns: whole microseconds, the
    /// packets spread evenly over the turn.
    fn hesai128_stamp_ns(&self, p: u64) -> i64 {
        let spec = Spec::of(self.sensor);
        let from_first = p * self.period_ns() / self.per_sweep;
        spec.first_stamp_ns() + (from_first / 1000 * 1000) as i64
    }

    /// Trajectory time of packet `p`'s block `block`, channel `channel`.
    fn hesai128_offset(&self, p: u64, block: usize, channel: usize) -> f64 {
        let ns = self.hesai128_stamp_ns(p) + Spec::of(self.sensor).channel_ns(block, channel);
        ns as f64 * 1e-9
    }

    /// Trajectory time of 128-channel packet `p`'s last firing.
    pub(super) fn hesai128_last_offset(&self, p: u64) -> f64 {
        let spec = Spec::of(self.sensor);
        let last_block = wire128::BLOCKS - 1;
        let (_, last) = spec
            .model
            .firing_span_ns(last_block, &spec.firing(last_block));
        (self.hesai128_stamp_ns(p) + last) as f64 * 1e-9
    }

    pub(super) fn hesai128_packet(&self, p: u64) -> (Packet, Vec<Truth>) {
        let spec = Spec::of(self.sensor);
        let layout = spec.layout();
        let mut buf = vec![0u8; layout.len];
        write_header(
            &mut buf,
            spec.version,
            (wire128::LASERS, wire128::BLOCKS),
            spec.flags,
        );
        let (unit_len, block_len, tail) = (layout.unit_len, layout.block_len, layout.tail);
        let mut truth = Vec::new();
        let mut azimuth_states = 0u16;
        for b in 0..wire128::BLOCKS {
            let at = field::BODY + b * block_len;
            let g = p * wire128::BLOCKS as u64 + b as u64;
            let azimuth = self.hesai_azimuth(g, wire128::BLOCKS);
            buf[at + field::AZIMUTH.start..at + field::AZIMUTH.end]
                .copy_from_slice(&azimuth.to_le_bytes());
            azimuth_states |= u16::from(spec.firing(b).azimuth_state) << (14 - 2 * b);
            let firing = spec.firing(b);
            for (c, angles) in spec.angles.iter().enumerate() {
                if !spec.model.fires(b, c, &firing) {
                    // Not fired in this loop or azimuth state: distance 0.
                    continue;
                }
                let at = at + field::AZIMUTH.end + c * unit_len;
                truth.extend(self.hesai_channel(
                    &mut buf[at..at + unit_len],
                    azimuth,
                    *angles,
                    self.hesai128_offset(p, b, c),
                    [p, (b * wire128::LASERS + c) as u64],
                ));
            }
        }
        // The functional safety part (flagged on both) follows the body CRC.
        let safety = layout.body_crc + field::BODY_CRC_LEN;
        buf[safety..safety + SAFETY.len()].copy_from_slice(&SAFETY);
        put_crc(&mut buf, safety + 1..safety + SAFETY.len());
        let f = spec.firing(0);
        buf[tail + field::MODE_FLAG] = f.mode_flag;
        buf[tail + field::OPERATIONAL_STATE] = f.operational_state;
        buf[tail + field::AZIMUTH_STATE.start..tail + field::AZIMUTH_STATE.end]
            .copy_from_slice(&azimuth_states.to_le_bytes());
        self.hesai_tail(&mut buf, tail, self.hesai128_stamp_ns(p));
        if let Some(at) = layout.sequence {
            buf[at..at + field::SEQUENCE_LEN].copy_from_slice(&(p as u32).to_le_bytes());
        }
        for (covered, _) in layout.crc_ranges() {
            put_crc(&mut buf, covered);
        }
        (
            Packet {
                offset: self.hesai128_last_offset(p),
                payload: buf,
            },
            truth,
        )
    }
}

/// The PandarQT128's angle correction file as a real unit's reads (TIER IV nebula's
/// `PandarQT128.csv`, `fixtures/hesai-qt128/`): elevation and azimuth offset, degrees.
#[rustfmt::skip]
pub const QT128_ANGLES: [[f64; 2]; wire128::LASERS] = [
    [-52.62676282, 10.10830596], [-51.0280939, 9.719503673],
    [-49.51495392, 9.384265827], [-48.07394795, 9.091433335],
    [-46.69466297, 8.832899657], [-45.36882812, 8.602605729],
    [-44.08974439, 8.395920495], [-42.85190128, 8.209210679],
    [-41.65069769, 8.03961095], [-40.48225401, 7.8848012],
    [-39.34326358, 7.742887867], [-38.23088092, 7.612311759],
    [-37.14263654, 7.491771683], [-36.07637316, 7.380164213],
    [-35.03019446, 7.276562397], [-34.00242585, 7.180171603],
    [-32.99157758, 7.090302002], [-31.99631045, 7.006369095],
    [-31.01543179, 6.927848973], [-30.04786472, 6.854295551],
    [-29.09262707, 6.785306938], [-28.14883195, 6.720536921],
    [-27.21566989, 6.659666871], [-26.29240356, 6.602428464],
    [-25.37835081, 6.548569874], [-24.47288318, 6.497872808],
    [-23.57542315, 6.450129948], [-22.68544071, 6.405178951],
    [-21.80243688, 6.362840261], [-20.92594329, 6.32298504],
    [-20.05553602, 6.285467298], [-19.19081372, 6.25017485],
    [-18.33139172, -6.21699538], [-17.47691901, -6.18583344],
    [-16.62705442, -6.156599148], [-15.78149317, -6.129208192],
    [-14.93993032, -6.103581848], [-14.10208035, -6.079663981],
    [-13.26767188, -6.057381402], [-12.43645574, -6.036683527],
    [-11.60818201, -6.017519726], [-10.78261371, -5.999833659],
    [-9.959523504, -5.983597281], [-9.138697037, -5.968771181],
    [-8.319929599, -5.955310246], [-7.503005408, -5.943192006],
    [-6.687807162, -5.926719867], [-5.873926875, -5.922876604],
    [-5.061393513, -5.914628713], [-4.249948322, -5.907639071],
    [-3.43941536, -5.901885097], [-2.629617595, -5.897355529],
    [-1.820378325, -5.894039091], [-1.011522452, -5.891935825],
    [-0.202883525, -5.89103442], [0.605717878, -5.89132922],
    [1.414444374, -5.892831558], [2.223469054, -5.895541414],
    [3.032962884, -5.899458754], [3.8431104, -5.904600534],
    [4.654074511, -5.910966684], [5.466034723, -5.918579795],
    [6.279180222, -5.927451101], [7.093696848, -5.937608821],
    [7.909760474, 5.949064148], [8.727579858, 5.961845258],
    [9.54735011, 5.97598597], [10.36927364, 5.99150874],
    [11.19356846, 6.008464331], [12.0204614, 6.026875139],
    [12.85016831, 6.046797524], [13.68294669, 6.068282136],
    [14.51903314, 6.091373918], [15.35869922, 6.116134758],
    [16.20222125, 6.142626487], [17.04988688, 6.170927865],
    [17.90200196, 6.201111915], [18.75890049, 6.233268566],
    [19.62091911, 6.267487655], [20.48842178, 6.303870236],
    [21.36180725, 6.342539884], [22.24149217, 6.383614369],
    [23.12791172, 6.427233938], [24.02155359, 6.473555624],
    [24.92293181, 6.52274755], [25.83260224, 6.574994555],
    [26.75116558, 6.63050945], [27.67927338, 6.689521655],
    [28.61763387, 6.752299732], [29.56702472, 6.819128697],
    [30.52828971, 6.890343815], [31.50236238, 6.966319159],
    [32.49026442, 7.0474731], [33.49313666, 7.134285032],
    [34.51223682, 7.227334588], [35.54897914, 7.327222327],
    [19.19081372, -6.25017485], [20.05553602, -6.285467298],
    [20.92594329, -6.32298504], [21.80243688, -6.362840261],
    [22.68544071, -6.405178951], [23.57542315, -6.450129948],
    [24.47288318, -6.497872808], [25.37835081, -6.548569874],
    [26.29240356, -6.602428464], [27.21566989, -6.659666871],
    [28.14883195, -6.720536921], [29.09262707, -6.785306938],
    [30.04786472, -6.854295551], [31.01543179, -6.927848973],
    [31.99631045, -7.006369095], [32.99157758, -7.090302002],
    [34.00242585, -7.180171603], [35.03019446, -7.276562397],
    [36.07637316, -7.380164213], [37.14263654, -7.491771683],
    [38.23088092, -7.612311759], [39.34326358, -7.742887867],
    [40.48225401, -7.8848012], [41.65069769, -8.03961095],
    [42.85190128, -8.209210679], [44.08974439, -8.395920495],
    [45.36882812, -8.602605729], [46.69466297, -8.832899657],
    [48.07394795, -9.091433335], [49.51495392, -9.384265827],
    [51.0280939, -9.719503673], [52.62676282, -10.10830596],
];

/// An OT128 angle correction file made for the simulator: channels 1 to 24 from +15 degrees
/// down in 0.5 degree steps, 25 to 104 from +3 in 0.125 steps (the finer band around the
/// horizon), 105 to 128 from -7.75 to -25 in 0.75 steps; azimuth offsets near -3, -1, 1 and 3
/// degrees in turn, each a few hundredths off as a unit's are.
#[rustfmt::skip]
pub const OT128_ANGLES: [[f64; 2]; wire128::LASERS] = [
    [15.0, -2.994], [14.5, -0.982], [14.0, 0.989], [13.5, 2.985],
    [13.0, -2.985], [12.5, -0.988], [12.0, 0.982], [11.5, 2.993],
    [11.0, -2.981], [10.5, -0.998], [10.0, 0.98], [9.5, 3.003],
    [9.0, -2.981], [8.5, -1.008], [8.0, 0.983], [7.5, 3.012],
    [7.0, -2.986], [6.5, -1.016], [6.0, 0.99], [5.5, 3.019],
    [5.0, -2.995], [4.5, -1.02], [4.0, 1.0], [3.5, 3.02],
    [3.0, -3.005], [2.875, -1.019], [2.75, 1.01], [2.625, 3.016],
    [2.5, -3.014], [2.375, -1.012], [2.25, 1.017], [2.125, 3.008],
    [2.0, -3.019], [1.875, -1.003], [1.75, 1.02], [1.625, 2.998],
    [1.5, -3.019], [1.375, -0.993], [1.25, 1.018], [1.125, 2.988],
    [1.0, -3.015], [0.875, -0.985], [0.75, 1.011], [0.625, 2.982],
    [0.5, -3.006], [0.375, -0.98], [0.25, 1.001], [0.125, 2.98],
    [0.0, -2.996], [-0.125, -0.981], [-0.25, 0.991], [-0.375, 2.984],
    [-0.5, -2.987], [-0.625, -0.987], [-0.75, 0.983], [-0.875, 2.991],
    [-1.0, -2.981], [-1.125, -0.996], [-1.25, 0.98], [-1.375, 3.001],
    [-1.5, -2.98], [-1.625, -1.006], [-1.75, 0.982], [-1.875, 3.011],
    [-2.0, -2.985], [-2.125, -1.015], [-2.25, 0.989], [-2.375, 3.018],
    [-2.5, -2.993], [-2.625, -1.02], [-2.75, 0.998], [-2.875, 3.02],
    [-3.0, -3.004], [-3.125, -1.019], [-3.25, 1.008], [-3.375, 3.017],
    [-3.5, -3.013], [-3.625, -1.014], [-3.75, 1.016], [-3.875, 3.009],
    [-4.0, -3.019], [-4.125, -1.005], [-4.25, 1.02], [-4.375, 2.999],
    [-4.5, -3.02], [-4.625, -0.994], [-4.75, 1.018], [-4.875, 2.99],
    [-5.0, -3.016], [-5.125, -0.986], [-5.25, 1.012], [-5.375, 2.983],
    [-5.5, -3.007], [-5.625, -0.981], [-5.75, 1.002], [-5.875, 2.98],
    [-6.0, -2.997], [-6.125, -0.981], [-6.25, 0.992], [-6.375, 2.983],
    [-6.5, -2.988], [-6.625, -0.986], [-6.75, 0.984], [-6.875, 2.99],
    [-7.75, -2.982], [-8.5, -0.995], [-9.25, 0.98], [-10.0, 3.0],
    [-10.75, -2.98], [-11.5, -1.005], [-12.25, 0.981], [-13.0, 3.01],
    [-13.75, -2.984], [-14.5, -1.014], [-15.25, 0.987], [-16.0, 3.017],
    [-16.75, -2.992], [-17.5, -1.019], [-18.25, 0.997], [-19.0, 3.02],
    [-19.75, -3.002], [-20.5, -1.019], [-21.25, 1.007], [-22.0, 3.018],
    [-22.75, -3.012], [-23.5, -1.015], [-24.25, 1.015], [-25.0, 3.011],
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::packets::xt32::tests::{decoded_as_simulated, sim};
    use kiss_odom_sensors::hesai::{self, Calibration};

    /// The decoder's configuration for `sensor`: its model and angle correction file.
    fn config(sensor: PacketSensor) -> hesai::Config {
        let spec = Spec::of(sensor);
        let mut calibration = Calibration::nominal();
        calibration.channels = wire128::LASERS;
        for (c, [e, a]) in spec.angles.iter().enumerate() {
            calibration.elevation_deg[c] = *e;
            calibration.azimuth_deg[c] = *a;
        }
        hesai::Config {
            model: spec.model,
            calibration: Some(calibration),
            cut_angle_deg: None,
        }
    }

    #[test]
    fn the_decoders_sweeps_are_the_simulators_and_silent_channels_have_no_return() {
        for (sensor, per_turn, len) in [
            (PacketSensor::Qt128, 450, 1127),
            (PacketSensor::Ot128, 900, 861),
        ] {
            let sim = sim(sensor, 10.0, 0.0);
            let ps = PacketSim::new(&sim, sensor);
            let sweeps = decoded_as_simulated(&ps, config(sensor));
            assert_eq!(ps.packets_per_sweep(), per_turn);
            assert_eq!(sweeps[0].packets.len() as u64, per_turn + 1);
            let spec = Spec::of(sensor);
            let (mut returns, mut silent) = (0, 0);
            for (i, packet) in sweeps[1].packets.iter().enumerate() {
                assert_eq!(packet.payload.len(), len);
                let p = wire128::Packet::new_checked(&packet.payload).unwrap();
                assert_eq!(p.udp_sequence(), Some(per_turn as u32 + 1 + i as u32));
                assert_eq!(p.motor_rpm(), 600);
                for b in 0..wire128::BLOCKS {
                    let f = Firing {
                        returns: 1,
                        mode_flag: p.mode_flag(),
                        operational_state: p.operational_state(),
                        azimuth_state: p.azimuth_state(b),
                        near: false,
                    };
                    assert_eq!(f, spec.firing(b));
                    for c in 0..wire128::LASERS {
                        let fires = spec.model.fires(b, c, &f);
                        let hit = p.channel(b, c).0 != 0;
                        assert!(fires || !hit, "{sensor:?}: silent channel {c} has a return");
                        returns += usize::from(hit);
                        silent += usize::from(!fires);
                    }
                }
            }
            // QT128: 32 channels in each loop (a quarter); OT128 standard: every channel fires.
            println!("{sensor:?}: {returns} returns, {silent} silent channel firings a turn");
            let silent_per_firing = if sensor == PacketSensor::Qt128 { 32 } else { 0 };
            assert!(returns > 0);
            assert_eq!(silent, silent_per_firing * 2 * sweeps[1].packets.len());
            // A turn's last block at azimuth 0, the blocks 360 degrees / blocks a turn apart.
            let last =
                wire128::Packet::new_checked(&sweeps[1].packets.last().unwrap().payload).unwrap();
            let step = 36000 / (per_turn as u16 * 2);
            assert_eq!((last.azimuth(0), last.azimuth(1)), (36000 - step, 0));
        }
    }

    #[test]
    fn crcs_are_computed_as_a_recorded_qt128_computes_them() {
        use pcap_file::pcap::PcapReader;
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../fixtures/hesai-qt128/qt128-sector.pcap"
        );
        let mut reader = PcapReader::new(std::fs::File::open(path).unwrap()).unwrap();
        let frame = reader.next_packet().unwrap().unwrap();
        // Ethernet, IPv4 and UDP headers: 42 bytes.
        let b = &frame.data[42..];
        let crc_at = |at: usize| u32::from_le_bytes(b[at..at + 4].try_into().unwrap());
        let layout = QT128.layout();
        let (body_end, tail) = (layout.body_crc, layout.tail);
        let safety = body_end + field::BODY_CRC_LEN;
        let tail_crc = tail + field::TAIL_LEN + field::SEQUENCE_LEN;
        assert_eq!(tail_crc, layout.tail_crc);
        assert_eq!(b.len(), 1127);
        assert_eq!(
            wire128::crc32_mpeg2(&b[field::BODY..body_end]),
            crc_at(body_end)
        );
        assert_eq!(
            wire128::crc32_mpeg2(&b[safety + 1..tail - 4]),
            crc_at(tail - 4)
        );
        assert_eq!(b[safety..tail - 4], SAFETY);
        assert_eq!(wire128::crc32_mpeg2(&b[tail..tail_crc]), crc_at(tail_crc));
    }
}
