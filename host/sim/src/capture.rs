//! Writes simulated packets as a pcap capture (Ethernet, IPv4, UDP, as Wireshark or VeloView
//! record a sensor) and, for an Ouster, the metadata JSON that describes it, for a Hesai its
//! angle correction file (a CSV; the AT128's: a `.dat`).
//!
//! The last step of `simulate --format pcap`, after [`crate::packets`]. Datagrams are not
//! fragmented: an OS1-64 packet (12 544 bytes) travels in one jumbo frame. IMU packets (the
//! OS1's and the Mid-360's, with `--imu-rate`) go to the sensor's IMU port: the OS1's
//! `udp_port_imu` (7503), the Mid-360's 56401 from 56400 (Livox's defaults).

use crate::packets::{os1, Packet, PacketSensor};
use crate::trajectory::PoseM;
use anyhow::{Context, Result};
use etherparse::PacketBuilder;
use pcap_file::pcap::{PcapHeader, PcapPacket, PcapWriter};
use pcap_file::DataLink;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The capture's file name in the output folder.
pub const PCAP_NAME: &str = "packets.pcap";
/// The Ouster metadata's file name in the output folder.
pub const META_NAME: &str = "packets.json";
/// The Hesai angle correction file's name in the output folder.
pub const ANGLES_NAME: &str = "packets.csv";
/// The Velodyne calibration (ROS YAML) beside a HDL-64E's or VLS-128's capture.
pub const CALIBRATION_NAME: &str = "packets.yaml";
/// The PandarAT128's angle correction file's name in the output folder.
pub const CORRECTION_NAME: &str = "packets.dat";

/// Where simulated packets go, in sending order: a capture ([`CaptureWriter`]) or a ROS
/// recording of them ([`crate::ros::packet_bag`]).
pub trait PacketSink {
    /// One lidar packet.
    fn write(&mut self, packet: &Packet) -> Result<()>;
    /// One IMU packet ([`PacketSensor::imu_packet`]).
    fn write_imu(&mut self, packet: &Packet) -> Result<()>;
    /// One device-information packet ([`PacketSensor::device_packet`]).
    fn write_device(&mut self, packet: &Packet) -> Result<()>;
    /// The sweep's last packet has been written.
    fn end_sweep(&mut self) -> Result<()> {
        Ok(())
    }
    /// Writes what is left and closes the file.
    fn finish(self: Box<Self>) -> Result<()>;
}

/// When a packet leaving the sensor at trajectory time `offset` (s) is captured, on a host
/// whose clock read `clock_start` (s) at trajectory time 0 and agrees with the sensor's: ns
/// since the epoch, to the microsecond a pcap keeps.
pub fn capture_ns(clock_start: f64, offset: f64) -> u64 {
    let t = Duration::from_secs_f64((clock_start + offset).max(0.0));
    t.as_secs() * 1_000_000_000 + u64::from(t.subsec_micros()) * 1_000
}

/// The host clock's reading at trajectory time 0 for `sensor`'s packets, s.
pub fn clock_start(sensor: PacketSensor, start_time: f64) -> f64 {
    start_time + sensor.clock_origin_s() as f64
}

/// A pcap file being written.
pub struct CaptureWriter {
    path: PathBuf,
    writer: PcapWriter<BufWriter<File>>,
    /// Source and destination UDP ports.
    ports: (u16, u16),
    /// Source and destination UDP ports of the IMU packets.
    imu_ports: (u16, u16),
    source: [u8; 4],
    /// The capture clock at trajectory time 0 (s).
    start_time: f64,
}

impl CaptureWriter {
    /// Creates `path` for `sensor`'s packets; `start_time` is the sequence time of the first.
    pub fn create(path: &Path, sensor: PacketSensor, start_time: f64) -> Result<Self> {
        let file = File::create(path).with_context(|| format!("creating {}", path.display()))?;
        // Little-endian, as Wireshark and tcpdump write on the usual hosts.
        let header = PcapHeader {
            datalink: DataLink::ETHERNET,
            endianness: pcap_file::Endianness::Little,
            ..PcapHeader::default()
        };
        let writer = PcapWriter::with_header(BufWriter::new(file), header)
            .with_context(|| format!("writing {}", path.display()))?;
        let (ports, imu_ports, source) = match sensor {
            PacketSensor::Os1 => ((7502, 7502), (7503, 7503), [192, 168, 1, 100]),
            // The Mid-360 sends from port 56300 to the host's 56301, its IMU from 56400 to
            // 56401 (Livox's defaults).
            PacketSensor::Mid360 => ((56300, 56301), (56400, 56401), [192, 168, 1, 160]),
            // A Livox SDK 1 sensor sends its points to the host's port 56001.
            PacketSensor::Avia => ((65000, 56001), (65000, 56001), [192, 168, 1, 150]),
            // Robosense: points to 6699, device information (DIFOP) to 7788.
            s if s.robosense().is_some() || s.solid().is_some() => {
                ((6699, 6699), (7788, 7788), [192, 168, 1, 200])
            }
            // Velodyne and Hesai.
            _ => ((2368, 2368), (2368, 2368), [192, 168, 1, 201]),
        };
        Ok(Self {
            path: path.to_path_buf(),
            writer,
            ports,
            imu_ports,
            source,
            // Captured on a host whose clock agrees with the sensor's.
            start_time: clock_start(sensor, start_time),
        })
    }

    fn write_to(&mut self, packet: &Packet, (from, to): (u16, u16)) -> Result<()> {
        let builder = PacketBuilder::ethernet2([0x60, 0x76, 0x88, 0, 0, 1], [0xFF; 6])
            .ipv4(self.source, [192, 168, 1, 2], 64)
            .udp(from, to);
        let mut frame = Vec::with_capacity(builder.size(packet.payload.len()));
        builder
            .write(&mut frame, &packet.payload)
            .context("building a UDP frame")?;
        let time = Duration::from_nanos(capture_ns(self.start_time, packet.offset));
        let record = PcapPacket::new(time, frame.len() as u32, &frame);
        self.writer
            .write_packet(&record)
            .with_context(|| format!("writing {}", self.path.display()))?;
        Ok(())
    }
}

impl PacketSink for CaptureWriter {
    /// Appends one lidar packet, stamped with the time it leaves the sensor.
    fn write(&mut self, packet: &Packet) -> Result<()> {
        self.write_to(packet, self.ports)
    }

    /// Appends one IMU packet, to the sensor's IMU port.
    fn write_imu(&mut self, packet: &Packet) -> Result<()> {
        self.write_to(packet, self.imu_ports)
    }

    /// Appends one device-information packet, to the port the sensor sends it to (the
    /// Robosense DIFOP port; the IMU port of the others).
    fn write_device(&mut self, packet: &Packet) -> Result<()> {
        self.write_to(packet, self.imu_ports)
    }

    /// Flushes the file.
    fn finish(self: Box<Self>) -> Result<()> {
        let path = self.path.clone();
        let mut w = self.writer.into_writer();
        std::io::Write::flush(&mut w).with_context(|| format!("writing {}", path.display()))
    }
}

/// The OS1-64's metadata in the sensor's own (firmware 2.x, `json_calibration_version` 4)
/// layout, which ouster-sdk and `io::ouster_meta` read; `imu`, the simulated IMU's pose in
/// the sensor frame, becomes its `imu_to_sensor_transform` (an OS1's own otherwise).
pub fn ouster_metadata(rate_hz: f64, imu: Option<&PoseM>) -> serde_json::Value {
    let beams = 0..os1::BEAMS;
    let width = f64::from(os1::WIDTH);
    let shift: Vec<i64> = beams
        .clone()
        .map(|u| libm::round(os1::azimuth_deg(u) / 360.0 * width) as i64)
        .collect();
    let imu_to_sensor: Vec<f64> = match imu {
        Some(pose) => {
            let mut m = pose.to_homogeneous();
            for r in 0..3 {
                m[(r, 3)] *= 1000.0; // millimetres
            }
            m.transpose().iter().copied().collect() // row-major
        }
        None => vec![
            1.0, 0.0, 0.0, 6.253, 0.0, 1.0, 0.0, -11.775, 0.0, 0.0, 1.0, 7.645, 0.0, 0.0, 0.0, 1.0,
        ],
    };
    serde_json::json!({
        "base_pn": "", "base_sn": "", "hostname": "", "proto_rev": "",
        "beam_altitude_angles": beams.clone().map(os1::altitude_deg).collect::<Vec<_>>(),
        "beam_azimuth_angles": beams.map(os1::azimuth_deg).collect::<Vec<_>>(),
        "build_date": "2022-04-14T21:11:47Z",
        "build_rev": "v2.3.0",
        "client_version": "ouster_client 0.3.0",
        "data_format": {
            "column_window": [0, os1::WIDTH - 1],
            "columns_per_frame": os1::WIDTH,
            "columns_per_packet": os1::COLUMNS_PER_PACKET,
            "pixel_shift_by_row": shift,
            "pixels_per_column": os1::BEAMS,
            "udp_profile_imu": "LEGACY",
            "udp_profile_lidar": "RNG19_RFL8_SIG16_NIR16",
        },
        "image_rev": "kiss-odom simulate",
        "imu_to_sensor_transform": imu_to_sensor,
        "initialization_id": os1::INIT_ID,
        "json_calibration_version": 4,
        "lidar_mode": format!("{}x{}", os1::WIDTH, rate_hz as u32),
        "lidar_origin_to_beam_origin_mm": os1::BEAM_ORIGIN_MM,
        "lidar_to_sensor_transform": os1::LIDAR_TO_SENSOR,
        "prod_line": "OS-1-64",
        "prod_pn": "840-102145-D",
        "prod_sn": os1::SERIAL.to_string(),
        "status": "RUNNING",
        "udp_port_imu": 7503,
        "udp_port_lidar": 7502,
    })
}
