//! `kiss-odom ros2`: the odometry as a ROS 2 node speaking DDS directly, with nothing to
//! install or source, and a player that publishes recordings as ROS 2 clouds.
//!
//! It sits beside `run`: where `run` reads frames from files, the node reads
//! `sensor_msgs/PointCloud2` from the wire ([`node`]) and publishes odometry, `/tf` and the
//! local map; [`play`] goes the other way, from the file readers to the wire. [`msg`] holds the
//! ROS 2 message layouts, [`dds`] the participant, QoS and discovery, [`params`] the parameter
//! file, `engine` the adapter to the host frame driver, and [`watch`] what a caller in the
//! same process can see of a running node.

pub mod dds;
pub(crate) mod engine;
pub mod imu;
pub mod msg;
pub mod node;
pub mod params;
pub mod play;
pub mod watch;

use crate::args::{CoreArgs, ImuMode, PipelineArgs};
use anyhow::Result;
use kiss_odom_drive::settings::Settings;
use kiss_odom_io::{Format, ImuInput};
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

/// `kiss-odom ros2` arguments. Without `--play`, runs the node until Ctrl-C. Parameters:
/// defaults, then `--config` (as `run`'s), then `--params` (ROS 2 YAML), then flags.
#[derive(Debug, clap::Args)]
pub struct Ros2Args {
    /// Cloud topic (node: subscribe; --play: publish).
    #[arg(long)]
    pub(crate) points: Option<String>,
    /// Odometry topic.
    #[arg(long)]
    pub(crate) odom: Option<String>,
    /// ROS 2 parameter file (`node_name: ros__parameters: {...}`).
    #[arg(long)]
    pub params: Option<PathBuf>,
    /// Node name looked up in the parameter file.
    #[arg(long, default_value = params::NODE_NAME)]
    pub(crate) node_name: String,
    /// DDS domain (default: $ROS_DOMAIN_ID, else 0).
    #[arg(long)]
    pub domain: Option<u16>,
    /// Moving frame (default: the cloud's frame_id).
    #[arg(long)]
    pub base_frame: Option<String>,
    /// Odometry frame.
    #[arg(long)]
    pub(crate) odom_frame: Option<String>,
    /// Do not publish `/tf`.
    #[arg(long)]
    pub(crate) no_tf: bool,
    /// Publish the local map (every `local_map_period` seconds).
    #[arg(long)]
    pub(crate) local_map: bool,
    /// Localize each cloud in this prior map (`map_file`): the base's pose in the map frame on
    /// `map_pose_topic`, `map -> odometry frame` on /tf.
    #[arg(long, requires = "initial_pose")]
    pub(crate) map: Option<PathBuf>,
    /// With --map: the sensor's pose in the map frame at the first cloud, X,Y,Z,ROLL,PITCH,YAW
    /// (metres, degrees; `initial_pose`).
    #[arg(long, requires = "map", allow_hyphen_values = true)]
    pub(crate) initial_pose: Option<String>,
    /// Also write each published pose as a KITTI line to this file.
    #[arg(long)]
    pub poses: Option<PathBuf>,
    /// Take a cloud at most once per this many seconds (0: as they come); the others are
    /// latest-only.
    #[arg(long, default_value_t = 0.0, value_parser = non_negative)]
    pub min_period: f64,
    /// Publish this recording's clouds instead of running the node (.mcap, .bag or a folder).
    #[arg(long)]
    pub play: Option<PathBuf>,
    /// --play: speed factor.
    #[arg(long, default_value_t = 1.0)]
    pub(crate) rate: f64,
    /// --play: input format.
    #[arg(long, value_enum, default_value_t = Format::Auto)]
    pub(crate) format: Format,
    /// --play: topic inside the bag or MCAP (default: its only cloud topic).
    #[arg(long)]
    pub(crate) topic: Option<String>,
    /// --play: frame_id of the published clouds.
    #[arg(long, default_value = "lidar")]
    pub frame_id: String,
    /// --play: seconds between frames that carry no time.
    #[arg(long, default_value_t = 0.1)]
    pub(crate) period: f64,
    /// --play: seconds to wait for a subscriber before the first cloud (and, with
    /// --lockstep, for each cloud's odometry).
    #[arg(long, default_value_t = 10.0)]
    pub(crate) wait: f64,
    /// --play: publish each cloud only once the node's odometry for the one before came (on
    /// --odom), so that no cloud is dropped whatever the node's speed; the pace is the node's.
    #[arg(long)]
    pub lockstep: bool,
    /// The node's pipeline parameters, as `run`'s.
    #[command(flatten, next_help_heading = "Pipeline")]
    pub(crate) pipeline: PipelineArgs,
    /// How the node's core runs, as `run`'s.
    #[command(flatten, next_help_heading = "Core")]
    pub(crate) core: CoreArgs,
}

fn non_negative(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && (0.0..=3600.0).contains(&v) => Ok(v),
        _ => Err(format!(
            "`{s}` is not a number of seconds between 0 and 3600"
        )),
    }
}

/// Set by Ctrl-C or SIGTERM; every loop of the node and the player looks at it.
static STOP: AtomicBool = AtomicBool::new(false);

/// Runs `kiss-odom ros2`.
pub(crate) fn execute(args: &Ros2Args, err: &mut dyn Write) -> Result<i32> {
    // Ctrl-C, SIGTERM and SIGHUP end the node cleanly, even where the shell had SIGINT
    // ignored (background jobs). One handler per process: a second install keeps the first.
    let _ = ctrlc::set_handler(|| STOP.store(true, Ordering::SeqCst));
    STOP.store(false, Ordering::SeqCst);
    let domain = args.domain.unwrap_or_else(dds::default_domain);
    let mut out = std::io::stdout();
    if let Some(opts) = play_options(args) {
        play::run(&opts, &STOP, &mut out, err)?;
        return Ok(0);
    }
    let (settings, params) = resolve(args)?;
    let opts = node::NodeOptions {
        settings,
        params,
        domain,
        poses: args.poses.clone(),
        min_period: std::time::Duration::from_secs_f64(args.min_period),
        imu_topic: Some(imu_topic(args.pipeline.imu.as_ref())?),
        watch: Default::default(),
    };
    node::run(&opts, &STOP, &mut out, err)?;
    Ok(0)
}

/// What `--play` plays and how, from the arguments (`None` without `--play`).
pub fn play_options(args: &Ros2Args) -> Option<play::PlayOptions> {
    let path = args.play.as_ref()?;
    Some(play::PlayOptions {
        path: path.clone(),
        format: args.format,
        source_topic: args.topic.clone(),
        points_topic: args.points.clone().unwrap_or_else(|| "/points".into()),
        frame_id: args.frame_id.clone(),
        rate: args.rate,
        period: args.period,
        wait: args.wait,
        lockstep: args
            .lockstep
            .then(|| args.odom.clone().unwrap_or_else(|| "/kiss/odometry".into())),
        domain: args.domain.unwrap_or_else(dds::default_domain),
        imu: match &args.pipeline.imu {
            None | Some(ImuMode::Auto) => Some((ImuInput::Auto, DEFAULT_IMU_TOPIC.to_string())),
            Some(ImuMode::Off) => None,
            Some(ImuMode::Topic(t)) => Some((ImuInput::Topic(t.clone()), t.clone())),
            Some(ImuMode::File(f)) => {
                Some((ImuInput::File(f.clone()), DEFAULT_IMU_TOPIC.to_string()))
            }
        },
    })
}

/// The IMU topic the node reads when the gyroscope prior is on: `--imu TOPIC`, else `/imu`.
/// A file is refused: the node has no recording to pair it with.
pub fn imu_topic(mode: Option<&ImuMode>) -> Result<String> {
    match mode {
        Some(ImuMode::Topic(t)) => Ok(t.clone()),
        Some(ImuMode::File(f)) => anyhow::bail!(
            "ros2: --imu takes auto, off or a topic, not a file ({})",
            f.display()
        ),
        _ => Ok(DEFAULT_IMU_TOPIC.into()),
    }
}

/// The IMU topic of `--imu auto`, for the node and the player.
pub(crate) const DEFAULT_IMU_TOPIC: &str = "/imu";

/// Settings and node parameters from the defaults, `--config`, `--params` and the flags.
pub(crate) fn resolve(args: &Ros2Args) -> Result<(Settings, params::NodeParams)> {
    imu_topic(args.pipeline.imu.as_ref())?;
    let mut settings = crate::args::from_file(&args.pipeline)?;
    let mut p = params::NodeParams::default();
    if let Some(path) = &args.params {
        params::load_yaml(path, &args.node_name, &mut settings, &mut p)?;
    }
    if let Some(t) = &args.points {
        p.points_topic = t.clone();
    }
    if let Some(t) = &args.odom {
        p.odom_topic = t.clone();
    }
    if let Some(f) = &args.base_frame {
        p.base_frame = f.clone();
    }
    if let Some(f) = &args.odom_frame {
        p.lidar_odom_frame = f.clone();
    }
    if args.no_tf {
        p.publish_odom_tf = false;
    }
    if args.local_map {
        p.publish_local_map = true;
    }
    if let (Some(m), Some(pose)) = (&args.map, &args.initial_pose) {
        p.map_file = m.to_string_lossy().into_owned();
        p.initial_pose = pose.clone();
    }
    crate::args::apply(&mut settings, &args.pipeline, &args.core)?;
    p.validate()?;
    Ok((settings, p))
}
