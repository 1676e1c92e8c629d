//! A whole simulated sequence written to a folder: the frames and ground truth in the generic
//! layout ([`crate::writer`]), `sim.toml`, with [`Format::Pcap`] the same sweeps as the
//! sensor's packets ([`crate::packets`], [`crate::capture`]), with [`Format::Bag`],
//! [`Format::Mcap`] or [`Format::Db3`] a ROS recording ([`crate::ros`]) of the same frames and
//! IMU samples, of the same packets, or of a Livox sensor's frames as its driver publishes
//! them ([`Messages`]), and an IMU's `imu.csv` ([`crate::imu`]) if asked for. The folder
//! appears only once complete; a stop asked for between frames leaves none.

use crate::capture::{self, PacketSink};
use crate::imu::{self, ImuSample, ImuSpec};
use crate::layouts::{self, Layout};
use crate::packets::{PacketSensor, PacketSim};
use crate::profile::Profile;
use crate::ros;
use crate::sensor::Lidar;
use crate::simulation::{SimParams, Simulation};
use crate::writer::DatasetWriter;
use anyhow::{bail, Context, Result};
use serde::Serialize;
use std::path::Path;

/// What a sequence is written as.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// The generic layout only.
    #[default]
    Generic,
    /// The generic layout (exact points) and the same sweeps as the sensor's packets in
    /// `packets.pcap` (needs a packet sensor; an Ouster's metadata goes to `packets.json`, a
    /// QT128's or OT128's angle correction file to `packets.csv`; with `--imu-rate` an OS1's
    /// or a Mid-360's IMU samples are in it too, as the sensor's IMU packets).
    Pcap,
    /// The generic layout and the same frames as `sensor_msgs/PointCloud2` on `/points` in
    /// the ROS 1 bag `points.bag`, with `--imu-rate` the IMU's samples as `sensor_msgs/Imu` on
    /// `/imu`.
    Bag,
    /// As `bag`, in the ROS 2 MCAP file `points.mcap` (CDR messages).
    Mcap,
    /// As `mcap`, in the ROS 2 sqlite3 bag `points/` (`metadata.yaml`, `points_0.db3`).
    Db3,
}

/// What a ROS recording (`--format bag|mcap|db3`) carries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Messages {
    /// Every frame as a `sensor_msgs/PointCloud2` on `/points`.
    #[default]
    Points,
    /// The sensor's packets as its ROS driver records them: VelodyneScan, nebula's
    /// PandarScan, ouster-ros' PacketMsg (with the metadata on `/ouster/metadata`), nebula's
    /// RobosenseScan (with its DIFOP packet; MCAP and db3 only), or for the Livox sensors
    /// nebula's NebulaPackets (MCAP and db3 only); needs `--sensor`.
    Packets,
    /// A Livox sensor's frames (`--sensor mid360` or `avia`) as the Livox driver's `CustomMsg`
    /// on `/livox/lidar`.
    Livox,
}

/// Everything that decides a written sequence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Request {
    /// Scene, motion, sensor geometry.
    pub params: SimParams,
    /// A real sensor's beams, firing timing and packets instead of the generic sensor.
    pub sensor: Option<PacketSensor>,
    /// What to write.
    pub format: Format,
    /// What a ROS recording carries.
    pub messages: Messages,
    /// A Livox `CustomMsg` recording's messages per frame (the driver's publish rate times
    /// the frame period; at least 1).
    pub messages_per_frame: usize,
    /// An IMU riding along, written to `imu.csv`.
    pub imu: Option<ImuSpec>,
    /// A public dataset's layout to write instead of the generic one.
    pub layout: Layout,
    /// Replace a sequence already in the folder.
    pub overwrite: bool,
}

/// How writing a sequence ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Written {
    /// Every frame was written.
    Complete {
        /// Points in all frames.
        points: usize,
        /// Length of the route driven (m).
        route_m: f64,
    },
    /// `stop` asked to end after this many frames; nothing was left in the folder.
    Stopped {
        /// Frames written before the stop.
        frames: u64,
    },
}

/// What `sim.toml` records.
#[derive(Serialize)]
struct Provenance<'a> {
    generator: &'static str,
    version: &'static str,
    profile: Profile,
    seed: u64,
    frames: u64,
    start_time: f64,
    #[serde(skip_serializing_if = "is_zero")]
    lead_in: f64,
    /// What the files mean, for a reader without this source at hand.
    layout: &'static str,
    sensor: &'a Lidar,
    #[serde(skip_serializing_if = "Option::is_none")]
    packets: Option<PacketSummary>,
    /// What the ROS recording carries, if one was written.
    #[serde(skip_serializing_if = "Option::is_none")]
    ros_messages: Option<Messages>,
    #[serde(skip_serializing_if = "Option::is_none")]
    imu: Option<ImuSummary>,
    #[serde(skip_serializing_if = "Option::is_none")]
    revisit: Option<RevisitSummary>,
    scene: SceneSummary,
}

/// What `sim.toml` records of a revisit.
#[derive(Serialize)]
struct RevisitSummary {
    /// What the revisit is, for a reader without this source at hand.
    meaning: &'static str,
    /// Share of the objects asked to change.
    changes: f64,
    /// Offset of the revisit's path from the first run's route (m, left of the route).
    lateral_offset_m: f64,
    /// Objects the first run's scene has that a revisit may change.
    objects: usize,
    moved: usize,
    turned: usize,
    removed: usize,
    new_walls: usize,
}

const REVISIT: &str = "the first run's scene (these parameters without revisit), changed, \
    driven the other way along its route, beside it; poses.txt is in the first run's frame \
    (its sensor at the end of its first sweep), so frame 0 is not the identity; \
    initial_pose.txt: frame 0's pose as X,Y,Z,ROLL,PITCH,YAW (m, degrees, R = Rz(yaw) \
    Ry(pitch) Rx(roll))";

#[derive(Serialize)]
struct ImuSummary {
    #[serde(flatten)]
    spec: ImuSpec,
    /// The turn-on biases this seed drew (rad/s, m/s^2); they then walk.
    gyro_bias_turn_on: [f64; 3],
    accel_bias_turn_on: [f64; 3],
    /// Samples in `imu.csv`.
    samples: usize,
}

#[derive(Serialize)]
struct PacketSummary {
    /// The sensor whose beams, timing and packets were simulated.
    sensor: PacketSensor,
    packets_per_sweep: u64,
    /// Whether `packets.pcap` was written.
    pcap: bool,
}

#[derive(Serialize)]
struct SceneSummary {
    planes: usize,
    solids: usize,
    route_length_m: f64,
}

const LAYOUT: &str = "velodyne/NNNNNN.bin: f32 LE x y z intensity, sensor frame at capture \
    time; timestamps/NNNNNN.bin: f64 LE capture time (s) per point; poses.txt: 3x4 sensor pose \
    at the end of each sweep (its last column) in the frame of the first sweep's end; \
    times.txt: end-of-sweep times (s); packets.pcap (if written): the same sweeps as the \
    sensor's UDP packets, exact points above before range quantisation, in decoder order, \
    with an OS1's or a Mid-360's IMU samples (if written) as its IMU packets; \
    packets.json: Ouster metadata; points.bag, points.mcap or points/ (a ROS 2 sqlite3 bag), if \
    written: the frames as sensor_msgs/PointCloud2 on /points (x y z intensity f32, time f64 s) \
    stamped at the sweep's end, or the sensor's packets as its driver records them, or a Livox \
    sensor's frames as CustomMsg on /livox/lidar (ros_messages), the IMU samples as \
    sensor_msgs/Imu on /imu; imu.csv (if written): time (s, the frames' clock plus the \
    IMU's offset), angular rate (rad/s) and specific force (m/s^2) in the IMU's axes";

/// The simulation parameters of `request`, with the rate a packet sensor rounds to.
pub fn params_of(request: &Request) -> Result<SimParams> {
    let mut params = request.params;
    if let Some(s) = request.sensor {
        params.sensor.rate_hz = s
            .rate_hz(params.sensor.rate_hz)
            .map_err(anyhow::Error::msg)?;
    }
    if request.layout != Layout::Generic {
        if params.revisit.is_some() {
            bail!("--revisit writes the generic layout only (without --layout)");
        }
        if request.format != Format::Generic || request.sensor.is_some() || request.imu.is_some() {
            bail!(
                "--layout {}: a dataset layout is written on its own (without --format, \
                 --sensor or --imu-rate)",
                serde_json::to_value(request.layout)?
                    .as_str()
                    .unwrap_or("?")
            );
        }
        let (rows, columns) = layouts::OUSTER_GRID;
        if request.layout.ouster_grid()
            && (params.sensor.beams > rows || params.sensor.columns > columns)
        {
            // Each beam is a row of the OS1-64's grid and each column one of its firings.
            bail!(
                "--layout {}: the scans are {rows} x {columns} Ouster grids: at most {rows} \
                 --beams and {columns} --columns (fewer leave rows and columns without returns)",
                serde_json::to_value(request.layout)?
                    .as_str()
                    .unwrap_or("?")
            );
        }
    }
    if request.format == Format::Pcap && request.sensor.is_none() {
        bail!(
            "--format pcap needs --sensor: a sensor whose packets the simulator writes (see \
             simulate --help)"
        );
    }
    let ros = matches!(request.format, Format::Bag | Format::Mcap | Format::Db3);
    match (request.messages, request.sensor) {
        (Messages::Points, _) => {}
        (_, _) if !ros => bail!("--messages is for --format bag, mcap or db3"),
        (Messages::Packets, None) => bail!("--messages packets needs --sensor"),
        (Messages::Livox, Some(PacketSensor::Mid360 | PacketSensor::Avia)) => {}
        (Messages::Livox, _) => bail!("--messages livox needs --sensor mid360 or avia"),
        (Messages::Packets, Some(_)) => {}
    }
    if request.messages_per_frame == 0
        || (request.messages_per_frame > 1 && request.messages != Messages::Livox)
    {
        bail!("--messages-per-frame is at least 1, and above 1 only with --messages livox");
    }
    Ok(params)
}

/// Writes the sequence `request` asks for into `out`. `stop` is asked before every frame
/// (a signal, a deadline); `progress` hears of every frame written.
pub fn write(
    request: &Request,
    out: &Path,
    stop: &dyn Fn() -> bool,
    progress: &mut dyn FnMut(u64),
) -> Result<Written> {
    let params = params_of(request)?;
    let sim = Simulation::new(params).context("invalid simulation parameters")?;
    if request.layout != Layout::Generic {
        return write_layout(request, &sim, out, stop, progress);
    }
    let packets = request.sensor.map(|s| PacketSim::new(&sim, s));
    let last = params.frames - 1;
    let end_offset = match &packets {
        Some(p) => p.end_offset(last),
        None => sim.end_offset(last),
    };
    let route_m = sim.trajectory().arc_length(end_offset);
    // The IMU runs on a little past the last point, so the last sweep is covered.
    let imu_samples = match &request.imu {
        Some(spec) => {
            spec.validate().map_err(anyhow::Error::msg)?;
            imu::samples(&sim, spec, end_offset + 0.1)
        }
        None => Vec::new(),
    };
    let provenance = Provenance {
        generator: "kiss-odom simulate",
        version: env!("CARGO_PKG_VERSION"),
        profile: params.profile,
        seed: params.seed,
        frames: params.frames,
        start_time: params.start_time,
        lead_in: params.lead_in,
        layout: LAYOUT,
        sensor: &params.sensor,
        packets: packets
            .as_ref()
            .zip(request.sensor)
            .map(|(p, sensor)| PacketSummary {
                sensor,
                packets_per_sweep: p.packets_per_sweep(),
                pcap: request.format == Format::Pcap,
            }),
        ros_messages: matches!(request.format, Format::Bag | Format::Mcap | Format::Db3)
            .then_some(request.messages),
        imu: request.imu.map(|spec| {
            let (gyro, accel) = imu::turn_on_bias(&spec, params.seed);
            ImuSummary {
                spec,
                gyro_bias_turn_on: gyro,
                accel_bias_turn_on: accel,
                samples: imu_samples.len(),
            }
        }),
        revisit: params.revisit.zip(sim.changed()).map(|(r, c)| {
            use crate::city::changes::Change;
            RevisitSummary {
                meaning: REVISIT,
                changes: r.changes,
                lateral_offset_m: crate::revisit::lateral_offset(params.profile),
                objects: c.groups,
                moved: c.count(|c| matches!(c, Change::Moved(_))),
                turned: c.count(|c| matches!(c, Change::Turned(_))),
                removed: c.count(|c| *c == Change::Removed),
                new_walls: usize::from(c.wall),
            }
        }),
        scene: SceneSummary {
            planes: sim.scene().planes().count(),
            solids: sim.scene().solids().len(),
            route_length_m: route_m,
        },
    };
    let mut writer = DatasetWriter::create(out, request.overwrite, &provenance)?;
    if params.revisit.is_some() {
        let truth = match &packets {
            Some(p) => p.ground_truth(0),
            None => sim.ground_truth(0),
        };
        let path = writer.staging().join(crate::writer::INITIAL_POSE);
        let line = crate::writer::initial_pose_line(&truth) + "\n";
        std::fs::write(&path, line).with_context(|| format!("writing {}", path.display()))?;
    }
    if request.imu.is_some() {
        let path = writer.staging().join(imu::CSV_NAME);
        std::fs::write(&path, imu::csv(&imu_samples))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    let container = match request.format {
        Format::Bag => Some((ros::Container::Bag, ros::BAG_NAME)),
        Format::Mcap => Some((ros::Container::Mcap, ros::MCAP_NAME)),
        Format::Db3 => Some((ros::Container::Db3, ros::DB3_NAME)),
        Format::Generic | Format::Pcap => None,
    };
    let packet_file = request.format == Format::Pcap || request.messages == Messages::Packets;
    let mut pcap: Option<Box<dyn PacketSink>> = match (request.sensor, container) {
        (Some(sensor), _) if packet_file => {
            let meta = (sensor == PacketSensor::Os1)
                .then(|| {
                    let imu = request.imu.map(|spec| spec.extrinsic());
                    let meta = capture::ouster_metadata(params.sensor.rate_hz, imu.as_ref());
                    serde_json::to_string_pretty(&meta)
                })
                .transpose()?;
            if let Some(angles) = sensor.angle_file() {
                let path = writer.staging().join(capture::ANGLES_NAME);
                std::fs::write(&path, angles)
                    .with_context(|| format!("writing {}", path.display()))?;
            }
            if let Some(text) = sensor.calibration_file() {
                let path = writer.staging().join(capture::CALIBRATION_NAME);
                std::fs::write(&path, text)
                    .with_context(|| format!("writing {}", path.display()))?;
            }
            if let Some(dat) = sensor.correction_file() {
                let path = writer.staging().join(capture::CORRECTION_NAME);
                std::fs::write(&path, dat)
                    .with_context(|| format!("writing {}", path.display()))?;
            }
            let mut sink: Box<dyn PacketSink> = match container {
                Some((c, name)) => Box::new(ros::packet_bag::PacketBag::create(
                    &writer.staging().join(name),
                    c,
                    sensor,
                    params.start_time,
                    meta,
                )?),
                None => {
                    if let Some(meta) = meta {
                        let path = writer.staging().join(capture::META_NAME);
                        std::fs::write(&path, meta)
                            .with_context(|| format!("writing {}", path.display()))?;
                    }
                    let path = writer.staging().join(capture::PCAP_NAME);
                    Box::new(capture::CaptureWriter::create(
                        &path,
                        sensor,
                        params.start_time,
                    )?)
                }
            };
            // The device packet first: its decoder needs the angles it carries.
            if let Some(d) = sensor.device_packet(params.sensor.rate_hz) {
                sink.write_device(&d)?;
            }
            Some(sink)
        }
        _ => None,
    };
    let topic = match request.messages {
        Messages::Livox => ros::drivers::LIVOX,
        _ => ros::CLOUD,
    };
    let mut ros = container
        .filter(|_| !packet_file)
        .map(|(container, name)| {
            let path = writer.staging().join(name);
            ros::RosWriter::create(&path, container, &[topic], imu_samples.clone())
        })
        .transpose()?;
    let mut imu_packets = ImuPackets {
        sensor: request.sensor.filter(|_| pcap.is_some()),
        samples: &imu_samples,
        spec: request.imu,
        start_time: params.start_time,
        next: 0,
    };
    let mut points = 0usize;
    for k in 0..params.frames {
        if stop() {
            // The staging folder goes with the writer: no partial sequence is left.
            return Ok(Written::Stopped { frames: k });
        }
        let (frame, truth) = match &packets {
            Some(p) => {
                let sweep = p.sweep(k);
                if let Some(c) = pcap.as_mut() {
                    for packet in &sweep.packets {
                        imu_packets.send_until(packet.offset, c.as_mut())?;
                        c.write(packet)?;
                    }
                    c.end_sweep()?;
                }
                (sweep.frame, p.ground_truth(k))
            }
            None => (sim.frame(k), sim.ground_truth(k)),
        };
        points += frame.points.len();
        if let Some(r) = ros.as_mut() {
            if request.messages == Messages::Livox {
                let lines = if request.sensor == Some(PacketSensor::Avia) {
                    6
                } else {
                    4
                };
                let parts = request.messages_per_frame;
                for (ns, body) in ros::livox::custom_messages(r.encoding(), &frame, parts, lines)? {
                    r.write_after_imu(ns, vec![(0, ns, body)])?;
                }
            } else {
                r.write_frame(&frame)?;
            }
        }
        writer.write_frame(&frame, &truth)?;
        progress(k + 1);
    }
    // The capture ends with the last sweep's last packet, as a recording stopped there: the
    // IMU samples after it (imu.csv has them) would all reach a Livox's last frame, which ends
    // with the input.
    if let Some(c) = pcap {
        c.finish()?;
    }
    if let Some(r) = ros {
        r.finish()?;
    }
    writer.finish()?;
    Ok(Written::Complete { points, route_m })
}

/// Writes `sim` in the dataset layout `request` asks for.
fn write_layout(
    request: &Request,
    sim: &Simulation,
    out: &Path,
    stop: &dyn Fn() -> bool,
    progress: &mut dyn FnMut(u64),
) -> Result<Written> {
    let params = sim.params();
    let last = params.frames - 1;
    let route_m = sim.trajectory().arc_length(sim.end_offset(last));
    let provenance = LayoutProvenance {
        generator: "kiss-odom simulate",
        version: env!("CARGO_PKG_VERSION"),
        profile: params.profile,
        seed: params.seed,
        frames: params.frames,
        start_time: params.start_time,
        lead_in: params.lead_in,
        layout: request.layout,
        sensor: &params.sensor,
    };
    let header = "# Written by `kiss-odom simulate --layout`: the parameters that generated this \
                  dataset.\n\n";
    let toml = toml::to_string(&provenance).context("serialising sim.toml")?;
    let outcome = layouts::write(
        sim,
        request.layout,
        out,
        request.overwrite,
        &format!("{header}{toml}"),
        stop,
        progress,
    )?;
    Ok(match outcome.complete {
        true => Written::Complete {
            points: outcome.points,
            route_m,
        },
        false => Written::Stopped {
            frames: outcome.frames,
        },
    })
}

/// What a dataset layout's `sim.toml` records.
#[derive(Serialize)]
struct LayoutProvenance<'a> {
    generator: &'static str,
    version: &'static str,
    profile: Profile,
    seed: u64,
    frames: u64,
    start_time: f64,
    #[serde(skip_serializing_if = "is_zero")]
    lead_in: f64,
    layout: Layout,
    sensor: &'a Lidar,
}

/// `sim.toml` records a lead-in only when there is one.
fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// The IMU samples as the sensor's IMU packets, sent between its lidar packets in time order.
struct ImuPackets<'a> {
    /// The sensor, if a pcap is written (whether it sends IMU packets is
    /// [`PacketSensor::imu_packet`]'s to say).
    sensor: Option<PacketSensor>,
    samples: &'a [ImuSample],
    spec: Option<ImuSpec>,
    start_time: f64,
    /// The next sample to send.
    next: usize,
}

impl ImuPackets<'_> {
    /// Writes the packets of the samples read up to trajectory time `until` (s).
    fn send_until(&mut self, until: f64, capture: &mut dyn PacketSink) -> Result<()> {
        let (Some(sensor), Some(spec)) = (self.sensor, self.spec) else {
            return Ok(());
        };
        while let Some(sample) = self.samples.get(self.next) {
            // Read at its time on the frames' clock, whatever the IMU's offset stamps.
            let offset = sample.time - spec.time_offset - self.start_time;
            if offset > until {
                break;
            }
            if let Some(packet) = sensor.imu_packet(sample, offset, self.next as u64) {
                capture.write_imu(&packet)?;
            }
            self.next += 1;
        }
        Ok(())
    }
}
