//! `kiss-odom simulate`: a LiDAR sequence with exact ground truth, ray cast by
//! `kiss-odom-sim` and written in the generic layout (and as sensor packets or a ROS
//! recording).

use anyhow::Result;
use kiss_odom_sim::{
    Format, ImuSpec, Layout, Lidar, Messages, PacketSensor, Profile, Request, Revisit, SimParams,
    Written,
};
use std::path::PathBuf;
use std::time::Instant;

/// `kiss-odom simulate` arguments.
#[derive(Debug, clap::Args)]
pub struct SimulateArgs {
    /// Output folder; gets velodyne/ (sensor frame at each point's capture time),
    /// timestamps/, poses.txt (the pose at each sweep's end, i.e. its last column, relative to
    /// the first; with --revisit, to the first run's first), times.txt and sim.toml (and with
    /// --revisit initial_pose.txt).
    #[arg(long)]
    pub out: PathBuf,
    /// Number of sweeps to generate.
    #[arg(long, default_value_t = 100)]
    pub frames: u64,
    /// Seed of the scene, route, motion and noise (0 to 2^63-1): the same seed and flags give
    /// the same bytes.
    #[arg(long, default_value_t = 0,
          value_parser = clap::value_parser!(u64).range(..=i64::MAX as u64))]
    pub seed: u64,
    /// Scene and motion.
    #[arg(long, value_enum, default_value_t = Profile::Urban)]
    pub profile: Profile,
    /// Sweeps per second (Hz).
    #[arg(long, default_value_t = Lidar::DEFAULT.rate_hz)]
    pub rate_hz: f64,
    /// Laser beams (rows), evenly spread from --fov-down to --fov-up.
    #[arg(long, default_value_t = Lidar::DEFAULT.beams)]
    pub beams: u32,
    /// Columns (firings) per sweep, at uniform times and azimuths.
    #[arg(long, default_value_t = Lidar::DEFAULT.columns)]
    pub columns: u32,
    /// Elevation of the highest beam (degrees).
    #[arg(long, default_value_t = Lidar::DEFAULT.fov_up_deg, allow_negative_numbers = true)]
    pub fov_up: f64,
    /// Elevation of the lowest beam (degrees).
    #[arg(long, default_value_t = Lidar::DEFAULT.fov_down_deg, allow_negative_numbers = true)]
    pub fov_down: f64,
    /// Returns closer than this are dropped (m).
    #[arg(long, default_value_t = Lidar::DEFAULT.min_range)]
    pub min_range: f64,
    /// No return beyond this range (m).
    #[arg(long, default_value_t = Lidar::DEFAULT.max_range)]
    pub max_range: f64,
    /// Standard deviation of the Gaussian range noise (m); 0 gives exact ranges.
    #[arg(long, default_value_t = Lidar::DEFAULT.noise)]
    pub noise: f64,
    /// Probability that any return is lost, in [0, 1).
    #[arg(long, default_value_t = Lidar::DEFAULT.dropout)]
    pub dropout: f64,
    /// Sequence time of the first point (s); every timestamp is offset by it.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub start_time: f64,
    /// Start this many seconds into the drive (0 to 600): the same route and motion, entered
    /// moving rather than from the standing start (e.g. 8 s puts the urban profile under seed 0
    /// in its first turn).
    #[arg(long, default_value_t = 0.0)]
    pub lead_in: f64,
    /// A real sensor's beams, firing timing and packets instead of the generic sensor (whose
    /// --beams, --columns and --fov-* flags are then ignored); --rate-hz is rounded to the
    /// sensor's (a whole number of packets per turn; 10 or 20 Hz for the OS1, 5, 10 or 20 Hz
    /// for the XT32, 10 Hz for the QT128 and OT128, whose angle file goes beside the pcap as
    /// packets.csv for --calibration; the Livox sensors, mid360 and avia, cut frames by time:
    /// read back a rate other than 10 Hz with --frame-period 1/rate).
    #[arg(long, value_enum)]
    pub sensor: Option<PacketSensor>,
    /// What to write.
    #[arg(long, value_enum, default_value_t = Format::Generic)]
    pub format: Format,
    /// What a ROS recording (--format bag, mcap or db3) carries.
    #[arg(long, value_enum, default_value_t = Messages::Points)]
    pub messages: Messages,
    /// With --messages livox: the Livox driver's messages per frame (its publish_freq times
    /// the frame period; read the recording back with --frame-period to merge them).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..))]
    pub messages_per_frame: u16,
    /// Write a public dataset's own layout instead, with its ground truth in that dataset's
    /// convention (read it back with `run --format` of the same name; mulran and ncd store
    /// whole 64 x 1024 Ouster scans, so take at most 64 --beams and 1024 --columns, fewer
    /// leaving rows and columns empty; helipr writes all four of its LiDARs, chosen with `run
    /// --sequence`).
    #[arg(long, value_enum, default_value_t = Layout::Generic)]
    pub layout: Layout,
    /// Also write imu.csv: a MEMS IMU riding with the sensor, sampled at this rate (Hz, e.g.
    /// 200), with white noise, turn-on biases that then walk, and gravity, 11, 23 and -44 mm
    /// from the LiDAR with its axes (as the Mid-360's); sim.toml records all of it. With
    /// --format bag, mcap or db3, the samples are also in the recording as sensor_msgs/Imu on
    /// /imu; with --format pcap (or --messages packets) and --sensor os1-64 or mid360, in the
    /// packets as the sensor's own IMU packets.
    #[arg(long)]
    pub imu_rate: Option<f64>,
    /// With --imu-rate: the exact rates and forces, without noise or bias.
    #[arg(long, requires = "imu_rate")]
    pub imu_exact: bool,
    /// Replace the data set an earlier `simulate` wrote in --out: the files and folders its
    /// sim.toml lists go once the new one is complete. A folder holding anything else of those
    /// names (a data set simulate did not write, a file in velodyne/ that is not a frame) is
    /// refused, and nothing is removed.
    #[arg(long)]
    pub overwrite: bool,
    /// Drive the scene of the same flags without --revisit (the first run) again: the same
    /// route the other way, 1.75 m to its left (0.5 m in a warehouse, 1 m in a corridor or
    /// tunnel), from where the first run's last sweep ended back towards its start at 60-95 %
    /// of its mean speed, through the scene changed (--changes). poses.txt is in the first run's
    /// frame, so a map built from the first run's poses.txt is in the frame of this one's;
    /// initial_pose.txt holds frame 0's pose as X,Y,Z,ROLL,PITCH,YAW (m, degrees, R = Rz(yaw)
    /// Ry(pitch) Rx(roll)).
    #[arg(long)]
    pub revisit: bool,
    /// With --revisit: the share of the scene's objects (parked cars first, then buildings,
    /// walls, racks, poles, trees) moved 2-6 m along their axis, turned by 10-30 degrees or
    /// removed, in 0..=1 (default 0.1). Whatever the share, at least 10 % of the parked cars
    /// change and a new wall 10 m long and 3 m high stands beside the revisit's stretch.
    #[arg(long, value_name = "FRACTION", requires = "revisit")]
    pub changes: Option<f64>,
}

impl SimulateArgs {
    /// The sequence these flags ask for (not yet validated; a packet sensor rounds the rate).
    pub fn request(&self) -> Request {
        Request {
            params: self.params(),
            sensor: self.sensor,
            format: self.format,
            messages: self.messages,
            messages_per_frame: usize::from(self.messages_per_frame),
            layout: self.layout,
            imu: self.imu_rate.map(|rate| {
                let spec = ImuSpec::mems(rate);
                if self.imu_exact {
                    spec.exact()
                } else {
                    spec
                }
            }),
            overwrite: self.overwrite,
        }
    }

    fn params(&self) -> SimParams {
        SimParams {
            profile: self.profile,
            seed: self.seed,
            frames: self.frames,
            start_time: self.start_time,
            lead_in: self.lead_in,
            sensor: Lidar {
                beams: self.beams,
                columns: self.columns,
                fov_up_deg: self.fov_up,
                fov_down_deg: self.fov_down,
                rate_hz: self.rate_hz,
                min_range: self.min_range,
                max_range: self.max_range,
                noise: self.noise,
                dropout: self.dropout,
            },
            revisit: self.revisit.then(|| Revisit {
                changes: self
                    .changes
                    .unwrap_or(kiss_odom_sim::revisit::DEFAULT_CHANGES),
            }),
        }
    }
}

/// Runs `kiss-odom simulate`.
pub fn execute(args: &SimulateArgs) -> Result<i32> {
    let request = args.request();
    let frames = request.params.frames;
    let clock = Instant::now();
    let bar = indicatif::ProgressBar::new(frames);
    bar.set_style(
        indicatif::ProgressStyle::with_template("simulate {bar:40} {pos}/{len} frames, eta {eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let stop = || crate::interrupt::requested().is_some();
    let written = kiss_odom_sim::write(&request, &args.out, &stop, &mut |k| bar.set_position(k));
    bar.finish_and_clear();
    match written? {
        Written::Stopped { frames } => {
            let sig = crate::interrupt::requested().unwrap_or(2);
            eprintln!(
                "interrupted by signal {sig} after {frames} frames: no data set written to {}",
                args.out.display()
            );
            Ok(crate::interrupt::exit_status(sig))
        }
        Written::Complete { points, route_m } => {
            let secs = clock.elapsed().as_secs_f64();
            println!(
                "simulate: {} {:?} frames ({:.0} points each, {:.0} m driven) in {:.1} s ({:.1} frames/s) -> {}",
                frames,
                request.params.profile,
                points as f64 / frames as f64,
                route_m,
                secs,
                frames as f64 / secs.max(1e-9),
                args.out.display()
            );
            Ok(0)
        }
    }
}
