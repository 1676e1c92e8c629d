//! The vocabulary every reader shares: frames, what a source yields, formats and options.
//!
//! Every input format is a [`FrameSource`]: a stream of scans read one at a time, so a long
//! recording never has to fit in memory, and no frame costs more than the scan capacity
//! ([`OpenOptions::scan_points`]) whatever its file says. A frame's [`Frame::index`] is its
//! identity in the dataset (the number in its file name, its place in time order), so ground
//! truth and times pair with it whatever was lost before it.
//!
//! What the layer finds is reported through three channels the run loop prints, counts and
//! turns into exit 1 under `output.strict`: [`DatasetInfo::warnings`] for the dataset as a whole
//! (ignored files, side files of the wrong length, a recording out of time order), a
//! [`Frame::warnings`] entry for a frame used despite a problem, and [`Item::Skipped`] for a
//! frame that cannot be used (missing, truncated, garbage). Names that cannot be told apart
//! are refused when the dataset is opened; damage to a container (a bag or MCAP file cut in
//! the middle) ends the stream with an error after the frames before it.

use anyhow::Result;
use kiss_odom_sensors::SweepStats;
use nalgebra::Isometry3;
use std::path::PathBuf;

/// One scan as read from disk, in the sensor frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    /// The frame's identity: the number in its file name, or its place in time order (name
    /// times, bag and MCAP messages), 0-based, counting skipped frames. Row `index` of the
    /// ground truth and of `times.txt` belongs to it.
    pub index: usize,
    /// Where it came from: a file path, or `file:topic@stamp` for bags and MCAP files.
    pub name: String,
    /// Points in metres, sensor frame.
    pub points: Vec<[f64; 3]>,
    /// Per-point capture times in any unit and offset (one per point), if the format has them.
    pub stamps: Option<Vec<f64>>,
    /// Acquisition time of the frame in seconds, if known.
    pub time: Option<f64>,
    /// Problems that did not stop the frame from being used (e.g. timestamps ignored).
    pub warnings: Vec<String>,
    /// Per-point intensity (reflectivity), where the reader keeps it (sensor recordings).
    pub intensity: Option<Vec<f32>>,
    /// For a sweep decoded from sensor packets: its packet statistics and time span.
    pub sweep: Option<SweepInfo>,
    /// IMU samples that arrived with the frame (sensor captures whose sensor sends them, a
    /// folder's `imu.csv`, a bag's or MCAP file's `sensor_msgs/Imu` topic, `--imu FILE`), in
    /// time order; every sample of a recording is in exactly one frame.
    pub imu: Vec<ImuSample>,
    /// The sweep's end on the sensor's clock (s) where the reader knows it and the points'
    /// times do not tell it: a bag's or MCAP file's cloud whose point times are offsets, not
    /// seconds on its header's clock, ends at its header stamp.
    pub end: Option<f64>,
}

impl Frame {
    /// The instant the sweep ends on the sensor's clock, which its IMU shares (s): a decoded
    /// sweep's last point, else what the reader knows ([`Frame::end`]), else its latest point's
    /// time, else its time. The gyroscope prior integrates to it and IMU samples are handed
    /// on with the frame up to it.
    pub fn sweep_end(&self) -> Option<f64> {
        self.sweep
            .as_ref()
            .map(|s| s.end_s)
            .or(self.end)
            .or_else(|| {
                let stamps = self.stamps.as_deref()?;
                stamps.iter().copied().reduce(f64::max)
            })
            .or(self.time)
    }
}

/// One IMU sample, as the readers hand it on with a frame ([`Frame::imu`]). Built from a
/// sensor's units and written to `imu.csv` by [`crate::imu`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImuSample {
    /// Sensor-clock time, ns.
    pub time_ns: u64,
    /// Angular rate, rad/s.
    pub gyro: [f64; 3],
    /// Specific force, m/s^2.
    pub accel: [f64; 3],
}

impl ImuSample {
    /// Its time in seconds.
    pub fn seconds(&self) -> f64 {
        self.time_ns as f64 * 1e-9
    }
}

/// What a source yields.
#[derive(Clone, Debug, PartialEq)]
pub enum Item {
    /// A usable frame.
    Frame(Frame),
    /// A frame that could not be read; `reason` names the file and what was wrong.
    Skipped {
        /// The frame's identity (see [`Frame::index`]).
        index: usize,
        /// Where it was expected: a file path, or `file:topic@time`.
        name: String,
        /// Its time in seconds, if known without reading it.
        time: Option<f64>,
        /// One-line reason, naming the file.
        reason: String,
    },
}

impl Item {
    /// The frame's identity.
    pub fn index(&self) -> usize {
        match self {
            Item::Frame(f) => f.index,
            Item::Skipped { index, .. } => *index,
        }
    }

    /// The frame's time in seconds, if known.
    pub fn time(&self) -> Option<f64> {
        match self {
            Item::Frame(f) => f.time,
            Item::Skipped { time, .. } => *time,
        }
    }
}

/// What a source found that none of its items carries (a sensor recording's refusals after
/// its last sweep, a second sender), asked for once after the last item.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trailer {
    /// Warnings naming the source: to print, count and, under `output.strict`, refuse.
    pub warnings: Vec<String>,
    /// Sensor packets refused or lost after the last sweep, and those of an open sweep at the
    /// end that was not made a frame (`packets`), for the packet totals.
    pub packets: Option<SweepStats>,
}

/// A stream of scans.
pub trait FrameSource {
    /// Number of frames if known in advance.
    fn len_hint(&self) -> Option<usize>;
    /// The next frame, `Ok(None)` at the end, or `Err` when the container is damaged and
    /// nothing after this point can be trusted.
    fn next_item(&mut self) -> Result<Option<Item>>;
    /// Positions the stream so that the next item has index `index`, if the format can seek;
    /// returns false otherwise (the caller then reads and drops frames).
    fn seek(&mut self, _index: usize) -> bool {
        false
    }
    /// What the stream found that none of its items carried; ask once it has ended (or
    /// stopped being read). Empty for most formats.
    fn trailer(&mut self) -> Trailer {
        Trailer::default()
    }
}

/// Input formats (`--format`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// KITTI if the folder has the benchmark layout, otherwise the generic layout.
    Auto,
    /// KITTI odometry benchmark layout (`sequences/XX`).
    Kitti,
    /// Generic layout with `.bin` frames.
    Bin,
    /// Generic layout with `.ply` frames.
    Ply,
    /// Generic layout with `.pcd` frames.
    Pcd,
    /// ROS 1 bag with `sensor_msgs/PointCloud2` (or sensor packets, Livox `CustomMsg`).
    Bag,
    /// ROS 2 MCAP with `sensor_msgs/msg/PointCloud2`.
    Mcap,
    /// ROS 2 bag in sqlite3 storage: a folder of `metadata.yaml` and `.db3` files, or one
    /// `.db3` file.
    Db3,
    /// pcap or pcapng capture of Velodyne or Ouster packets (`--sensor`, `--calibration`,
    /// `input.port`).
    Pcap,
    /// MulRan sequence (`Ouster/`, `global_pose.csv`).
    Mulran,
    /// NCLT date folder (`velodyne_sync/`, `../ground_truth/`).
    Nclt,
    /// Newer College sequence (`raw_format/ouster_scan/`, `ground_truth/`).
    Ncd,
    /// HeLiPR sequence (`LiDAR/<sensor>/`, `LiDAR_GT/`); the sensor is `--sequence`.
    Helipr,
    /// Boreas sequence (`lidar/`, `applanix/`).
    Boreas,
    /// nuScenes data root (`v1.0-mini/`); the scene is `--sequence`.
    Nuscenes,
    /// Apollo-SouthBay sequence (`pcds/`, `poses/`).
    Apollo,
    /// KITTI raw data root (`2011_10_03/...`); the odometry sequence is `--sequence`.
    #[serde(rename = "kitti-raw")]
    KittiRaw,
}

/// Everything known about a dataset besides its frames.
#[derive(Clone, Debug, Default)]
pub struct DatasetInfo {
    /// Ground truth in the LiDAR frame, row `i` for frame `i` (see [`Frame::index`]).
    pub ground_truth: Option<Vec<Isometry3<f64>>>,
    /// Where the ground truth came from.
    pub ground_truth_path: Option<PathBuf>,
    /// Frame times in seconds (`times.txt`), row `i` for frame `i`, if present.
    pub frame_times: Option<Vec<f64>>,
    /// The format actually used (never `Auto`).
    pub format: Option<Format>,
    /// Whether the reference's KITTI vertical-angle correction is applied to every scan.
    pub kitti_correction: bool,
    /// Findings about the dataset as a whole, one line each, naming the file: to print, count
    /// and, under `output.strict`, refuse.
    pub warnings: Vec<String>,
}

impl DatasetInfo {
    /// Ground truth of the frames `indices`, re-based to the first of them that has one;
    /// `None` for a frame without ground truth.
    pub fn ground_truth_for(&self, indices: &[usize]) -> Vec<Option<Isometry3<f64>>> {
        let Some(all) = &self.ground_truth else {
            return vec![None; indices.len()];
        };
        let rows: Vec<Option<Isometry3<f64>>> =
            indices.iter().map(|&i| all.get(i).copied()).collect();
        let Some(first) = rows.iter().flatten().next().map(Isometry3::inverse) else {
            return rows;
        };
        rows.into_iter().map(|p| p.map(|p| first * p)).collect()
    }
}

/// An opened dataset: its frames and what else is known about it.
pub struct Dataset {
    /// The frames.
    pub frames: Box<dyn FrameSource>,
    /// Ground truth, times, format.
    pub info: DatasetInfo,
}

/// Options that affect how a dataset is opened.
#[derive(Clone, Debug)]
pub struct OpenOptions {
    /// Topic to read from a bag or MCAP file (default: the only point-cloud topic).
    pub topic: Option<String>,
    /// Most points read from one frame (the core's `Capacities::scan_points`, which ignores
    /// the rest anyway); a larger frame is truncated with a warning.
    pub scan_points: usize,
    /// How to decode a sensor recording (pcap).
    pub sensor: SensorOptions,
    /// Where the frames' IMU samples come from.
    pub imu: ImuInput,
    /// Which sequence of a dataset folder that holds several (`--sequence`): HeLiPR's sensor,
    /// a nuScenes scene number, a KITTI raw odometry sequence.
    pub sequence: Option<String>,
}

/// Where the frames' IMU samples come from (`--imu`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum ImuInput {
    /// What the format carries anyway: a folder's `imu.csv`, a sensor's IMU packets; a bag's
    /// or MCAP file's IMU topics are not read.
    #[default]
    Builtin,
    /// Also a bag's or MCAP file's only `sensor_msgs/Imu` topic, if it has exactly one.
    Auto,
    /// This `sensor_msgs/Imu` topic of a bag or MCAP file; an error for other inputs.
    Topic(String),
    /// This `imu.csv`, for any input, instead of what the recording carries.
    File(PathBuf),
}

impl Default for OpenOptions {
    fn default() -> Self {
        Self {
            topic: None,
            imu: ImuInput::Builtin,
            sequence: None,
            sensor: SensorOptions::default(),
            scan_points: kiss_odom_core::Capacities::FULL_SCALE.scan_points,
        }
    }
}

/// What a frame decoded from sensor packets carries besides its points: the sweep's packet
/// statistics (for `frames.csv`), the sensor-clock instants of its first and last point (the
/// instants a pose can refer to, `output.pose_time`) and when its last packet was captured.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SweepInfo {
    /// Packet statistics.
    pub stats: SweepStats,
    /// Sensor-clock time of the sweep's first point, s.
    pub start_s: f64,
    /// Sensor-clock time of the sweep's last point, s.
    pub end_s: f64,
    /// Capture (host) time of the last packet that gave the sweep points, ns since the Unix
    /// epoch.
    pub last_capture_ns: u64,
}

/// Which sensor a recording is from (`--sensor`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum SensorKind {
    /// Ouster if `--calibration` is its metadata JSON, otherwise Velodyne with the model from
    /// the packets.
    #[default]
    Auto,
    /// Velodyne VLP-16 / Puck.
    Vlp16,
    /// Velodyne VLP-16 Hi-Res.
    PuckHiRes,
    /// Velodyne VLP-32C.
    Vlp32c,
    /// Velodyne HDL-32E.
    Hdl32e,
    /// Velodyne VLP-32A or VLP-32B (needs its calibration file, --calibration).
    Vlp32ab,
    /// Velodyne HDL-64E S2 (needs its calibration file, --calibration).
    Hdl64eS2,
    /// Velodyne HDL-64E S3 (needs its calibration file, --calibration).
    Hdl64eS3,
    /// Velodyne VLS-128 / Alpha Prime (needs its calibration file, --calibration).
    Vls128,
    /// Ouster (needs its metadata JSON, --calibration).
    Ouster,
    /// Hesai PandarXT-32.
    Xt32,
    /// Hesai PandarXT-16 (nominal angles built in; --calibration for the unit's own).
    Xt16,
    /// Hesai PandarXT32M (needs its angle correction file, --calibration).
    Xt32m,
    /// Hesai Pandar40P (needs its angle correction file, --calibration).
    Pandar40p,
    /// Hesai Pandar64 (needs its angle correction file, --calibration).
    Pandar64,
    /// Hesai PandarQT64 (needs its angle correction file, --calibration).
    Qt64,
    /// Hesai PandarAT128 (needs its angle correction file, the .dat, --calibration).
    At128,
    /// Hesai PandarQT128 (needs its angle correction file, --calibration).
    Qt128,
    /// Hesai Pandar128 (needs its angle correction file, --calibration).
    Pandar128,
    /// Hesai OT128 (needs its angle correction file, --calibration).
    Ot128,
    /// Robosense RS-LiDAR-16 (angles from the recording's DIFOP packets or --calibration).
    Rs16,
    /// Robosense RS-LiDAR-32 (angles from the recording's DIFOP packets or --calibration).
    Rs32,
    /// Robosense RS-Bpearl (angles from the recording's DIFOP packets or --calibration).
    Bpearl,
    /// Robosense RS-Helios 5515 (angles from the recording's DIFOP packets or --calibration).
    Helios,
    /// Robosense RS-Helios-16P (angles from the recording's DIFOP packets or --calibration).
    Helios16p,
    /// Robosense RS-Ruby / RS-LiDAR-128 (angles from the recording's DIFOP packets or
    /// --calibration).
    Ruby,
    /// Robosense RS-Airy, 96-channel mode (angles from the recording's DIFOP packets or
    /// --calibration).
    Airy,
    /// Robosense RS-M1 (MEMS; every point carries its direction).
    M1,
    /// Robosense E1R (solid state; every point carries its direction).
    E1r,
    /// Livox Horizon, Tele-15 or Avia (SDK 1; 240,000 firings a second).
    Livox,
    /// Livox Mid-40 or Mid-70 (SDK 1; 100,000 firings a second).
    Mid40,
    /// Livox Mid-360 or HAP (SDK 2; each packet states its points' interval).
    #[cfg_attr(feature = "clap", value(alias = "hap"))]
    Mid360,
}

/// How to read a recording.
#[derive(Clone, Debug, Default)]
pub struct SensorOptions {
    /// The sensor.
    pub sensor: SensorKind,
    /// UDP port (default: 2368 for Velodyne, the metadata's or 7502 for Ouster).
    pub port: Option<u16>,
    /// Ouster metadata JSON.
    pub meta: Option<PathBuf>,
    /// Velodyne calibration (XML or YAML), Hesai angle correction (CSV; AT128: .dat), or
    /// Robosense angle.csv.
    pub calibration: Option<PathBuf>,
    /// Livox frame period, seconds (default 0.1).
    pub frame_period_s: Option<f64>,
    /// Velodyne and Hesai cut angle, degrees (default: a full turn from wherever the last sweep ended).
    pub cut_angle_deg: Option<f64>,
}
