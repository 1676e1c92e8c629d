//! `kiss-odom simulate`: a ray-cast spinning LiDAR with exact ground truth.
//!
//! It sits upstream of everything else: it writes sequences in the generic layout that `run`
//! reads, for tests, fuzzing, benchmarks, the deskew study and degenerate-geometry stress tests.
//! A seeded scene ([`city`], built from [`shapes`] and indexed by [`scene`]) is swept by a
//! multi-beam sensor ([`sensor`]) riding a smooth parametric trajectory ([`trajectory`]). Each
//! column is cast from the pose at its own capture time, so scans carry real motion distortion;
//! ground truth is the same pose function at each sweep's end ([`writer`] writes both). Every
//! random draw is keyed by indices ([`rng`]), so the bytes depend on the seed and parameters
//! only, never on the thread count.

pub mod capture;
pub mod city;
pub mod packets;
pub mod rng;
pub mod scene;
pub mod sensor;
pub mod shapes;
pub mod trajectory;
pub mod writer;

pub use packets::{PacketSensor, PacketSim};
pub use scene::{Scene, Surface};
pub use sensor::{Frame, Lidar};
pub use trajectory::{PoseM, Trajectory};

use anyhow::{bail, Context, Result};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// Scene and motion of a simulated sequence.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Profile {
    /// City streets and side streets (buildings, parked cars, poles, trees, kerb clutter),
    /// driven from a standing start at 5-15 m/s with car-like turns.
    Urban,
    /// An endless featureless tunnel along x, driven at 3-8 m/s: degenerate along its axis.
    Corridor,
    /// The urban scene at 20-30 m/s (after a 3 s launch) with turns near 1 rad/s: strong
    /// motion distortion.
    Fast,
    /// A lone ground plane, driven like urban: degenerate in x, y and yaw.
    Plane,
    /// The corridor with sparse structure on its walls (pillars, door frames, cabinets every
    /// 10-40 m): observable along the axis, but weakly, as a real tunnel is.
    Tunnel,
    /// The lone ground plane with sparse objects (poles, trees, boulders 20-60 m apart along
    /// the route): observable in x, y and yaw, but weakly, as an open field is.
    Field,
    /// Long suburban streets at 55-65 km/h with gentle turns, houses in rows out to 100 m on
    /// both sides, yards, hedges, trees and lamp posts: a 16-beam sensor's map fills its whole
    /// `r_max` disc (use with `--sensor vlp16`).
    Suburban,
}

/// What `simulate` writes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// The generic layout only.
    #[default]
    Generic,
    /// The generic layout (exact points) and the same sweeps as the sensor's packets in
    /// `packets.pcap` (needs --sensor; an Ouster's metadata goes to `packets.json`).
    Pcap,
}

/// Most frames one run may ask for (a longer route means a larger scene in memory).
pub const MAX_FRAMES: u64 = 100_000;

/// Everything that determines a simulated sequence.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SimParams {
    /// Scene and motion.
    pub profile: Profile,
    /// Seed of scene, route, motion and noise.
    pub seed: u64,
    /// Sweeps.
    pub frames: u64,
    /// Sequence time of the first column (s).
    pub start_time: f64,
    /// The sensor.
    pub sensor: Lidar,
}

impl SimParams {
    /// `frames` sweeps of `profile` under `seed` with the default sensor.
    pub fn new(profile: Profile, seed: u64, frames: u64) -> Self {
        Self {
            profile,
            seed,
            frames,
            start_time: 0.0,
            sensor: Lidar::DEFAULT,
        }
    }

    /// Checks every parameter; the message names the one at fault.
    pub fn validate(&self) -> Result<()> {
        if self.frames == 0 || self.frames > MAX_FRAMES {
            bail!("frames must be in 1..={MAX_FRAMES}");
        }
        if self.seed > i64::MAX as u64 {
            bail!("seed must be at most {}", i64::MAX);
        }
        if !self.start_time.is_finite() || self.start_time.abs() > 1e9 {
            bail!("start-time must be finite and within 1e9 s");
        }
        self.sensor.validate().map_err(anyhow::Error::msg)
    }
}

/// A scene, a trajectory through it and a sensor: generates frames on demand.
#[derive(Clone, Debug)]
pub struct Simulation {
    params: SimParams,
    trajectory: Trajectory,
    scene: Scene,
    sweeper: sensor::Sweeper,
    first_end: PoseM,
}

impl Simulation {
    /// Builds the scene and trajectory of validated `params`.
    pub fn new(params: SimParams) -> Result<Self> {
        params.validate()?;
        let l = params.sensor;
        let duration = (params.frames + 1) as f64 * l.period();
        let trajectory = Trajectory::generate(params.profile, params.seed, duration);
        let scene = city::build(params.profile, params.seed, trajectory.route());
        let sweeper = sensor::Sweeper::new(l, params.seed, params.start_time);
        let first_end = trajectory.pose(sweeper.end_offset(0));
        Ok(Self {
            params,
            trajectory,
            scene,
            sweeper,
            first_end,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &SimParams {
        &self.params
    }

    /// The scene (world frame).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The trajectory (trajectory time: seconds since the first column).
    pub fn trajectory(&self) -> &Trajectory {
        &self.trajectory
    }

    /// Ray casts frame `k`.
    pub fn frame(&self, k: u64) -> Frame {
        self.sweeper.frame(k, &self.trajectory, &self.scene)
    }

    /// Sequence time of frame `k`'s end (its last column).
    pub fn end_time(&self, k: u64) -> f64 {
        self.sweeper.sequence_time(self.sweeper.end_offset(k))
    }

    /// World-from-sensor pose at sequence time `t`.
    pub fn world_pose(&self, t: f64) -> PoseM {
        self.trajectory.pose(t - self.params.start_time)
    }

    /// World pose of the first sweep's end: the ground-truth frame's origin.
    pub fn ground_truth_origin(&self) -> PoseM {
        self.first_end
    }

    /// Ground truth of frame `k`: the sensor at the end of sweep `k` in the frame of the sensor
    /// at the end of sweep 0 (so frame 0 is the identity).
    pub fn ground_truth(&self, k: u64) -> PoseM {
        if k == 0 {
            // Exactly, rather than `T^-1 T` up to rounding.
            return PoseM::identity();
        }
        let end = self.trajectory.pose(self.sweeper.end_offset(k));
        self.first_end.inverse() * end
    }
}

/// `kiss-odom simulate` arguments.
#[derive(Debug, clap::Args)]
pub struct SimulateArgs {
    /// Output folder; gets velodyne/ (sensor frame at each point's capture time),
    /// timestamps/, poses.txt (the pose at each sweep's end, i.e. its last column, relative to
    /// the first), times.txt and sim.toml.
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
    /// A real sensor's beams, firing timing and packets instead of the generic sensor (whose
    /// --beams, --columns and --fov-* flags are then ignored); --rate-hz is rounded to the
    /// sensor's (a whole number of packets per turn; 10 or 20 Hz for the OS1).
    #[arg(long, value_enum)]
    pub sensor: Option<PacketSensor>,
    /// What to write.
    #[arg(long, value_enum, default_value_t = Format::Generic)]
    pub format: Format,
    /// Replace a dataset already in --out (removes only its frame files, poses, times and
    /// sim.toml). The new one appears only once complete.
    #[arg(long)]
    pub overwrite: bool,
}

impl SimulateArgs {
    /// The simulation parameters these flags ask for (not yet validated).
    pub fn params(&self) -> SimParams {
        let rate_hz = match self.sensor {
            // An invalid rate stays as given and fails validation or `rate_hz` later.
            Some(s) => s.rate_hz(self.rate_hz).unwrap_or(self.rate_hz),
            None => self.rate_hz,
        };
        SimParams {
            profile: self.profile,
            seed: self.seed,
            frames: self.frames,
            start_time: self.start_time,
            sensor: Lidar {
                beams: self.beams,
                columns: self.columns,
                fov_up_deg: self.fov_up,
                fov_down_deg: self.fov_down,
                rate_hz,
                min_range: self.min_range,
                max_range: self.max_range,
                noise: self.noise,
                dropout: self.dropout,
            },
        }
    }
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
    /// What the files mean, for a reader without this source at hand.
    layout: &'static str,
    sensor: &'a Lidar,
    #[serde(skip_serializing_if = "Option::is_none")]
    packets: Option<PacketSummary>,
    scene: SceneSummary,
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

/// Runs `kiss-odom simulate`.
pub fn execute(args: &SimulateArgs) -> Result<i32> {
    let params = args.params();
    let clock = Instant::now();
    if let Some(s) = args.sensor {
        s.rate_hz(args.rate_hz).map_err(anyhow::Error::msg)?;
    }
    if args.format == Format::Pcap && args.sensor.is_none() {
        bail!("--format pcap needs --sensor (vlp16, vlp32c or os1-64)");
    }
    let sim = Simulation::new(params).context("invalid simulation parameters")?;
    let packets = args.sensor.map(|s| PacketSim::new(&sim, s));
    let last = params.frames - 1;
    let end_offset = match &packets {
        Some(p) => p.end_offset(last),
        None => sim.sweeper.end_offset(last),
    };
    let end = sim.trajectory.arc_length(end_offset);
    let provenance = Provenance {
        generator: "kiss-odom simulate",
        version: env!("CARGO_PKG_VERSION"),
        profile: params.profile,
        seed: params.seed,
        frames: params.frames,
        start_time: params.start_time,
        layout: "velodyne/NNNNNN.bin: f32 LE x y z intensity, sensor frame at capture time; \
                 timestamps/NNNNNN.bin: f64 LE capture time (s) per point; poses.txt: 3x4 \
                 sensor pose at the end of each sweep (its last column) in the frame of the \
                 first sweep's end; times.txt: end-of-sweep times (s); packets.pcap (if \
                 written): the same sweeps as the sensor's UDP packets, exact points above \
                 before range quantisation, in decoder order; packets.json: Ouster metadata",
        sensor: &params.sensor,
        packets: packets
            .as_ref()
            .zip(args.sensor)
            .map(|(p, sensor)| PacketSummary {
                sensor,
                packets_per_sweep: p.packets_per_sweep(),
                pcap: args.format == Format::Pcap,
            }),
        scene: SceneSummary {
            planes: sim.scene.planes().count(),
            solids: sim.scene.solids().len(),
            route_length_m: end,
        },
    };
    let mut out = writer::DatasetWriter::create(&args.out, args.overwrite, &provenance)?;
    let mut capture = match (args.format, args.sensor) {
        (Format::Pcap, Some(sensor)) => {
            if sensor == PacketSensor::Os1 {
                let path = out.staging().join(capture::META_NAME);
                let meta =
                    serde_json::to_string_pretty(&capture::ouster_metadata(params.sensor.rate_hz))?;
                std::fs::write(&path, meta)
                    .with_context(|| format!("writing {}", path.display()))?;
            }
            let path = out.staging().join(capture::PCAP_NAME);
            Some(capture::CaptureWriter::create(
                &path,
                sensor,
                params.start_time,
            )?)
        }
        _ => None,
    };
    let bar = indicatif::ProgressBar::new(params.frames);
    bar.set_style(
        indicatif::ProgressStyle::with_template("simulate {bar:40} {pos}/{len} frames, eta {eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut points = 0usize;
    for k in 0..params.frames {
        if let Some(sig) = crate::interrupt::requested() {
            bar.finish_and_clear();
            drop(out); // the staging folder goes: no partial data set is left
            eprintln!(
                "interrupted by signal {sig} after {k} frames: no data set written to {}",
                args.out.display()
            );
            return Ok(crate::interrupt::exit_status(sig));
        }
        let (frame, truth) = match &packets {
            Some(p) => {
                let sweep = p.sweep(k);
                if let Some(c) = capture.as_mut() {
                    for packet in &sweep.packets {
                        c.write(packet)?;
                    }
                }
                (sweep.frame, p.ground_truth(k))
            }
            None => (sim.frame(k), sim.ground_truth(k)),
        };
        points += frame.points.len();
        out.write_frame(&frame, &truth)?;
        bar.inc(1);
    }
    if let Some(c) = capture {
        c.finish()?;
    }
    out.finish()?;
    bar.finish_and_clear();
    let secs = clock.elapsed().as_secs_f64();
    println!(
        "simulate: {} {:?} frames ({:.0} points each, {:.0} m driven) in {:.1} s ({:.1} frames/s) -> {}",
        params.frames,
        params.profile,
        points as f64 / params.frames as f64,
        end,
        secs,
        params.frames as f64 / secs.max(1e-9),
        args.out.display()
    );
    Ok(0)
}
