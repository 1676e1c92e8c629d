//! What `run` writes: `poses_kitti.txt`, `poses_tum.txt`, `frames.csv` (one typed row per
//! frame, one 0/1 column per status flag), `summary.json`, `config.toml`, `trajectory.png` and
//! `diagnostics.png`, each atomically (see [`kiss_odom_io::write`]); `summary.json`, last,
//! records the digest of each of the others, by which a later run knows them for its own
//! ([`kiss_odom_io::write::outputs`]).

use super::options::RunArgs;
use super::record::{FlagColumns, FrameRow, PacketTotals, Record, RowKind};
use crate::stats::percentile;
use anyhow::Result;
use kiss_odom_drive::settings::Settings;
use kiss_odom_drive::Driver;
use kiss_odom_io as io;
use kiss_odom_io::write::outputs::{Digests, Outputs};
use nalgebra::Isometry3;
use serde::Serialize;
use std::collections::BTreeMap;

/// Every file `run` writes, the stale ones removed before it starts.
pub const OUTPUTS: [&str; 7] = [
    "poses_kitti.txt",
    "poses_tum.txt",
    "frames.csv",
    "summary.json",
    "config.toml",
    "trajectory.png",
    "diagnostics.png",
];

/// Latency statistics (ms).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Latency {
    /// Median.
    pub p50: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Worst frame.
    pub max: f64,
}

impl Latency {
    /// The statistics of `v`, `None` when it is empty.
    pub fn of(mut v: Vec<f64>) -> Option<Self> {
        v.sort_by(f64::total_cmp);
        Some(Self {
            p50: percentile(&v, 50.0),
            p99: percentile(&v, 99.0),
            max: *v.last()?,
        })
    }
}

/// `summary.json`.
#[derive(Debug, Serialize)]
pub struct Summary {
    /// Frames written (registered, empty and skipped).
    pub frames: usize,
    /// Frames the core registered.
    pub registered_frames: usize,
    /// Seconds spent in the core's frame calls (file reading excluded).
    pub odometry_s: f64,
    /// Registered frames per second of core time.
    pub hz: f64,
    /// Per-frame core latency.
    pub latency_ms: Latency,
    /// Peak resident memory of the process (bytes), if the OS tells.
    pub peak_rss_bytes: Option<u64>,
    /// Bytes of the core's state at the end.
    pub state_bytes: usize,
    /// What the core's state used: bytes at the start, at the end and at the peak, the moves
    /// into larger storage, the limit growth stops at (`None`: fixed capacities) and the frame
    /// that reached it.
    pub state: StateSummary,
    /// Frames that could not be read (their pose is the constant-velocity prediction).
    pub skipped_frames: usize,
    /// Frames with no usable point (their pose is the prediction).
    pub empty_frames: usize,
    /// Registered frames by status flag (a frame counts once for each of its flags).
    pub degraded_frames: BTreeMap<&'static str, usize>,
    /// Largest buffer occupancy against capacity.
    pub high_water: serde_json::Value,
    /// The map the run ended on: `voxel_size` and `max_points_per_voxel`.
    pub map: serde_json::Value,
    /// The smallest radius the local map had after a frame, and the first frame that had it:
    /// `max_range` and no frame while the map never filled.
    pub map_radius: MapRadius,
    /// Warnings printed.
    pub warnings: usize,
    /// With `--imu` other than `off`: frames predicted without the gyroscope prior because
    /// the IMU consistency check found it disagreeing with ICP.
    pub imu_rejected_frames: Option<u64>,
    /// Sensor packets over the run's sweeps (a pcap recording or `live`).
    pub packets: Option<PacketTotals>,
    /// `live`: time from a sweep's last packet to its pose (ms).
    pub pose_latency_ms: Option<Latency>,
    /// With `--map`: frames by localization state and the localizer's state bytes.
    pub localization: Option<LocalizationSummary>,
    /// Whether SIGINT or SIGTERM stopped the run (the outputs hold the frames before it).
    pub interrupted: bool,
    /// Why the run stopped early, if an error stopped it.
    pub stop_reason: Option<String>,
    /// Input path, format and settings summary.
    pub input: serde_json::Value,
    /// Metrics against ground truth, when it exists.
    pub metrics: Option<serde_json::Value>,
    /// The other files this run wrote in the output folder and the SHA-256 of each: what a
    /// later command replaces as an earlier one's.
    pub outputs: Digests,
}

/// `summary.json`'s `localization`: see [`Summary::localization`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LocalizationSummary {
    /// Frames localized.
    pub localized: usize,
    /// Frames degraded.
    pub degraded: usize,
    /// Frames lost.
    pub lost: usize,
    /// Bytes of the localizer's state (ICP's work and the held tiles' keys; the map is read in
    /// place).
    pub state_bytes: usize,
    /// The most tiles of the prior map held at once.
    pub held_tiles: u32,
    /// The most points of the prior map within reach at once (read in place, never copied).
    pub held_points: u32,
    /// The localizer's bytes on a board (f32, the run's registration cloud capacity), whatever
    /// the map's size: to size firmware from.
    pub board_bytes: usize,
}

impl LocalizationSummary {
    fn of(record: &Record) -> Option<Self> {
        let rows = &record.rows;
        let count = |name: &str| rows.iter().filter(|r| r.localization == Some(name)).count();
        Some(Self {
            localized: count("localized"),
            degraded: count("degraded"),
            lost: count("lost"),
            state_bytes: record.localizer_bytes?,
            held_tiles: record.prior_held.0,
            held_points: record.prior_held.1,
            board_bytes: record.localizer_board_bytes?,
        })
    }
}

/// `summary.json`'s `state`: see [`Summary::state`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct StateSummary {
    /// Bytes at the start.
    pub start_bytes: usize,
    /// Bytes at the end.
    pub end_bytes: usize,
    /// The most bytes held.
    pub peak_bytes: usize,
    /// Moves into larger storage.
    pub moves: u64,
    /// The limit growth stops at; `None` for fixed capacities.
    pub limit_bytes: Option<u64>,
    /// The frame (its index) at which growth reached the limit, if it did.
    pub limit_reached_at: Option<usize>,
}

impl StateSummary {
    fn of(m: &kiss_odom_drive::StateMemory) -> Self {
        Self {
            start_bytes: m.start_bytes,
            end_bytes: m.bytes,
            peak_bytes: m.peak_bytes,
            moves: m.moves,
            limit_bytes: m.limit,
            limit_reached_at: m.capped_at,
        }
    }
}

/// The smallest radius of the local map over a run (`summary.json`'s `map_radius`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MapRadius {
    /// The smallest radius after a frame (m).
    pub smallest_m: f64,
    /// The first frame (its index) whose map had it; `None` when the radius never shrank.
    pub frame: Option<usize>,
}

impl MapRadius {
    /// The smallest `map_radius` of `rows`, for a run at `max_range`.
    fn of(rows: &[FrameRow], max_range: f64) -> Self {
        let mut least = Self {
            smallest_m: max_range,
            frame: None,
        };
        for r in rows {
            if let Some(m) = r.map_radius.filter(|&m| m < least.smallest_m) {
                least = Self {
                    smallest_m: m,
                    frame: Some(r.index),
                };
            }
        }
        least
    }
}

/// Everything the outputs are made of.
pub(super) struct Run<'a> {
    pub args: &'a RunArgs,
    pub settings: &'a Settings,
    pub info: &'a io::DatasetInfo,
    pub driver: &'a Driver,
    pub record: &'a Record,
    pub interrupted: Option<i32>,
    pub stop: Option<String>,
}

impl Run<'_> {
    /// Writes the outputs: `config.toml` and `summary.json` always, `frames.csv` when a frame
    /// was read (its header comes with the first row), the pose files and the plot when a
    /// frame was registered. An output that cannot be written (a full disk) does not keep the
    /// others from being tried: `summary.json`, last, then says which failed in `stop_reason`
    /// (if nothing else stopped the run), and the first such error is returned.
    pub fn write(&self) -> Result<Summary> {
        let mut out = Outputs::new(&self.args.run.out);
        let o = self.record;
        let mut failed: Option<anyhow::Error> = None;
        let mut attempt = |r: Result<()>| {
            if let Err(e) = r {
                failed.get_or_insert(e);
            }
        };
        attempt(
            self.settings
                .to_toml()
                .and_then(|t| out.write("config.toml", t.as_bytes())),
        );
        if !o.rows.is_empty() {
            attempt(out.write_with("frames.csv", |w| {
                let mut csv = csv::Writer::from_writer(w);
                for row in &o.rows {
                    csv.serialize((row, FlagColumns(row.status)))?;
                }
                csv.flush()?;
                Ok(())
            }));
        }
        let rows = self.info.ground_truth_for(&o.indices);
        let metrics = match self.metrics(&rows) {
            Ok(m) => m,
            Err(e) => {
                attempt(Err(e));
                None
            }
        };
        if o.registered() > 0 {
            attempt(self.write_poses(&mut out));
            let title = self
                .args
                .path
                .file_name()
                .map_or_else(|| "trajectory".into(), |n| n.to_string_lossy().into_owned());
            let gt = self.in_estimate_frame(&rows);
            let paired: Vec<Isometry3<f64>> = gt.iter().flatten().copied().collect();
            let paired = (!paired.is_empty()).then_some(paired.as_slice());
            attempt(out.write_via_path("trajectory.png", |p| {
                crate::plot::trajectory_png(p, &o.poses, paired, &title)
            }));
            let diagnostics = self.diagnostics(&gt);
            attempt(out.write_via_path("diagnostics.png", |p| {
                crate::plot::diagnostics_png(p, &diagnostics, &title)
            }));
        }
        let mut summary = self.summary(metrics.filter(|_| o.registered() > 0));
        if let (None, Some(e)) = (&summary.stop_reason, &failed) {
            summary.stop_reason = Some(format!(
                "outputs incomplete: {}",
                kiss_odom_drive::one_line(e)
            ));
        }
        summary.outputs = out.record().clone();
        let written = out.write_summary(&summary);
        match failed {
            Some(e) => Err(e),
            None => written.map(|()| summary),
        }
    }

    fn write_poses(&self, out: &mut Outputs) -> Result<()> {
        let o = self.record;
        let kitti = io::poses::format_kitti(&o.poses);
        out.write("poses_kitti.txt", kitti.as_bytes())?;
        // TUM needs a time per pose: the frames' own if every frame has one, else the frame
        // number for all (as the reference does without times), never a mix.
        let seconds = self.tum_seconds();
        let timed: Vec<io::poses::TimedPose> = o
            .times
            .iter()
            .zip(&o.indices)
            .zip(&o.poses)
            .map(|((t, &i), &pose)| io::poses::TimedPose {
                time: t.filter(|_| seconds).unwrap_or(i as f64),
                pose,
            })
            .collect();
        let tum = format!(
            "# {}\n{}",
            self.pose_instant(),
            io::poses::format_tum(&timed)
        );
        out.write("poses_tum.txt", tum.as_bytes())
    }

    /// The instant each pose refers to, for the TUM file's header.
    fn pose_instant(&self) -> String {
        let deskewed = self.record.rows.iter().any(|r| r.deskewed);
        let times = if !self.tum_seconds() {
            "frame numbers"
        } else if self.record.sweeps {
            "sensor clock, s"
        } else {
            "the frames' times, s"
        };
        if deskewed {
            format!(
                "time x y z qx qy qz qw: the sensor at the {} of each sweep (output.pose_time); \
                 times: {times}",
                self.settings.output.pose_time.name()
            )
        } else {
            format!(
                "time x y z qx qy qz qw: scans not deskewed, each pose is of its scan as a \
                 whole; times: {times}"
            )
        }
    }

    /// Whether the TUM file's times are seconds (every frame has a time) or frame numbers.
    fn tum_seconds(&self) -> bool {
        self.record.times.iter().all(Option::is_some)
    }

    /// The frames' ground truth `rows` (re-based to the first frame that has one) in the
    /// estimate's frame: placed at the estimate of that frame, for the plots.
    fn in_estimate_frame(&self, rows: &[Option<Isometry3<f64>>]) -> Vec<Option<Isometry3<f64>>> {
        let origin = rows
            .iter()
            .position(Option::is_some)
            .map_or_else(Isometry3::identity, |first| self.record.poses[first]);
        rows.iter().map(|g| g.map(|g| origin * g)).collect()
    }

    /// Metrics over the frames that have ground truth `rows` (the dataset layer warned about
    /// the others), both trajectories re-based to the first of them.
    fn metrics(&self, rows: &[Option<Isometry3<f64>>]) -> Result<Option<serde_json::Value>> {
        let o = self.record;
        let paired: Vec<usize> = (0..rows.len()).filter(|&k| rows[k].is_some()).collect();
        let Some(&first) = paired.first() else {
            return Ok(None);
        };
        let gt: Vec<Isometry3<f64>> = rows.iter().flatten().copied().collect();
        let base = o.poses[first].inverse();
        let est: Vec<Isometry3<f64>> = paired
            .iter()
            .map(|&k| {
                if first == 0 {
                    o.poses[k]
                } else {
                    base * o.poses[k]
                }
            })
            .collect();
        Ok(Some(serde_json::to_value(
            kiss_odom_io::metrics::evaluate(&est, &gt)?,
        )?))
    }

    /// The frames of `diagnostics.png`: latency, iterations and flags from the rows, the
    /// position error against ground truth `gt` over the distance it travelled.
    fn diagnostics(&self, gt: &[Option<Isometry3<f64>>]) -> Vec<crate::plot::FramePoint> {
        let o = self.record;
        let mut travelled = 0.0;
        let mut last: Option<nalgebra::Vector3<f64>> = None;
        o.rows
            .iter()
            .zip(&o.poses)
            .zip(gt)
            .map(|((row, pose), g)| {
                let error = g.map(|g| {
                    let at = g.translation.vector;
                    travelled += last.map_or(0.0, |l| (at - l).norm());
                    last = Some(at);
                    (travelled, (pose.translation.vector - at).norm())
                });
                crate::plot::FramePoint {
                    index: row.index,
                    latency_ms: row.latency_ms,
                    iterations: row.iterations,
                    status: row.status,
                    error,
                }
            })
            .collect()
    }

    fn summary(&self, metrics: Option<serde_json::Value>) -> Summary {
        let o = self.record;
        let registered = o.rows.iter().filter(|r| r.outcome == RowKind::Registered);
        let mut lat: Vec<f64> = registered.clone().filter_map(|r| r.latency_ms).collect();
        lat.sort_by(f64::total_cmp);
        let odometry_s = lat.iter().sum::<f64>() / 1e3;
        let mut degraded = BTreeMap::new();
        for flag in registered.flat_map(|r| r.status.flags()) {
            *degraded.entry(flag.name()).or_insert(0) += 1;
        }
        let count = |k: RowKind| o.rows.iter().filter(|r| r.outcome == k).count();
        let d = self.driver;
        let memory = d.memory();
        let (hw, c) = (d.high_water(), memory.capacities);
        let s = self.settings;
        Summary {
            frames: o.rows.len(),
            registered_frames: lat.len(),
            odometry_s,
            hz: if odometry_s > 0.0 {
                lat.len() as f64 / odometry_s
            } else {
                0.0
            },
            latency_ms: Latency::of(lat.clone()).unwrap_or_default(),
            peak_rss_bytes: crate::memory::peak_rss_bytes(),
            state_bytes: memory.bytes,
            state: StateSummary::of(&memory),
            skipped_frames: count(RowKind::Skipped),
            empty_frames: count(RowKind::Empty),
            degraded_frames: degraded,
            high_water: serde_json::json!({
                "scan_points": [
                    o.rows.iter().filter_map(|r| r.input_points).max().unwrap_or(0),
                    c.scan_points
                ],
                "merge_points": [hw.merge_points, c.merge_points],
                "source_points": [hw.source_points, c.source_points],
                "map_voxels": [hw.map_voxels, c.map_voxels],
                "map_point_slots": [hw.map_point_slots, c.map_points],
            }),
            map: {
                let m = d.map_in_use();
                serde_json::json!({
                    "voxel_size": m.voxel_size,
                    "max_points_per_voxel": m.max_points_per_voxel,
                })
            },
            map_radius: MapRadius::of(&o.rows, s.data.max_range),
            warnings: o.warnings,
            imu_rejected_frames: d.gyro_bias().map(|_| d.imu_rejected_frames()),
            packets: PacketTotals::of(&o.rows),
            pose_latency_ms: Latency::of(o.rows.iter().filter_map(|r| r.pose_latency_ms).collect()),
            localization: LocalizationSummary::of(o),
            interrupted: self.interrupted.is_some(),
            stop_reason: self.stop.clone(),
            input: serde_json::json!({
                "path": self.args.path.display().to_string(),
                "format": self.info.format,
                "kitti_correction": self.info.kitti_correction,
                "ground_truth": self.info.ground_truth_path.as_ref().map(|p| p.display().to_string()),
                "plane_terms": c.plane_terms,
                "scalar": s.runtime.scalar,
                "map_storage": s.runtime.map_storage,
                "threads": d.build().threads,
                "tum_times": if self.tum_seconds() { "seconds" } else { "frame numbers" },
            }),
            metrics,
            outputs: Digests::new(),
        }
    }
}

/// The state's size as the summary line gives it: fixed, or grown in moves.
fn state_line(s: &StateSummary) -> String {
    let mib = |b: usize| b as f64 / (1 << 20) as f64;
    match s.moves {
        0 => format!("{:.1} MiB", mib(s.end_bytes)),
        n => format!(
            "{:.1} MiB (grew from {:.1} MiB in {n} move{}, peak {:.1} MiB)",
            mib(s.end_bytes),
            mib(s.start_bytes),
            if n == 1 { "" } else { "s" },
            mib(s.peak_bytes)
        ),
    }
}

/// The two lines `run` prints.
pub(super) fn print_summary(s: &Summary) {
    println!(
        "{} frames, {:.1} Hz in the core (p50 {:.1} ms, p99 {:.1} ms, max {:.1} ms), state {}",
        s.frames,
        s.hz,
        s.latency_ms.p50,
        s.latency_ms.p99,
        s.latency_ms.max,
        state_line(&s.state)
    );
    if let Some(l) = s.pose_latency_ms {
        println!(
            "last packet to pose: p50 {:.1} ms, p99 {:.1} ms, max {:.1} ms",
            l.p50, l.p99, l.max
        );
    }
    if let Some(l) = s.localization {
        println!(
            "localization: {} localized, {} degraded, {} lost, state {:.1} KiB (a board holding \
             the most tiles held: {:.1} KiB)",
            l.localized,
            l.degraded,
            l.lost,
            l.state_bytes as f64 / 1024.0,
            l.board_bytes as f64 / 1024.0
        );
    }
    if let Some(obj) = s.metrics.as_ref().and_then(|m| m.as_object()) {
        let parts: Vec<String> = obj
            .iter()
            .filter_map(|(k, v)| Some(format!("{k} {:.4}", v.as_f64()?)))
            .collect();
        println!("metrics: {}", parts.join(", "));
    }
}
