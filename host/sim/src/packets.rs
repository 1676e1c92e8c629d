//! The simulated sweeps as a real sensor's UDP packets (`simulate --sensor ... --format pcap`).
//!
//! Sits between the ray caster and the capture writer ([`crate::capture`]): each laser fires at
//! the instant its sensor's firing sequence says (Velodyne's and Hesai's published timing,
//! Ouster's per-column timestamps, Livox's points a second), from the pose at that instant,
//! along its own beam (per-laser elevation, azimuth offset and beam origin), and the range is
//! written in the packet's unit (2 or 4 mm, 1 mm). The exact point before that quantisation,
//! with its firing time, is the sweep's ground truth, in the order a decoder emits points.
//!
//! A Velodyne spins a whole number of packets per turn (the rate is rounded to make it so) and
//! the turn starts 1.5 blocks after azimuth 0, so the packet whose last block passes azimuth 0
//! is the last of each sweep: decoders cutting at 0 degrees see the simulator's sweeps (without
//! a cut angle, `run` takes a full turn from the first packet: the same sweeps one packet
//! later). The Hesai sensors (`packets/xt32.rs`, `packets/hesai128.rs`) are placed so that
//! `run` without a cut angle sees their sweeps. An Ouster's sweep is one frame id. The Livox
//! sensors (`packets/mid360.rs`, `packets/avia.rs`) have no sweep: their frames are cut by
//! time, as their decoder cuts them.
//!
//! With an IMU, the OS1 and the Mid-360 also send its samples as their own IMU packets
//! (`packets/ouster_imu.rs`, `packets/mid360_imu.rs`), one a sample, stamped on the clock of
//! their lidar packets.

mod at128;
mod avia;
mod hesai128;
mod hesai_fixed;
mod mid360;
mod mid360_imu;
mod ouster_imu;
mod robosense;
mod solid;
mod velodyne_wide;
mod xt32;

use crate::imu::ImuSample;
use crate::rng::{key, Purpose, Stream};
use crate::sensor::Frame;
use crate::simulation::Simulation;
use crate::trajectory::PoseM;
use kiss_odom_sensors::robosense::solid::Model as Solid;
use kiss_odom_sensors::robosense::Model as RobosenseModel;
use kiss_odom_sensors::velodyne::{self, Calibration, Model};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use serde::Serialize;

/// A sensor whose packets the simulator writes. A sensor's place in this list keys the noise of
/// its rays (`PacketSim::cast`): new sensors go last, so the others' recordings stay the same.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum PacketSensor {
    /// Velodyne VLP-16, strongest return, 2 mm ranges.
    #[cfg_attr(feature = "clap", value(name = "vlp16"))]
    #[serde(rename = "vlp16")]
    Vlp16,
    /// Velodyne VLP-32C, strongest return, 4 mm ranges.
    #[cfg_attr(feature = "clap", value(name = "vlp32c"))]
    #[serde(rename = "vlp32c")]
    Vlp32c,
    /// Ouster OS1-64, 1024 columns, profile RNG19_RFL8_SIG16_NIR16 (metadata JSON beside).
    #[cfg_attr(feature = "clap", value(name = "os1-64"))]
    #[serde(rename = "os1-64")]
    Os1,
    /// Livox Mid-360, Livox SDK 2 packets of 96 points (x, y, z in mm), frames by time.
    #[cfg_attr(feature = "clap", value(name = "mid360"))]
    #[serde(rename = "mid360")]
    Mid360,
    /// Hesai PandarXT-32, UDP protocol 6.1 with sequence numbers, strongest return, 4 mm
    /// ranges, 5, 10 or 20 Hz.
    #[cfg_attr(feature = "clap", value(name = "xt32"))]
    #[serde(rename = "xt32")]
    Xt32,
    /// Livox Avia, Livox SDK 1 packets of 96 points (x, y, z in mm), a 70.4 x 77.2 degree
    /// rosette, frames by time.
    #[cfg_attr(feature = "clap", value(name = "avia"))]
    #[serde(rename = "avia")]
    Avia,
    /// Hesai PandarQT128, UDP protocol 3.2 with sequence numbers, functional safety, signature
    /// and confidence bytes, strongest return, 4 mm ranges, 10 Hz (angle file beside).
    #[cfg_attr(feature = "clap", value(name = "qt128"))]
    #[serde(rename = "qt128")]
    Qt128,
    /// Hesai OT128, UDP protocol 1.4 with sequence numbers, IMU and functional safety,
    /// standard operational state, strongest return, 4 mm ranges, 10 Hz (angle file beside).
    #[cfg_attr(feature = "clap", value(name = "ot128"))]
    #[serde(rename = "ot128")]
    Ot128,
    /// Robosense RS-Helios: MSOP packets (port 6699) of twelve 32-laser blocks, strongest
    /// return, 2.5 mm ranges, and a DIFOP packet with the lasers' angles (port 7788).
    #[cfg_attr(feature = "clap", value(name = "helios"))]
    #[serde(rename = "helios")]
    Helios,
    /// Robosense RS-LiDAR-16: the Helios's MSOP and DIFOP ports, blocks of two 16-laser
    /// firings, 5 mm ranges, calendar-date stamps.
    #[cfg_attr(feature = "clap", value(name = "rs16"))]
    #[serde(rename = "rs16")]
    Rs16,
    /// Robosense RS-LiDAR-32: twelve 32-laser blocks, 5 mm ranges, calendar-date stamps.
    #[cfg_attr(feature = "clap", value(name = "rs32"))]
    #[serde(rename = "rs32")]
    Rs32,
    /// Robosense RS-Bpearl: the RS-32's packets, 0 to 89 degrees up.
    #[cfg_attr(feature = "clap", value(name = "bpearl"))]
    #[serde(rename = "bpearl")]
    Bpearl,
    /// Robosense RS-Helios-16P: the Helios's packets, blocks of two 16-laser firings.
    #[cfg_attr(feature = "clap", value(name = "helios16p"))]
    #[serde(rename = "helios16p")]
    Helios16p,
    /// Robosense RS-Ruby: three 128-laser blocks a packet, 5 mm ranges, single return.
    #[cfg_attr(feature = "clap", value(name = "ruby"))]
    #[serde(rename = "ruby")]
    Ruby,
    /// Velodyne HDL-64E S3: upper and lower blocks of 32 lasers, strongest return, 2 mm
    /// ranges (calibration YAML beside).
    #[cfg_attr(feature = "clap", value(name = "hdl64e-s3"))]
    #[serde(rename = "hdl64e-s3")]
    Hdl64e,
    /// Velodyne HDL-64E S2: the S3's packets with the S2's firing timing (calibration YAML
    /// beside).
    #[cfg_attr(feature = "clap", value(name = "hdl64e-s2"))]
    #[serde(rename = "hdl64e-s2")]
    Hdl64eS2,
    /// Velodyne VLS-128: four banks of 32 lasers, strongest return, 4 mm ranges (calibration
    /// YAML beside).
    #[cfg_attr(feature = "clap", value(name = "vls128"))]
    #[serde(rename = "vls128")]
    Vls128,
    /// Hesai PandarXT-16, protocol 6.1 with sequence numbers, strongest return, 10 Hz.
    #[cfg_attr(feature = "clap", value(name = "xt16"))]
    #[serde(rename = "xt16")]
    Xt16,
    /// Hesai PandarXT32M, protocol 6.1, six blocks a packet, strongest return, 10 Hz (angle
    /// file beside).
    #[cfg_attr(feature = "clap", value(name = "xt32m"))]
    #[serde(rename = "xt32m")]
    Xt32m,
    /// Hesai Pandar40P, headerless packets of ten blocks, strongest return, 10 Hz (angle file
    /// beside).
    #[cfg_attr(feature = "clap", value(name = "pandar40p"))]
    #[serde(rename = "pandar40p")]
    Pandar40p,
    /// Hesai Pandar64, 8-byte header, sequence numbers, strongest return, 10 Hz (angle file
    /// beside).
    #[cfg_attr(feature = "clap", value(name = "pandar64"))]
    #[serde(rename = "pandar64")]
    Pandar64,
    /// Hesai PandarQT64, protocol 3.1 with sequence numbers, last return, 10 Hz (angle file
    /// beside).
    #[cfg_attr(feature = "clap", value(name = "qt64"))]
    #[serde(rename = "qt64")]
    Qt64,
    /// Hesai PandarAT128, protocol 4.3, strongest return, 10 frames a second of 600 packets
    /// (its angle correction file, the `.dat`, beside).
    #[cfg_attr(feature = "clap", value(name = "at128"))]
    #[serde(rename = "at128")]
    At128,
    /// Velodyne VLP-32A/B: the VLP-32C's packets and firing times with its own product byte,
    /// strongest return, 4 mm ranges (calibration YAML beside).
    #[cfg_attr(feature = "clap", value(name = "vlp32ab"))]
    #[serde(rename = "vlp32ab")]
    Vlp32ab,
    /// Robosense RS-M1 (MEMS): MSOP packets of 25 blocks of five returns, each with its own
    /// pitch and yaw, a raster of 126 lines over 120 x 25 degrees, 5 mm ranges, 10 Hz frames
    /// of 630 packets numbered from 1.
    #[cfg_attr(feature = "clap", value(name = "m1"))]
    #[serde(rename = "m1")]
    M1,
    /// Robosense E1R (solid state): MSOP packets of 96 blocks of one return with its
    /// direction, 192 x 144 returns over 120 x 90 degrees, 5 mm ranges, 10 Hz frames of 288
    /// packets numbered from 1.
    #[cfg_attr(feature = "clap", value(name = "e1r"))]
    #[serde(rename = "e1r")]
    E1r,
    /// Robosense RS-Airy (96-channel mode): eight 48-channel blocks a packet, a firing's 96
    /// lasers in two, 5 mm ranges to 60 m, single return, mounted normally.
    #[cfg_attr(feature = "clap", value(name = "airy"))]
    #[serde(rename = "airy")]
    Airy,
}

impl PacketSensor {
    /// The Hesai models of fixed layout (`packets/hesai_fixed.rs`).
    const fn hesai_fixed(self) -> bool {
        matches!(
            self,
            Self::Xt16 | Self::Xt32m | Self::Pandar40p | Self::Pandar64 | Self::Qt64
        )
    }
}

/// Ouster geometry: 64 beams over +-22.5 degrees staggered over four azimuths (an OS1-64's
/// layout), beam origins 15.806 mm off the axis, the lidar frame turned half a turn about z and
/// 36.18 mm below the sensor frame (the OS1's `lidar_to_sensor_transform`).
pub mod os1 {
    /// Beams.
    pub const BEAMS: usize = 64;
    /// Columns per frame.
    pub const WIDTH: u16 = 1024;
    /// Columns per packet.
    pub const COLUMNS_PER_PACKET: u16 = 16;
    /// Beam origin distance from the lidar axis, mm.
    pub const BEAM_ORIGIN_MM: f64 = 15.806;
    /// Lidar frame to sensor frame, 4x4 row-major, mm.
    pub const LIDAR_TO_SENSOR: [f64; 16] = [
        -1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 36.18, 0.0, 0.0, 0.0, 1.0,
    ];
    /// Metadata `initialization_id`, also in every packet header.
    pub const INIT_ID: u32 = 0x51_4D_55;
    /// Serial number (`prod_sn`), also in every packet header.
    pub const SERIAL: u64 = 992_000_000_001;
    /// Beam azimuth offsets, degrees, repeating every four beams.
    const AZIMUTH: [f64; 4] = [4.2, 1.4, -1.4, -4.2];

    /// Beam `u`'s altitude, degrees (top first), to 0.01 degree as metadata gives it.
    pub fn altitude_deg(u: usize) -> f64 {
        let a = 22.5 - 45.0 * u as f64 / (BEAMS - 1) as f64;
        libm::round(a * 100.0) / 100.0
    }
    /// Beam `u`'s azimuth offset, degrees.
    pub fn azimuth_deg(u: usize) -> f64 {
        AZIMUTH[u % 4]
    }
}

/// One packet: its UDP payload and the trajectory time it leaves the sensor.
#[derive(Clone, Debug, PartialEq)]
pub struct Packet {
    /// Trajectory time of its last firing (s).
    pub offset: f64,
    /// The UDP payload.
    pub payload: Vec<u8>,
}

/// One firing of one laser: when, from where and where to, in the sensor frame.
struct Firing {
    offset: f64,
    origin: Vector3<f64>,
    dir: Vector3<f64>,
}

/// A return: range (m, with noise), intensity; `None` when nothing came back.
type Echo = Option<(f64, f32)>;

/// A simulated sweep: ground-truth points and the packets carrying them.
pub struct Sweep {
    /// Exact points, times and surfaces, in decoder order.
    pub frame: Frame,
    /// The packets, in sending order.
    pub packets: Vec<Packet>,
}

/// The packets of a simulation for one sensor.
pub struct PacketSim<'a> {
    sim: &'a Simulation,
    sensor: PacketSensor,
    model: Model,
    calib: Calibration,
    /// Velodyne and Hesai: packets per turn; Ouster: packets per frame; Livox: per period,
    /// rounded.
    per_sweep: u64,
}

impl PacketSensor {
    /// The Robosense sensors the simulator writes.
    pub const ROBOSENSE: [Self; 7] = [
        Self::Rs16,
        Self::Rs32,
        Self::Bpearl,
        Self::Helios,
        Self::Helios16p,
        Self::Ruby,
        Self::Airy,
    ];

    /// The Robosense model of a Robosense sensor; `None` for the others.
    pub fn robosense(self) -> Option<kiss_odom_sensors::robosense::Model> {
        use kiss_odom_sensors::robosense::Model as R;
        Some(match self {
            Self::Rs16 => R::Rs16,
            Self::Rs32 => R::Rs32,
            Self::Bpearl => R::Bpearl,
            Self::Helios => R::Helios,
            Self::Helios16p => R::Helios16p,
            Self::Ruby => R::Ruby,
            Self::Airy => R::Airy,
            _ => return None,
        })
    }

    /// The Robosense model whose returns carry their directions; `None` for the others.
    pub fn solid(self) -> Option<Solid> {
        match self {
            Self::M1 => Some(Solid::M1),
            Self::E1r => Some(Solid::E1r),
            _ => None,
        }
    }

    /// Velodyne packet period (s), single return.
    fn velodyne_packet_s(model: Model) -> f64 {
        model.packet_us(false) * 1e-6
    }

    fn model(self) -> Model {
        match self {
            Self::Vlp32c => Model::Vlp32c,
            Self::Vlp32ab => Model::Vlp32ab,
            Self::Hdl64e => Model::Hdl64eS3,
            Self::Hdl64eS2 => Model::Hdl64eS2,
            Self::Vls128 => Model::Vls128,
            _ => Model::Vlp16,
        }
    }

    /// The Velodyne calibration file a VLP-32A/B, HDL-64E or VLS-128 needs (the ROS YAML), to write
    /// beside the capture as [`crate::capture::CALIBRATION_NAME`]; `None` for the others.
    pub fn calibration_file(self) -> Option<String> {
        matches!(
            self,
            Self::Vlp32ab | Self::Hdl64e | Self::Hdl64eS2 | Self::Vls128
        )
        .then(|| velodyne_wide::yaml(&velodyne_wide::calibration(self.model())))
    }

    /// A Livox sensor's point timing (the Mid-360's for the sensors that have none).
    fn timing(self) -> Timing {
        match self {
            Self::Avia => avia::TIMING,
            _ => mid360::TIMING,
        }
    }

    /// The sweep rate the sensor runs at when asked for `rate_hz`: a whole number of packets
    /// per turn (Velodyne), or a rate of the sensor's motor (OS1: 10 or 20 Hz; XT32: 5, 10 or
    /// 20 Hz).
    pub fn rate_hz(self, rate_hz: f64) -> Result<f64, String> {
        match self {
            Self::Os1 if rate_hz == 10.0 || rate_hz == 20.0 => Ok(rate_hz),
            Self::Os1 => Err("an OS1 runs at 10 or 20 Hz (--rate-hz)".into()),
            Self::Xt32 if xt32::RATES_HZ.contains(&rate_hz) => Ok(rate_hz),
            Self::Xt32 => Err("an XT32 runs at 5, 10 or 20 Hz (--rate-hz)".into()),
            Self::Qt128 | Self::Ot128 if rate_hz == hesai128::RATE_HZ => Ok(rate_hz),
            Self::Qt128 | Self::Ot128 => Err("a QT128 or OT128 runs at 10 Hz (--rate-hz)".into()),
            Self::At128 if rate_hz == at128::RATE_HZ => Ok(rate_hz),
            Self::At128 => Err("an AT128 runs at 10 frames a second (--rate-hz)".into()),
            Self::M1 | Self::E1r if rate_hz == solid::RATE_HZ => Ok(rate_hz),
            Self::M1 | Self::E1r => {
                Err("an RS-M1 or E1R runs at 10 frames a second (--rate-hz)".into())
            }
            s if s.hesai_fixed() && rate_hz == hesai_fixed::RATE_HZ => Ok(rate_hz),
            s if s.hesai_fixed() => {
                Err("the simulated Hesai sensors run at 10 Hz (--rate-hz)".into())
            }
            // Frames by time: any rate, read back with `--frame-period` 1 / rate.
            Self::Mid360 | Self::Avia => Ok(rate_hz),
            s if s.robosense().is_some() => {
                let packet =
                    robosense::packet_us(s.robosense().unwrap_or(RobosenseModel::Helios)) * 1e-6;
                let per_turn = libm::round(1.0 / (rate_hz * packet)).max(1.0);
                Ok(1.0 / (per_turn * packet))
            }
            _ => {
                let packet = Self::velodyne_packet_s(self.model());
                let per_turn = libm::round(1.0 / (rate_hz * packet)).max(1.0);
                Ok(1.0 / (per_turn * packet))
            }
        }
    }

    /// Hesai's angle correction file of a QT128 or OT128, which its decoder needs
    /// (`Laser id,Elevation,Azimuth`); `None` for the other sensors.
    pub fn angle_file(self) -> Option<String> {
        if self.hesai_fixed() {
            return Some(hesai_fixed::csv_text(self));
        }
        matches!(self, Self::Qt128 | Self::Ot128).then(|| hesai128::csv_text(self))
    }

    /// The device-information packet a sensor sends beside its points, with the lasers'
    /// angles its decoder needs (the Helios's DIFOP, to port 7788); `None` for the others.
    pub fn device_packet(self, rate_hz: f64) -> Option<Packet> {
        self.robosense().map(|model| Packet {
            offset: 0.0,
            payload: robosense::difop(model, rate_hz),
        })
    }

    /// The PandarAT128's angle correction file (the `.dat`, version 1.5), which its decoder
    /// needs; `None` for the other sensors.
    pub fn correction_file(self) -> Option<Vec<u8>> {
        (self == Self::At128).then(at128::correction_file)
    }

    /// The IMU packet carrying `sample`, the `count`th, sent at trajectory time `offset` and
    /// stamped with the sample's time on the clock the sensor's lidar packets use; `None` for
    /// a sensor whose IMU packets the simulator does not write (all but the OS1 and the
    /// Mid-360).
    pub fn imu_packet(self, sample: &ImuSample, offset: f64, count: u64) -> Option<Packet> {
        let ns = libm::round((sample.time + self.clock_origin_s() as f64).max(0.0) * 1e9) as u64;
        let payload = match self {
            Self::Os1 => ouster_imu::packet(sample, ns),
            Self::Mid360 => mid360_imu::packet(sample, ns, count),
            _ => return None,
        };
        Some(Packet { offset, payload })
    }

    /// The sensor clock's reading at sequence time 0, s: the Hesai sensors stamp their packets
    /// with a UTC date (from 2024-01-01 00:00:00); the other sensors' clocks read sequence time.
    pub const fn clock_origin_s(self) -> i64 {
        match self {
            Self::Xt32 | Self::Qt128 | Self::Ot128 | Self::At128 => xt32::CLOCK_ORIGIN_S,
            Self::Rs16
            | Self::Rs32
            | Self::Bpearl
            | Self::Helios
            | Self::Helios16p
            | Self::Ruby
            | Self::Airy
            | Self::M1
            | Self::E1r => xt32::CLOCK_ORIGIN_S,
            s if s.hesai_fixed() => xt32::CLOCK_ORIGIN_S,
            _ => 0,
        }
    }
}

impl<'a> PacketSim<'a> {
    /// Packets for `sim`, whose sensor rate is already `sensor.rate_hz(...)`.
    pub fn new(sim: &'a Simulation, sensor: PacketSensor) -> Self {
        let model = sensor.model();
        let period = sim.params().sensor.period();
        let per_period = |packet_ns: u64| libm::round(period * 1e9 / packet_ns as f64) as u64;
        let per_sweep = match sensor {
            PacketSensor::Os1 => u64::from(os1::WIDTH / os1::COLUMNS_PER_PACKET),
            PacketSensor::Xt32 => per_period(xt32::PACKET_NS),
            PacketSensor::Qt128 | PacketSensor::Ot128 => per_period(hesai128::packet_ns(sensor)),
            s if s.hesai_fixed() => per_period(hesai_fixed::packet_ns(sensor)),
            PacketSensor::At128 => at128::PACKETS_PER_FRAME,
            s if s.solid().is_some() => solid::packets_per_frame(s.solid().unwrap_or(Solid::M1)),
            PacketSensor::Mid360 | PacketSensor::Avia => per_period(sensor.timing().packet_ns),
            s if s.robosense().is_some() => {
                let model = s.robosense().unwrap_or(RobosenseModel::Helios);
                libm::round(period * 1e6 / robosense::packet_us(model)) as u64
            }
            _ => libm::round(period / PacketSensor::velodyne_packet_s(model)) as u64,
        };
        Self {
            sim,
            sensor,
            model,
            calib: if model.needs_calibration() {
                velodyne_wide::calibration(model)
            } else {
                Calibration::nominal(model)
            },
            per_sweep,
        }
    }

    /// Packets in one sweep (Livox: on average, rounded; Hesai: the first sweep has one more).
    pub fn packets_per_sweep(&self) -> u64 {
        self.per_sweep
    }

    /// The first packet of sweep `k`.
    fn first_packet(&self, k: u64) -> u64 {
        match self.sensor {
            PacketSensor::Mid360 | PacketSensor::Avia => self.timed_first_packet(k),
            // The first sweep also holds the packet before its turn (`packets/xt32.rs`).
            PacketSensor::Xt32 | PacketSensor::Qt128 | PacketSensor::Ot128 if k > 0 => {
                k * self.per_sweep + 1
            }
            s if s.hesai_fixed() && k > 0 => k * self.per_sweep + 1,
            _ => k * self.per_sweep,
        }
    }

    /// Trajectory time of sweep `k`'s last firing.
    pub fn end_offset(&self, k: u64) -> f64 {
        let last = self.first_packet(k + 1) - 1;
        match self.sensor {
            PacketSensor::Os1 => self.column_offset(k, os1::WIDTH - 1),
            PacketSensor::Mid360 | PacketSensor::Avia => {
                self.timed_offset(last, self.sensor.timing().points - 1)
            }
            PacketSensor::Xt32 => xt32::last_offset(last),
            s if s.robosense().is_some() => self.robosense_last_offset(last),
            PacketSensor::Hdl64e | PacketSensor::Hdl64eS2 | PacketSensor::Vls128 => {
                let groups = velodyne::Layout {
                    model: self.model,
                    dual: false,
                }
                .groups();
                let banks = self.model.banks();
                self.wide_start(last) + self.model.firing_s(groups - 1, banks - 1, 31)
            }
            PacketSensor::Qt128 | PacketSensor::Ot128 => self.hesai128_last_offset(last),
            s if s.hesai_fixed() => hesai_fixed::last_offset(s, last),
            PacketSensor::At128 => at128::last_offset(last),
            s if s.solid().is_some() => solid::last_offset(s.solid().unwrap_or(Solid::M1), last),
            _ => {
                let n = velodyne::wire::field::BLOCKS - 1;
                self.packet_offset(last) + self.model.firing_time_s(n, 31)
            }
        }
    }

    /// Ground truth of sweep `k`: its end in the frame of sweep 0's end (with a revisit, the
    /// first run's sweep 0).
    pub fn ground_truth(&self, k: u64) -> PoseM {
        let t = self.sim.trajectory();
        if let Some(first) = self.sim.first_run() {
            // A revisit: in the frame of the first run's sweep 0, at this sensor's timing.
            return first.pose(self.end_offset(0)).inverse() * t.pose(self.end_offset(k));
        }
        if k == 0 {
            return PoseM::identity();
        }
        t.pose(self.end_offset(0)).inverse() * t.pose(self.end_offset(k))
    }

    /// Casts and encodes sweep `k`.
    pub fn sweep(&self, k: u64) -> Sweep {
        let (first, end) = (self.first_packet(k), self.first_packet(k + 1));
        let parts: Vec<(Packet, Vec<Truth>)> = (first..end)
            .into_par_iter()
            .map(|p| match self.sensor {
                PacketSensor::Os1 => self.ouster_packet(k, p - first),
                PacketSensor::Mid360 => self.mid360_packet(p),
                PacketSensor::Avia => self.avia_packet(p),
                PacketSensor::Xt32 => self.xt32_packet(p),
                PacketSensor::Qt128 | PacketSensor::Ot128 => self.hesai128_packet(p),
                s if s.robosense().is_some() => self.robosense_packet(p),
                PacketSensor::Hdl64e | PacketSensor::Hdl64eS2 | PacketSensor::Vls128 => {
                    self.wide_packet(p)
                }
                s if s.hesai_fixed() => self.hesai_fixed_packet(p),
                PacketSensor::At128 => self.at128_packet(p),
                s if s.solid().is_some() => self.solid_packet(s.solid().unwrap_or(Solid::M1), p),
                _ => self.velodyne_packet(p),
            })
            .collect();
        let start = self.sim.params().start_time;
        let mut frame = Frame {
            index: k,
            points: Vec::new(),
            stamps: Vec::new(),
            surfaces: Vec::new(),
            end_time: start + self.end_offset(k),
        };
        let mut packets = Vec::with_capacity(parts.len());
        for (packet, truth) in parts {
            for (p, t, s) in truth {
                frame.points.push(p);
                frame.stamps.push(start + t);
                frame.surfaces.push(s);
            }
            packets.push(packet);
        }
        Sweep { frame, packets }
    }

    /// Casts one firing; the echo and, for a return, the exact point.
    fn cast(&self, f: &Firing, ray: [u64; 2]) -> (Echo, Option<Truth>) {
        let l = &self.sim.params().sensor;
        let pose = self.sim.trajectory().pose(f.offset);
        let origin = pose * Point3::from(f.origin);
        let dw = pose.rotation * f.dir;
        let Some(hit) = self.sim.scene().cast(&origin, &dw, l.max_range) else {
            return (None, None);
        };
        let seed = self.sim.params().seed;
        // Keys apart from the generic sweeps' (which use the frame index third).
        let tag = 1 << 62 | self.sensor as u64;
        let mut rng = Stream::from_key(key(&[seed, Purpose::Ray as u64, tag, ray[0], ray[1]]));
        let [n_range, n_speckle] = rng.normal_pair();
        let range = hit.t + l.noise * n_range;
        if rng.chance(l.dropout) || range < l.min_range || range > l.max_range {
            return (None, None);
        }
        let cos_inc = hit.normal.dot(&dw).abs();
        let intensity =
            hit.reflectivity as f64 * (0.3 + 0.7 * cos_inc) * (1.0 - 0.25 * range / l.max_range)
                + 0.02 * n_speckle;
        let intensity = (libm::round(intensity.clamp(0.0, 1.0) * 255.0) / 255.0) as f32;
        let p = f.origin + f.dir * range;
        let point = [p.x as f32, p.y as f32, p.z as f32, intensity];
        (
            Some((range, intensity)),
            Some((point, f.offset, hit.surface)),
        )
    }

    /// Trajectory time of Velodyne packet `p`'s timestamp: whole microseconds, as the sensor's
    /// clock counts them.
    fn packet_offset(&self, p: u64) -> f64 {
        let us = self.model.packet_us(false);
        libm::floor(p as f64 * us) * 1e-6
    }

    /// Rotor azimuth at trajectory time `t`, degrees (clockwise, unwrapped).
    fn azimuth_deg(&self, t: f64) -> f64 {
        let block = 360.0 / (self.per_sweep as f64 * velodyne::wire::field::BLOCKS as f64);
        1.5 * block + 360.0 * t * self.sim.params().sensor.rate_hz
    }

    fn velodyne_packet(&self, p: u64) -> (Packet, Vec<Truth>) {
        use velodyne::wire::{field, AZIMUTH_UNITS, HOUR_US};
        let start_us = libm::round(self.sim.params().start_time * 1e6) as i64;
        let t0 = self.packet_offset(p);
        let mut buf = vec![0u8; field::LEN];
        let mut truth = Vec::new();
        let lasers = self.model.lasers();
        for g in 0..field::BLOCKS {
            let block = &mut buf[g * field::BLOCK_LEN..(g + 1) * field::BLOCK_LEN];
            block[field::FLAG].copy_from_slice(&[0xFF, 0xEE]);
            let az = libm::round(self.azimuth_deg(t0 + self.model.firing_time_s(g, 0)) * 100.0);
            let az = (az as i64).rem_euclid(i64::from(AZIMUTH_UNITS)) as u16;
            block[field::AZIMUTH].copy_from_slice(&az.to_le_bytes());
            for c in 0..field::CHANNELS {
                let laser = &self.calib.lasers[c % lasers];
                let offset = t0 + self.model.firing_time_s(g, c);
                let theta = (self.azimuth_deg(offset) + laser.azimuth_offset_deg).to_radians();
                let (s, co) = (libm::sin(theta), libm::cos(theta));
                let v = laser.vertical_deg.to_radians();
                let h = laser.horizontal_offset_m;
                let firing = Firing {
                    offset,
                    origin: Vector3::new(h * s, h * co, laser.vertical_offset_m),
                    dir: Vector3::new(libm::cos(v) * co, -libm::cos(v) * s, libm::sin(v)),
                };
                let (echo, point) = self.cast(&firing, [p, (g * field::CHANNELS + c) as u64]);
                let Some((raw, reflectivity)) = in_units(echo, self.calib.distance_resolution_m)
                else {
                    continue;
                };
                let at = field::DATA.start + c * field::CHANNEL_LEN;
                block[at..at + 2].copy_from_slice(&raw.to_le_bytes());
                block[at + 2] = reflectivity;
                truth.extend(point);
            }
        }
        let stamp = (start_us + libm::round(t0 * 1e6) as i64).rem_euclid(i64::from(HOUR_US));
        buf[field::TIMESTAMP].copy_from_slice(&(stamp as u32).to_le_bytes());
        buf[field::RETURN_MODE] = 0x37;
        buf[field::PRODUCT] = self.model.product().unwrap_or(0);
        let last = t0
            + self
                .model
                .firing_time_s(field::BLOCKS - 1, field::CHANNELS - 1);
        (
            Packet {
                offset: last,
                payload: buf,
            },
            truth,
        )
    }

    /// Trajectory time of column `m` of Ouster frame `k`: whole nanoseconds.
    fn column_offset(&self, k: u64, m: u16) -> f64 {
        let period_ns = libm::round(1e9 / self.sim.params().sensor.rate_hz);
        let ns =
            k as f64 * period_ns + libm::round(f64::from(m) * period_ns / f64::from(os1::WIDTH));
        ns * 1e-9
    }

    fn ouster_packet(&self, k: u64, i: u64) -> (Packet, Vec<Truth>) {
        const HEADER: usize = 32;
        const COLUMN_HEADER: usize = 12;
        const PIXEL: usize = 12;
        let cpp = usize::from(os1::COLUMNS_PER_PACKET);
        let column_len = COLUMN_HEADER + os1::BEAMS * PIXEL;
        let mut buf = vec![0u8; HEADER + cpp * column_len + 32];
        buf[0..2].copy_from_slice(&1u16.to_le_bytes());
        buf[2..4].copy_from_slice(&(k as u16).to_le_bytes());
        buf[4..7].copy_from_slice(&os1::INIT_ID.to_le_bytes()[..3]);
        buf[7..12].copy_from_slice(&os1::SERIAL.to_le_bytes()[..5]);
        let start_ns = libm::round(self.sim.params().start_time.max(0.0) * 1e9) as u64;
        let l2s = &os1::LIDAR_TO_SENSOR;
        let rotate = |v: [f64; 3]| {
            Vector3::from_fn(|r, _| {
                l2s[4 * r] * v[0] + l2s[4 * r + 1] * v[1] + l2s[4 * r + 2] * v[2]
            })
        };
        let lift = Vector3::new(l2s[3], l2s[7], l2s[11]) * 1e-3;
        let mut truth = Vec::new();
        let mut last = 0.0;
        for j in 0..cpp {
            let m = (i as usize * cpp + j) as u16;
            let offset = self.column_offset(k, m);
            last = offset;
            let col = &mut buf[HEADER + j * column_len..HEADER + (j + 1) * column_len];
            let ns = start_ns + libm::round(offset * 1e9) as u64;
            col[0..8].copy_from_slice(&ns.to_le_bytes());
            col[8..10].copy_from_slice(&m.to_le_bytes());
            col[10..12].copy_from_slice(&1u16.to_le_bytes());
            let enc = 2.0 * core::f64::consts::PI * (1.0 - f64::from(m) / f64::from(os1::WIDTH));
            let (ce, se) = (libm::cos(enc), libm::sin(enc));
            for u in 0..os1::BEAMS {
                let alt = os1::altitude_deg(u).to_radians();
                let az = enc - os1::azimuth_deg(u).to_radians();
                let d = [
                    libm::cos(az) * libm::cos(alt),
                    libm::sin(az) * libm::cos(alt),
                    libm::sin(alt),
                ];
                let o = [ce * os1::BEAM_ORIGIN_MM, se * os1::BEAM_ORIGIN_MM, 0.0];
                let firing = Firing {
                    offset,
                    origin: rotate(o) * 1e-3 + lift,
                    dir: rotate(d),
                };
                let (echo, point) = self.cast(&firing, [k << 16 | u64::from(m), u as u64]);
                // ouster-sdk measures range from the lidar axis, so the origin's offset is in it.
                let mm = echo.map_or(0.0, |(r, _)| libm::round(r * 1000.0 + os1::BEAM_ORIGIN_MM));
                if mm < 1.0 || mm > f64::from(0x7FFFFu32) {
                    continue;
                }
                let px = &mut col[COLUMN_HEADER + u * PIXEL..COLUMN_HEADER + (u + 1) * PIXEL];
                px[0..4].copy_from_slice(&(mm as u32).to_le_bytes());
                let refl = echo.map_or(0, |(_, i)| libm::roundf(i * 255.0) as u8);
                px[4] = refl;
                px[6..8].copy_from_slice(&(u16::from(refl) * 4).to_le_bytes());
                truth.extend(point);
            }
        }
        (
            Packet {
                offset: last,
                payload: buf,
            },
            truth,
        )
    }
}

/// One ground-truth point: x, y, z, intensity; trajectory time; surface.
type Truth = ([f32; 4], f64, crate::scene::Surface);

/// A return as a spinning sensor writes it: the range in `unit_m` (rounded) and the
/// reflectivity byte; `None` for no return or one the 16-bit range cannot hold (0 means none).
fn in_units(echo: Echo, unit_m: f64) -> Option<(u16, u8)> {
    let (range, intensity) = echo?;
    let raw = libm::round(range / unit_m);
    (1.0..=f64::from(u16::MAX))
        .contains(&raw)
        .then(|| (raw as u16, libm::roundf(intensity * 255.0) as u8))
}

/// The unit vector at `azimuth` (radians, counter-clockwise from x seen from above) and
/// `elevation` (radians, up from the x-y plane).
fn unit(azimuth: f64, elevation: f64) -> Vector3<f64> {
    let c = libm::cos(elevation);
    Vector3::new(
        c * libm::cos(azimuth),
        c * libm::sin(azimuth),
        libm::sin(elevation),
    )
}

/// How a Livox sensor's points are timed: one after the other, a packet at a time; its frames
/// are cut by time.
#[derive(Clone, Copy, Debug)]
struct Timing {
    /// Points a packet holds.
    points: usize,
    /// Time a packet's points span, ns.
    packet_ns: u64,
    /// Time from one point to the next, ns.
    point_ns: f64,
}

/// Bytes of a Livox Cartesian point (SDK 1 data type 2, SDK 2 data type 1): x, y, z in mm
/// (i32), reflectivity, tag.
const LIVOX_POINT_LEN: usize = 14;

impl PacketSim<'_> {
    /// Frame period, ns: whole nanoseconds, as the decoder's `--frame-period` counts them.
    fn period_ns(&self) -> u64 {
        libm::round(1e9 / self.sim.params().sensor.rate_hz) as u64
    }

    /// The first Livox packet of frame `k`: the first whose first point is at or after `k`
    /// periods, as the decoder cuts frames.
    fn timed_first_packet(&self, k: u64) -> u64 {
        (k * self.period_ns()).div_ceil(self.sensor.timing().packet_ns)
    }

    /// Livox packet `p`'s timestamp: its first point's time, ns on the sensor's clock (which
    /// reads sequence time, from 0).
    fn timed_stamp_ns(&self, p: u64) -> u64 {
        let start_ns = libm::round(self.sim.params().start_time.max(0.0) * 1e9) as u64;
        start_ns + p * self.sensor.timing().packet_ns
    }

    /// Trajectory time of Livox packet `p`'s point `i`.
    fn timed_offset(&self, p: u64, i: usize) -> f64 {
        let t = self.sensor.timing();
        ((p * t.packet_ns) as f64 + i as f64 * t.point_ns) * 1e-9
    }

    /// Livox packet `p`, its header already in `buf`: casts its points, point `n` (counted
    /// from the first packet's first) along `direction(time, n)` from the sensor's origin, and
    /// writes each return from byte `data` on in whole millimetres; the exact points. A point
    /// with no return stays all zero, as the sensor sends it.
    fn livox_packet(
        &self,
        p: u64,
        mut buf: Vec<u8>,
        data: usize,
        direction: impl Fn(f64, usize) -> Vector3<f64>,
    ) -> (Packet, Vec<Truth>) {
        let points = self.sensor.timing().points;
        let mut truth = Vec::new();
        let area = buf.get_mut(data..).unwrap_or_default();
        for (i, bytes) in area.chunks_exact_mut(LIVOX_POINT_LEN).enumerate() {
            let offset = self.timed_offset(p, i);
            let firing = Firing {
                offset,
                origin: Vector3::zeros(),
                dir: direction(offset, p as usize * points + i),
            };
            let (echo, point) = self.cast(&firing, [p, i as u64]);
            let Some((range, intensity)) = echo else {
                continue;
            };
            let mm = (firing.dir * range * 1000.0).map(libm::round);
            if mm.iter().all(|&v| v == 0.0) {
                continue;
            }
            for (j, v) in mm.iter().enumerate() {
                bytes[4 * j..4 * j + 4].copy_from_slice(&(*v as i32).to_le_bytes());
            }
            bytes[12] = libm::roundf(intensity * 255.0) as u8;
            truth.extend(point);
        }
        let packet = Packet {
            offset: self.timed_offset(p, points - 1),
            payload: buf,
        };
        (packet, truth)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::Profile;
    use crate::simulation::SimParams;

    /// Asserts that the rates and forces an IMU packet decodes to are `sample`'s within one f32
    /// rounding (2^-24 of the value; the unit conversions, degrees and g, are f64 both ways).
    pub(super) fn assert_imu_decodes_to(sample: &ImuSample, gyro: [f64; 3], accel: [f64; 3]) {
        for (got, want) in gyro
            .iter()
            .zip(sample.gyro)
            .chain(accel.iter().zip(sample.accel))
        {
            let tol = want.abs() * f64::from(f32::EPSILON);
            println!(
                "{want:e}: decoded {got:e}, off {:.1e} (tol {tol:.1e})",
                got - want
            );
            assert!((got - want).abs() <= tol, "{got} vs {want}");
        }
    }

    /// Asserts that a frame's directions `b` do not retrace the last frame's `a`, fired at the
    /// same instants within it: under 1 % of them within 1e-3 rad.
    pub(super) fn assert_not_retraced(a: &[Vector3<f64>], b: &[Vector3<f64>]) {
        let same = a
            .iter()
            .zip(b)
            .filter(|(p, q)| (*p - *q).norm() < 1e-3)
            .count();
        println!("points retraced one frame later: {same} of {}", a.len());
        assert!(same < a.len() / 100);
    }

    fn sim(sensor: PacketSensor, frames: u64) -> Simulation {
        let mut p = SimParams::new(Profile::Fast, 5, frames);
        p.sensor.noise = 0.0;
        p.sensor.rate_hz = sensor.rate_hz(10.0).unwrap();
        Simulation::new(p).unwrap()
    }

    #[test]
    fn noiseless_points_lie_on_their_surface_from_the_pose_at_their_firing() {
        for sensor in [
            PacketSensor::Vlp16,
            PacketSensor::Vlp32c,
            PacketSensor::Os1,
            PacketSensor::Mid360,
            PacketSensor::Xt32,
            PacketSensor::Avia,
            PacketSensor::Qt128,
            PacketSensor::Ot128,
        ] {
            let sim = sim(sensor, 40);
            let ps = PacketSim::new(&sim, sensor);
            let k = 38; // past the fast profile's launch: > 15 m/s
            let sweep = ps.sweep(k);
            let f = &sweep.frame;
            assert!(sim.trajectory().speed(f.end_time) > 15.0);
            let mut worst: f64 = 0.0;
            for ((p, t), s) in f.points.iter().zip(&f.stamps).zip(&f.surfaces) {
                let local = Point3::new(p[0] as f64, p[1] as f64, p[2] as f64);
                let w = sim.world_pose(*t) * local;
                worst = worst.max(sim.scene().distance_to(*s, &w).unwrap());
            }
            println!("{sensor:?}: worst distance {worst:.2e} m (tol 1e-4, f32 rounding)");
            assert!(!f.points.is_empty() && worst < 1e-4);
            // Every firing slot's time is after the last sweep's end and at most this one's
            // (a 128-channel Hesai's channels do not fire in their order).
            let t0 = f.stamps.iter().copied().fold(f64::INFINITY, f64::min);
            let before = sim.params().start_time + ps.end_offset(k - 1);
            assert!(t0 > before && f.stamps.iter().all(|&t| t <= f.end_time));
            assert!(f.end_time - t0 > 0.09, "a sweep spans most of its period");
        }
    }

    #[test]
    fn velodyne_turns_span_whole_packets_and_ouster_frames_are_one_frame_id() {
        let vlp = PacketSensor::Vlp16.rate_hz(10.0).unwrap();
        let turn = 1.0 / vlp;
        let packet = PacketSensor::velodyne_packet_s(Model::Vlp16);
        assert!((turn / packet - libm::round(turn / packet)).abs() < 1e-9);
        assert!((vlp - 10.0).abs() < 0.1, "{vlp} Hz");
        assert!(PacketSensor::Os1.rate_hz(15.0).is_err());
        assert!(PacketSensor::Xt32.rate_hz(15.0).is_err());
        let sim = sim(PacketSensor::Os1, 2);
        let sweep = PacketSim::new(&sim, PacketSensor::Os1).sweep(1);
        assert_eq!(sweep.packets.len(), 64);
        assert!(sweep.packets.iter().all(|p| p.payload[2..4] == [1, 0]));
    }
}
