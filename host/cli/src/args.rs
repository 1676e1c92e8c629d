//! Command-line options that `run`, `bench` and `crosscheck` share, as clap argument groups
//! each command flattens (`#[command(flatten)]`), and how they become [`Settings`].
//!
//! Precedence is the same everywhere: defaults, then `--config FILE`, then `--set`, then the
//! named flags.

use anyhow::{bail, Result};
use kiss_odom_drive::settings::{Input, PresetName, Settings};
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
    pub fn open_options(&self, scan_points: usize, input: &Input) -> OpenOptions {
        OpenOptions {
            imu: self
                .pipeline
                .imu
                .as_ref()
                .map_or(ImuInput::Builtin, ImuMode::input),
            ..self.input.open_options(scan_points, input)
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
    /// The sensor of a pcap recording; `auto`: Ouster if `--calibration` is its metadata
    /// JSON, else Velodyne with the model the packets name, or Hesai or Livox if their packets
    /// are there instead.
    #[arg(long, value_enum, default_value_t = SensorKind::Auto)]
    pub sensor: SensorKind,
    /// The sensor's own file: Ouster metadata JSON (as `ouster-cli` saves it beside a
    /// recording; an Ouster needs it), Velodyne calibration (XML or YAML), Hesai angle
    /// correction file (CSV; AT128: .dat), Robosense angle.csv; without one, the model's
    /// published angles (the QT128, Pandar128, OT128, HDL-64E, VLS-128 and VLP-32A/B have
    /// none: they need it; a Robosense takes the recording's DIFOP packet).
    #[arg(long)]
    pub calibration: Option<PathBuf>,
}

impl SensorArgs {
    /// The decoder's options, with the settings' `[input]` (port, sweep cut, frame period);
    /// `--calibration` is the Ouster metadata under `--sensor ouster`, or under `auto` when it
    /// is a JSON file ([`is_json`]), else the other sensors' calibration.
    pub fn options(&self, input: &Input) -> SensorOptions {
        let ouster = |file: &PathBuf| match self.sensor {
            SensorKind::Ouster => true,
            SensorKind::Auto => is_json(file),
            _ => false,
        };
        let (meta, calibration) = match &self.calibration {
            Some(file) if ouster(file) => (Some(file.clone()), None),
            file => (None, file.clone()),
        };
        SensorOptions {
            sensor: self.sensor,
            port: input.port,
            meta,
            calibration,
            cut_angle_deg: input.cut_angle,
            frame_period_s: input.frame_period,
        }
    }
}

/// Whether `file` is a JSON document, as an Ouster's metadata is and no other sensor's
/// calibration (XML, YAML, CSV or the AT128's binary .dat): a `.json` name (read or not, the
/// Ouster reader then names its fault), else a first non-blank byte `{`.
pub fn is_json(file: &Path) -> bool {
    use std::io::Read;
    if file
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
    {
        return true;
    }
    let mut head = [0; 256];
    std::fs::File::open(file)
        .and_then(|mut f| f.read(&mut head))
        .is_ok_and(|n| {
            head[..n]
                .iter()
                .find(|b| !b.is_ascii_whitespace())
                .is_some_and(|b| *b == b'{')
        })
}

impl InputArgs {
    /// The frame range (all frames when not given).
    pub fn range(&self) -> FrameRange {
        self.frames.unwrap_or_default()
    }

    /// Options for `io::open`: read at most `scan_points` points of a frame (the core's
    /// `Capacities::scan_points`, which ignores the rest anyway); the IMU samples the
    /// recording carries (a bag's IMU topic is read with [`CommonArgs::open_options`]); the
    /// settings' `[input]` for sensor packets.
    pub fn open_options(&self, scan_points: usize, input: &Input) -> OpenOptions {
        OpenOptions {
            topic: self.topic.clone(),
            sequence: self.sequence.clone(),
            scan_points,
            sensor: self.sensor.options(input),
            imu: ImuInput::Builtin,
        }
    }
}

/// The pipeline's parameters: the few a user reaches for by name, every other setting by its
/// key in the settings file (`--set`).
#[derive(Debug, Clone, clap::Args)]
pub struct PipelineArgs {
    /// Settings file: TOML, as `run` writes to `config.toml`, or kiss-icp's YAML (a .yaml or
    /// .yml name).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Any setting by its key in the settings file, e.g. `registration.degeneracy=robust`,
    /// `capacities=small` (the book's configuration reference lists every key); repeatable,
    /// over --config, under the named flags.
    #[arg(long, value_name = "SECTION.KEY=VALUE")]
    pub set: Vec<String>,
    /// The defaults of every setting not given: `default` (kiss-icp 1.3.0's poses, bit for bit)
    /// or `accurate` (lower error at one to three times the time) [default: default].
    #[arg(long, value_enum)]
    pub preset: Option<PresetName>,
    /// Maximum range r_max (m); the map's voxel follows it unless `mapping.voxel_size` is set
    /// [default: 100].
    #[arg(long, allow_negative_numbers = true)]
    pub max_range: Option<f64>,
    /// The gyroscope prior: `auto` (the recording's IMU), an imu.csv FILE, a bag's IMU TOPIC,
    /// or `off`, the reference's constant-velocity prediction (the book's "Fast motion")
    /// [default: off].
    #[arg(long, value_name = "auto|off|TOPIC|FILE", value_parser = ImuMode::parse)]
    pub imu: Option<ImuMode>,
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
    /// Worker threads for the correspondence search, 0 = all cores, at most the machine's
    /// cores; results are identical for any count [default: the settings' (all cores)].
    #[arg(long)]
    pub threads: Option<usize>,
}

/// Resolves the settings: defaults, then `--config`, then `--set`, then the flags. A command whose thread
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

/// `--set`, then the named flags over `s`, then the check of the whole (errors name the
/// setting at fault).
pub fn apply(s: &mut Settings, p: &PipelineArgs, c: &CoreArgs) -> Result<()> {
    *s = s.with_set(&p.set)?;
    if let Some(r) = p.max_range {
        s.data.max_range = r;
    }
    if let Some(m) = &p.imu {
        s.imu.enabled = *m != ImuMode::Off;
    }
    if let Some(t) = c.threads {
        s.runtime.threads = t;
    }
    if s.runtime.memory_limit.is_some() && !s.grows() {
        bail!("runtime.memory_limit: fixed capacities never grow (leave out the capacities)");
    }
    s.validate()
}

/// The settings the pipeline and core options `argv` resolve to, `threads` as a command gives
/// it (the unit tests' parser).
#[cfg(test)]
pub(crate) fn resolve(argv: &[&str], threads: Option<usize>) -> Result<Settings> {
    use clap::Parser;
    #[derive(Parser)]
    struct Wrap {
        #[command(flatten)]
        pipeline: PipelineArgs,
        #[command(flatten)]
        core: CoreArgs,
    }
    let w = Wrap::try_parse_from(std::iter::once("x").chain(argv.iter().copied())).unwrap();
    settings(&w.pipeline, &w.core, threads)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::{CommandFactory, Parser};

    #[derive(Parser)]
    struct Wrap {
        #[command(flatten)]
        pipeline: PipelineArgs,
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
        let s = resolve(
            &[
                "--config",
                f,
                "--set",
                "data.max_range=40",
                "--set",
                "runtime.threads=4",
            ],
            None,
        )
        .unwrap();
        assert_eq!(
            (s.data.max_range, s.runtime.threads),
            (40.0, 4),
            "--set over the file"
        );
        let s = resolve(&["--set", "data.max_range=40", "--max-range", "30"], None).unwrap();
        assert_eq!(s.data.max_range, 30.0, "the named flag over --set");
        let s = resolve(&["--set", "runtime.memory_limit=2G"], Some(1)).unwrap();
        assert_eq!(s.memory_limit(), Some(2 << 30));
        let e = resolve(
            &[
                "--set",
                "capacities=small",
                "--set",
                "runtime.memory_limit=2G",
            ],
            Some(1),
        );
        assert!(format!("{:#}", e.unwrap_err()).contains("never grow"));
        let s = resolve(
            &["--set", "data.deskew=false", "--set", "capacities=small"],
            Some(1),
        )
        .unwrap();
        assert_eq!(s.memory_limit(), None);
        assert!(!s.data.deskew && s.runtime.threads == 1);
        assert_eq!(s.capacities, kiss_odom_core::Capacities::SMALL.into());
        let e = resolve(&["--set", "registration.plane_gat=1"], None).unwrap_err();
        assert!(format!("{e:#}").contains("plane_gat"), "{e:#}");
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

    #[test]
    fn calibration_is_the_ouster_metadata_when_it_is_json_or_the_sensor_is_ouster() {
        #[derive(Parser)]
        struct Sensor {
            #[command(flatten)]
            sensor: SensorArgs,
        }
        let dir = tempfile::tempdir().unwrap();
        let file = |name: &str, text: &str| {
            let path = dir.path().join(name);
            std::fs::write(&path, text).unwrap();
            path.to_str().unwrap().to_string()
        };
        let json = file("os.txt", " \n\t{\"sensor_info\": {}}");
        let yaml = file("vlp32.yaml", "lasers:\n- {laser_id: 0}\n");
        let xml = file("hdl64.xml", "<?xml version=\"1.0\"?>");
        let csv = file("angle.csv", "Laser id,Elevation,Azimuth\n");
        let dat = file("at128.dat", "\u{ee}\u{ff}");
        let missing = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
        let (missing_json, missing_csv) = (missing("os.json"), missing("angle.csv"));
        let empty_json = file("empty.json", "");
        let is_meta = |argv: &[&str]| {
            let s =
                Sensor::try_parse_from(std::iter::once("x").chain(argv.iter().copied())).unwrap();
            let o = s.sensor.options(&Input::default());
            assert_ne!(o.meta.is_some(), o.calibration.is_some(), "{argv:?}");
            o.meta.is_some()
        };
        for (argv, meta) in [
            (vec!["--calibration", &json], true),
            (vec!["--calibration", &missing_json], true),
            (vec!["--calibration", &empty_json], true),
            (vec!["--calibration", &yaml], false),
            (vec!["--calibration", &xml], false),
            (vec!["--calibration", &csv], false),
            (vec!["--calibration", &dat], false),
            (vec!["--calibration", &missing_csv], false),
            (vec!["--sensor", "ouster", "--calibration", &csv], true),
            (vec!["--sensor", "vlp32ab", "--calibration", &json], false),
        ] {
            assert_eq!(is_meta(&argv), meta, "{argv:?}");
        }
        let none = Sensor::try_parse_from(["x"])
            .unwrap()
            .sensor
            .options(&Input::default());
        assert!(none.meta.is_none() && none.calibration.is_none());
        let command = Sensor::command();
        let names: Vec<_> = command
            .get_arguments()
            .filter_map(|a| a.get_long())
            .collect();
        assert_eq!(
            names,
            ["sensor", "calibration"],
            "one option for the sensor's file"
        );
    }
}
