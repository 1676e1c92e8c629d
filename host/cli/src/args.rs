//! Command-line options that `run`, `bench` and `crosscheck` share, as clap argument groups
//! each command flattens (`#[command(flatten)]`), and how they become [`Settings`].
//!
//! Precedence is the same everywhere: defaults, then `--config FILE`, then flags.

use anyhow::{bail, Result};
use kiss_odom_core::Capacities;
use kiss_odom_drive::settings::{DegeneracyMode, PresetName, Scalar, Settings, Storage};
use kiss_odom_io::{Format, ImuInput, OpenOptions};
use kiss_odom_io::{FrameRange, SensorKind, SensorOptions};
use std::path::{Path, PathBuf};

/// What every command that runs the pipeline takes: which frames, the pipeline's parameters and
/// how the core runs.
#[derive(Debug, Clone, clap::Args)]
pub struct CommonArgs {
    /// Which frames, how read.
    #[command(flatten, next_help_heading = "Input")]
    pub input: InputArgs,
    /// The pipeline's parameters.
    #[command(flatten, next_help_heading = "Pipeline")]
    pub pipeline: PipelineArgs,
    /// How the core runs.
    #[command(flatten, next_help_heading = "Core")]
    pub core: CoreArgs,
}

impl CommonArgs {
    /// The settings these options ask for; see [`settings`].
    pub fn settings(&self, threads: Option<usize>) -> Result<Settings> {
        settings(&self.pipeline, &self.core, threads)
    }

    /// [`InputArgs::open_options`], with the IMU samples `--imu` asks for.
    pub fn open_options(&self, scan_points: usize) -> OpenOptions {
        OpenOptions {
            imu: self
                .pipeline
                .imu
                .as_ref()
                .map_or(ImuInput::Builtin, ImuMode::input),
            ..self.input.open_options(scan_points)
        }
    }
}

/// Which frames of a dataset, and how to read them.
#[derive(Debug, Clone, clap::Args)]
pub struct InputArgs {
    /// Input format; `auto` picks KITTI only for the benchmark layout.
    #[arg(long, value_enum, default_value_t = Format::Auto)]
    pub format: Format,
    /// Frames to use, `A..B` (B excluded), `A..` or `..B`, by frame index.
    #[arg(long)]
    pub frames: Option<FrameRange>,
    /// Bag/MCAP/db3 topic (default: the only PointCloud2 topic, else the only topic of sensor
    /// packets or Livox CustomMsg).
    #[arg(long)]
    pub topic: Option<String>,
    /// Which sequence of a dataset folder that holds several, as kiss-icp's --sequence:
    /// HeLiPR's LiDAR (Ouster, Velodyne, Avia or Aeva), a nuScenes scene number (61 for
    /// scene-0061), a KITTI raw odometry sequence (00-10) [default: the only one there].
    #[arg(long)]
    pub sequence: Option<String>,
    /// How to decode a sensor recording.
    #[command(flatten)]
    pub sensor: SensorArgs,
}

/// How to decode sensor packets (a pcap recording, `live`).
#[derive(Debug, Clone, Default, clap::Args)]
pub struct SensorArgs {
    /// The sensor of a pcap recording; `auto`: Ouster if `--meta` is given, else Velodyne
    /// with the model the packets name, or Hesai or Livox if their packets are there instead.
    #[arg(long, value_enum, default_value_t = SensorKind::Auto)]
    pub sensor: SensorKind,
    /// Ouster metadata JSON (as `ouster-cli` saves it beside a recording); Ouster needs it.
    #[arg(long)]
    pub meta: Option<PathBuf>,
    /// Velodyne calibration (XML or YAML), Hesai angle correction file (CSV), Robosense
    /// angle.csv; without one, the model's published angles (the QT128, Pandar128, OT128,
    /// HDL-64E, VLS-128 and VLP-32A/B have none: they need it; a Robosense takes the
    /// recording's DIFOP packet).
    #[arg(long)]
    pub calibration: Option<PathBuf>,
    /// UDP port of the sensor's data packets [default: Velodyne and Hesai 2368, Ouster the
    /// metadata's lidar port, else 7502, Livox 56001, Robosense 6699].
    #[arg(long)]
    pub port: Option<u16>,
    /// Velodyne and Hesai: azimuth (degrees) where one sweep ends and the next begins [default: a full
    /// turn from where the recording starts].
    #[arg(long, allow_negative_numbers = true)]
    pub cut_angle: Option<f64>,
    /// Livox: seconds of points in a frame (the sensor has no sweep) [default: 0.1, the Livox
    /// ROS driver's; a bag's CustomMsg: each message a frame, with this its messages merged].
    #[arg(long)]
    pub frame_period: Option<f64>,
}

impl SensorArgs {
    /// The decoder's options.
    pub fn options(&self) -> SensorOptions {
        SensorOptions {
            sensor: self.sensor,
            port: self.port,
            meta: self.meta.clone(),
            calibration: self.calibration.clone(),
            cut_angle_deg: self.cut_angle,
            frame_period_s: self.frame_period,
        }
    }
}

impl InputArgs {
    /// The frame range (all frames when not given).
    pub fn range(&self) -> FrameRange {
        self.frames.unwrap_or_default()
    }

    /// Options for `io::open`: read at most `scan_points` points of a frame (the core's
    /// `Capacities::scan_points`, which ignores the rest anyway); the IMU samples the
    /// recording carries (a bag's IMU topic is read with [`CommonArgs::open_options`]).
    pub fn open_options(&self, scan_points: usize) -> OpenOptions {
        OpenOptions {
            topic: self.topic.clone(),
            sequence: self.sequence.clone(),
            scan_points,
            sensor: self.sensor.options(),
            imu: ImuInput::Builtin,
        }
    }
}

/// The pipeline's parameters.
#[derive(Debug, Clone, clap::Args)]
pub struct PipelineArgs {
    /// Settings file: TOML, as `run` writes to `config.toml`, or kiss-icp's YAML (a .yaml or
    /// .yml name); flags override it.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// The defaults every setting not given takes: `default` (kiss-icp 1.3.0's poses, bit for
    /// bit) or `accurate` (the lowest error measured: point-to-plane terms where the map is
    /// planar on every frame, max_range / 200 voxels, or 1.2 times those with 3 points each
    /// when the first scan has fewer than 32,768 points, a scan whose motion was not the
    /// model's deskewed again with its own, a dense scan's registration cloud thinned toward
    /// 3,000 points, both clouds in the scan's order, the vehicle and hold priors only where
    /// the scene leaves a translation free (--prior-gate 0.1); 1.1-2.6 times the time on urban
    /// and KITTI scans, 2.6-2.8 in a corridor); replaces the file's `[pipeline] preset`
    /// [default: default].
    #[arg(long, value_enum)]
    pub preset: Option<PresetName>,
    /// Maximum range r_max (m) [default: 100].
    #[arg(long, allow_negative_numbers = true)]
    pub max_range: Option<f64>,
    /// Minimum range (m) [default: 0].
    #[arg(long, allow_negative_numbers = true)]
    pub min_range: Option<f64>,
    /// Map voxel size v (m) [default: max_range / 100].
    #[arg(long, allow_negative_numbers = true)]
    pub voxel_size: Option<f64>,
    /// Deskew scans that carry per-point timestamps (the default).
    #[arg(long, overrides_with = "no_deskew")]
    pub deskew: bool,
    /// Do not deskew.
    #[arg(long, overrides_with = "deskew")]
    pub no_deskew: bool,
    /// Registration along directions the scene does not constrain: `reference` (kiss-icp) or
    /// `robust` (the reference, but frames it leaves degenerate are registered again with
    /// point-to-plane terms where the map is planar, flagged `planes`: for open ground, and
    /// with --plane-gate 1 --voxel-size 0.5 for tunnels and corridors; on a car add
    /// --lateral-prior 1, and in tunnels --prediction-prior 0.01) [default: reference].
    #[arg(long, value_enum)]
    pub degeneracy: Option<DegeneracyMode>,
    /// Robust mode registers a frame again with plane terms when the reference registration's
    /// observability is below this; 1: every frame, without the reference registration
    /// [default: 0.015].
    #[arg(long)]
    pub plane_gate: Option<f64>,
    /// Robust mode: weight per correspondence pulling a registration with plane terms to the
    /// constant-velocity prediction, so what the scene leaves free stays there [default: 0].
    #[arg(long)]
    pub prediction_prior: Option<f64>,
    /// Robust mode: weight per correspondence against sideways motion along the sensor's y
    /// axis, for a car-like vehicle with the sensor's x axis forward; in a corridor a turn
    /// then tells how far it went [default: 0].
    #[arg(long)]
    pub lateral_prior: Option<f64>,
    /// Robust mode: the two priors act only in frames whose weakest translation, measured at
    /// the prediction, is below this fraction of the strongest (frames.csv `weak_t`); 1: in
    /// every frame [default: 1].
    #[arg(long)]
    pub prior_gate: Option<f64>,
    /// ICP's work budget per frame, in the core's work units (frames.csv `work`): a frame that
    /// would spend more keeps its last complete iterate and is flagged `budget`. With the
    /// capacities it bounds a frame's time on a given target (the book's "Embedded and deadlines") [default:
    /// none, the reference's behaviour].
    #[arg(long)]
    pub budget: Option<u64>,
    /// The gyroscope prior: `auto` predicts and deskews each frame with the rotation the
    /// recording's IMU measured (a folder's imu.csv, an Ouster's or Livox's IMU packets, a bag's
    /// or MCAP file's only sensor_msgs/Imu topic; the IMU's clock must be the frames'),
    /// learning the gyroscope's bias from ICP; frames without samples fall back to the
    /// constant-velocity model and say so in frames.csv. A FILE (an existing path) is an
    /// imu.csv for any input, in place of the recording's own samples; any other value is the
    /// bag's or MCAP file's sensor_msgs/Imu TOPIC (`ros2`: the node subscribes to TOPIC, or
    /// /imu for auto; --play publishes the recording's samples there). `off`: the reference's
    /// prediction [default: off].
    #[arg(long, value_name = "auto|off|TOPIC|FILE", value_parser = ImuMode::parse)]
    pub imu: Option<ImuMode>,
    /// The IMU's pose in the LiDAR frame, X,Y,Z,ROLL,PITCH,YAW (m, deg; Rz Ry Rx), as
    /// `simulate` writes it in sim.toml [default: 0,0,0,0,0,0].
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "X,Y,Z,ROLL,PITCH,YAW",
        allow_negative_numbers = true
    )]
    pub imu_extrinsic: Option<Vec<f64>>,
    /// The IMU's clock minus the LiDAR's (s) [default: 0].
    #[arg(long, allow_negative_numbers = true)]
    pub imu_time_offset: Option<f64>,
}

/// Whether the gyroscope prior runs, and with which samples.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ImuMode {
    /// With the IMU samples the recording carries.
    Auto,
    /// Without (the reference's constant-velocity prediction).
    Off,
    /// With a bag's or MCAP file's `sensor_msgs/Imu` topic.
    Topic(String),
    /// With an `imu.csv`, for any input.
    File(PathBuf),
}

impl ImuMode {
    /// `auto`, `off`, an existing file, else a topic.
    pub fn parse(value: &str) -> Result<Self, String> {
        Ok(match value {
            "auto" => Self::Auto,
            "off" => Self::Off,
            "" => return Err("give auto, off, a topic or an imu.csv".into()),
            file if Path::new(file).is_file() => Self::File(file.into()),
            topic => Self::Topic(topic.into()),
        })
    }

    /// Where the reader takes the samples from.
    pub fn input(&self) -> ImuInput {
        match self {
            Self::Auto => ImuInput::Auto,
            Self::Off => ImuInput::Builtin,
            Self::Topic(t) => ImuInput::Topic(t.clone()),
            Self::File(f) => ImuInput::File(f.clone()),
        }
    }

    /// Refuses a topic or file where no recording is read (`live`, the ROS 2 node).
    pub fn recording_only(mode: Option<&Self>, command: &str) -> Result<()> {
        match mode {
            Some(Self::Topic(v)) => bail!("{command}: --imu takes auto or off, not a topic ({v})"),
            Some(Self::File(f)) => bail!(
                "{command}: --imu takes auto or off, not a file ({})",
                f.display()
            ),
            _ => Ok(()),
        }
    }
}

/// How the core runs.
#[derive(Debug, Clone, clap::Args)]
pub struct CoreArgs {
    /// Scalar type of the core [default: f64].
    #[arg(long, value_enum)]
    pub scalar: Option<Scalar>,
    /// Map point storage [default: exact, which agrees with the reference; quantized uses 6
    /// bytes a point].
    #[arg(long, value_enum)]
    pub storage: Option<Storage>,
    /// Fixed capacities of the core's buffers, as a board has them: they never grow, and a
    /// full map gives up its farthest voxels [default: none: sized from the configuration,
    /// growing as the run needs up to --memory-limit].
    #[arg(long, value_enum)]
    pub capacities: Option<Preset>,
    /// Bytes the core's state may grow to without --capacities (e.g. 512M, 8G; K, M, G, T are
    /// powers of 1024) [default: a quarter of the machine's memory].
    #[arg(long, value_name = "SIZE", value_parser = parse_size)]
    pub memory_limit: Option<u64>,
    /// Worker threads for the correspondence search, 0 = all cores, at most the machine's
    /// cores; results are identical for any count [default: the settings' (all cores)].
    #[arg(long)]
    pub threads: Option<usize>,
}

/// Capacity presets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Preset {
    /// `Capacities::FULL_SCALE` (KITTI-like sensors at 100 m).
    Full,
    /// `Capacities::SMALL` (microcontroller budget).
    Small,
    /// `Capacities::TINY` (a 16-beam sensor in 512 KiB); also sets the parameters it was sized
    /// for (`Config::tiny`: max range 50 m, voxel 2 m, 10 points a voxel) unless given.
    Tiny,
}

impl Preset {
    /// The capacities of the preset.
    pub fn capacities(self) -> Capacities {
        match self {
            Preset::Full => Capacities::FULL_SCALE,
            Preset::Small => Capacities::SMALL,
            Preset::Tiny => Capacities::TINY,
        }
    }
}

/// Resolves the settings: defaults, then `--config`, then the flags. A command whose thread
/// count must not follow the file (bench and crosscheck time and compare single-threaded
/// runs) gives it as `threads`, which only `--threads` overrides. The result is validated,
/// errors naming the setting at fault.
pub fn settings(p: &PipelineArgs, c: &CoreArgs, threads: Option<usize>) -> Result<Settings> {
    let mut s = from_file(p)?;
    if let Some(t) = threads {
        s.runtime.threads = t;
    }
    apply(&mut s, p, c)?;
    Ok(s)
}

/// The defaults, then `--config`.
pub fn from_file(p: &PipelineArgs) -> Result<Settings> {
    match &p.config {
        Some(path) => Settings::load_as(path, p.preset),
        None => Ok(Settings::preset(p.preset.unwrap_or_default())),
    }
}

/// The flags over `s`, then the check of the whole (errors name the setting at fault).
pub fn apply(s: &mut Settings, p: &PipelineArgs, c: &CoreArgs) -> Result<()> {
    if c.capacities == Some(Preset::Tiny) {
        let t = kiss_odom_core::Config::<f64>::tiny();
        s.data.max_range = t.max_range;
        s.mapping.voxel_size = Some(t.voxel_size);
        s.mapping.max_points_per_voxel = t.max_points_per_voxel;
    }
    if let Some(r) = p.max_range {
        s.data.max_range = r;
    }
    if let Some(r) = p.min_range {
        s.data.min_range = r;
    }
    if let Some(v) = p.voxel_size {
        s.mapping.voxel_size = Some(v);
    }
    if p.deskew {
        s.data.deskew = true;
    }
    if p.no_deskew {
        s.data.deskew = false;
    }
    if let Some(d) = p.degeneracy {
        s.registration.degeneracy = d;
    }
    if let Some(g) = p.plane_gate {
        s.registration.plane_gate = g;
    }
    if let Some(w) = p.prediction_prior {
        s.registration.prediction_prior = w;
    }
    if let Some(w) = p.lateral_prior {
        s.registration.lateral_prior = w;
    }
    if let Some(g) = p.prior_gate {
        s.registration.prior_gate = g;
    }
    if let Some(b) = p.budget {
        s.registration.work_budget = Some(b);
    }
    if let Some(m) = &p.imu {
        s.imu.enabled = *m != ImuMode::Off;
    }
    if let Some(e) = &p.imu_extrinsic {
        s.imu.extrinsic = e.as_slice().try_into().map_err(|_| {
            anyhow::anyhow!(
                "--imu-extrinsic takes 6 numbers, X,Y,Z,ROLL,PITCH,YAW, not {}",
                e.len()
            )
        })?;
    }
    if let Some(t) = p.imu_time_offset {
        s.imu.time_offset = t;
    }
    if let Some(x) = c.scalar {
        s.runtime.scalar = x;
    }
    if let Some(x) = c.storage {
        s.runtime.map_storage = x;
    }
    if let Some(preset) = c.capacities {
        s.capacities = preset.capacities().into();
    }
    if let Some(t) = c.threads {
        s.runtime.threads = t;
    }
    if let Some(m) = c.memory_limit {
        if !s.grows() {
            bail!("--memory-limit: fixed capacities never grow (leave out --capacities)");
        }
        s.runtime.memory_limit = Some(m);
    }
    s.validate()
}

/// A size in bytes: a number with an optional K, M, G or T (powers of 1024; `B`, `iB` and
/// lower case accepted).
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let t = t
        .strip_suffix("iB")
        .or_else(|| t.strip_suffix('B'))
        .unwrap_or(t);
    let (digits, shift) = match t.chars().last().map(|c| c.to_ascii_uppercase()) {
        Some('K') => (&t[..t.len() - 1], 10),
        Some('M') => (&t[..t.len() - 1], 20),
        Some('G') => (&t[..t.len() - 1], 30),
        Some('T') => (&t[..t.len() - 1], 40),
        _ => (t, 0),
    };
    let n: f64 = digits
        .trim()
        .parse()
        .map_err(|_| format!("{text}: not a size (e.g. 512M, 8G)"))?;
    let bytes = n * (1u64 << shift) as f64;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(format!("{text}: not a size of at least one byte"));
    }
    Ok(bytes as u64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Wrap {
        #[command(flatten)]
        pipeline: PipelineArgs,
        #[command(flatten)]
        core: CoreArgs,
    }

    fn resolve(argv: &[&str], threads: Option<usize>) -> Result<Settings> {
        let w = Wrap::try_parse_from(std::iter::once("x").chain(argv.iter().copied())).unwrap();
        settings(&w.pipeline, &w.core, threads)
    }

    #[test]
    fn flags_override_the_file_which_overrides_the_defaults() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("c.toml");
        std::fs::write(&file, "[data]\nmax_range = 60.0\n[runtime]\nthreads = 3\n").unwrap();
        let f = file.to_str().unwrap();
        let s = resolve(&["--config", f], None).unwrap();
        assert_eq!((s.data.max_range, s.runtime.threads), (60.0, 3));
        let s = resolve(&["--config", f], Some(1)).unwrap();
        assert_eq!(
            s.runtime.threads, 1,
            "bench and crosscheck keep their default"
        );
        let s = resolve(
            &["--config", f, "--max-range", "50", "--threads", "2"],
            None,
        )
        .unwrap();
        assert_eq!((s.data.max_range, s.runtime.threads), (50.0, 2));
        assert_eq!(parse_size("512M"), Ok(512 << 20));
        assert_eq!(parse_size("1.5GiB"), Ok(3 << 29));
        assert_eq!(parse_size("4096"), Ok(4096));
        assert!(parse_size("lots").is_err() && parse_size("0").is_err());
        let s = resolve(&["--memory-limit", "2G"], Some(1)).unwrap();
        assert_eq!(s.memory_limit(), Some(2 << 30));
        let e = resolve(&["--capacities", "small", "--memory-limit", "2G"], Some(1));
        assert!(format!("{:#}", e.unwrap_err()).contains("never grow"));
        let s = resolve(&["--no-deskew", "--capacities", "small"], Some(1)).unwrap();
        assert_eq!(s.memory_limit(), None);
        assert!(!s.data.deskew && s.runtime.threads == 1);
        assert_eq!(s.capacities, Capacities::SMALL.into());
        let s = resolve(&[], None).unwrap();
        assert_eq!(s.runtime.threads, 0, "run's default: all cores");
    }

    #[test]
    fn imu_takes_auto_off_an_existing_file_or_a_topic_and_any_but_off_turns_the_prior_on() {
        let dir = tempfile::tempdir().unwrap();
        let csv = dir.path().join("imu.csv");
        std::fs::write(&csv, "").unwrap();
        let csv_arg = csv.to_str().unwrap();
        let parse = |v: &str| {
            let w = Wrap::try_parse_from(["x", "--imu", v]).unwrap();
            w.pipeline.imu.unwrap()
        };
        assert_eq!(parse("auto"), ImuMode::Auto);
        assert_eq!(parse("off"), ImuMode::Off);
        assert_eq!(parse(csv_arg), ImuMode::File(csv.clone()));
        // A path that is not a file is a topic name.
        let missing = dir.path().join("missing.csv");
        let missing = missing.to_str().unwrap();
        assert_eq!(parse(missing), ImuMode::Topic(missing.into()));
        assert_eq!(parse("/imu").input(), ImuInput::Topic("/imu".into()));
        for (v, on) in [
            ("auto", true),
            ("off", false),
            ("/imu", true),
            (csv_arg, true),
        ] {
            assert_eq!(resolve(&["--imu", v], None).unwrap().imu.enabled, on, "{v}");
        }
        let e = ImuMode::recording_only(Some(&parse("/imu")), "live").unwrap_err();
        assert!(e.to_string().contains("not a topic (/imu)"), "{e}");
        assert!(ImuMode::recording_only(Some(&ImuMode::Auto), "live").is_ok());
    }
}
