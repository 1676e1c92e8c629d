//! What `run` writes: `poses_kitti.txt`, `poses_tum.txt`, `frames.csv` (one typed row per
//! frame, one 0/1 column per status flag), `summary.json`, `config.toml`, `trajectory.png` and
//! `diagnostics.png`, each atomically (see [`kiss_odom_io::write`]).

use super::{Record, RunArgs};
use crate::stats::percentile;
use anyhow::Result;
use kiss_odom_core::{Flag, Status};
use kiss_odom_drive::settings::Settings;
use kiss_odom_drive::{Driver, Outcome, Step};
use kiss_odom_io as io;
use kiss_odom_sensors::SweepStats;
use nalgebra::Isometry3;
use serde::ser::SerializeStruct;
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

/// What became of a frame, as `frames.csv` names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RowKind {
    /// Registered by the core (its flags are in the flag columns).
    Registered,
    /// No usable point: the pose is the constant-velocity prediction.
    Empty,
    /// Unreadable: the pose is the constant-velocity prediction.
    Skipped,
}

/// One line of `frames.csv` before its flag columns; figures of the core's report are empty
/// for frames that were not registered.
#[derive(Clone, Debug, Serialize)]
pub struct FrameRow {
    /// Frame index (its identity in the dataset).
    pub index: usize,
    /// Where it came from: the file, or `file:topic@time` for a bag or MCAP message.
    pub source: String,
    /// Registered, empty or skipped.
    pub outcome: RowKind,
    /// Time in the core's frame call (ms).
    pub latency_ms: Option<f64>,
    /// ICP iterations.
    pub iterations: Option<u32>,
    /// ICP's work units (`FrameReport::work`).
    pub work: Option<u64>,
    /// Correspondences in the last iteration.
    pub correspondences: Option<u32>,
    /// The threshold's sigma the frame was registered with.
    pub sigma: f64,
    /// Map voxels after the update.
    pub map_voxels: Option<u32>,
    /// Map points after the update.
    pub map_points: Option<u32>,
    /// The map's radius after the update (m): `max_range`, or less once a full map gave up
    /// its farthest voxels.
    pub map_radius: Option<f64>,
    /// Map voxels evicted, farthest first, to make room in this frame.
    pub evicted_voxels: Option<u32>,
    /// Points given.
    pub input_points: Option<usize>,
    /// Merge cloud points.
    pub merge_points: Option<u32>,
    /// Registration cloud points.
    pub source_points: Option<u32>,
    /// Non-finite points skipped.
    pub dropped_non_finite: Option<u32>,
    /// Points past the scan capacity.
    pub dropped_truncated: Option<u32>,
    /// Merge voxels dropped (full).
    pub dropped_merge_full: Option<u32>,
    /// Source voxels dropped (full).
    pub dropped_source_full: Option<u32>,
    /// Map voxels refused (table full).
    pub dropped_map_voxels_full: Option<u32>,
    /// Map points refused (pool full).
    pub dropped_map_points_full: Option<u32>,
    /// Observability ratio (empty on the first frame and when nothing was measured).
    pub observability: Option<f64>,
    /// Robust mode: the sensor axes held at the constant-velocity prediction, `|`-joined
    /// (`tx|ty|yaw`); empty when none was (the `held` flag column says whether any
    /// direction was).
    pub held_axes: String,
    /// Robust mode: weakest over strongest eigenvalue of the translation information.
    pub weak_t: Option<f64>,
    /// Robust mode: the same for rotation.
    pub weak_r: Option<f64>,
    /// Sensor packets decoded into the sweep (empty for frames not decoded from packets).
    pub packets: Option<u32>,
    /// Packets the decoder found missing (timestamp gaps, missing columns or frame ids).
    pub packets_lost: Option<u32>,
    /// Packets late or repeated (dropped) and, Ouster, columns out of order.
    pub packets_out_of_order: Option<u32>,
    /// Packets refused as malformed.
    pub packets_bad: Option<u32>,
    /// Packets refused as another sensor's.
    pub packets_other_sensor: Option<u32>,
    /// Velodyne azimuth jumps the timestamps do not explain.
    pub azimuth_jumps: Option<u32>,
    /// `live`: time from the sweep's last packet to its pose (ms); empty for a sweep the end
    /// of the stream closed and for recordings.
    pub pose_latency_ms: Option<f64>,
    /// Whether the scan was deskewed.
    pub deskewed: bool,
    /// The core's flags, written as one column each.
    #[serde(skip)]
    pub status: Status,
}

impl FrameRow {
    /// The row of an outcome.
    pub fn of(o: &Outcome) -> Self {
        let r = o.report();
        let kind = match o.step {
            Step::Registered(_) => RowKind::Registered,
            Step::Empty => RowKind::Empty,
            Step::Skipped(_) => RowKind::Skipped,
        };
        Self {
            index: o.meta.index,
            source: o.meta.source.clone(),
            outcome: kind,
            // Microseconds are what a timer on a shared machine resolves.
            latency_ms: (kind != RowKind::Skipped)
                .then(|| (o.latency.as_secs_f64() * 1e6).round() / 1e3),
            iterations: r.map(|r| r.iterations),
            work: r.map(|r| r.work),
            correspondences: r.map(|r| r.correspondences),
            sigma: o.sigma,
            map_voxels: r.map(|r| r.map_voxels),
            map_points: r.map(|r| r.map_points),
            map_radius: r.map(|r| r.map_radius),
            evicted_voxels: r.map(|r| r.evicted_voxels),
            input_points: (kind != RowKind::Skipped).then_some(o.input_points),
            merge_points: r.map(|r| r.merge_points),
            source_points: r.map(|r| r.source_points),
            dropped_non_finite: r.map(|r| r.dropped.non_finite),
            dropped_truncated: r.map(|r| r.dropped.truncated),
            dropped_merge_full: r.map(|r| r.dropped.merge_full),
            dropped_source_full: r.map(|r| r.dropped.source_full),
            dropped_map_voxels_full: r.map(|r| r.dropped.map_voxels_full),
            dropped_map_points_full: r.map(|r| r.dropped.map_points_full),
            observability: r.and_then(|r| r.observability),
            held_axes: r.map_or_else(String::new, |r| r.held.to_string()),
            weak_t: r.and_then(|r| r.weak_ratios).map(|w| w[0]),
            weak_r: r.and_then(|r| r.weak_ratios).map(|w| w[1]),
            packets: None,
            packets_lost: None,
            packets_out_of_order: None,
            packets_bad: None,
            packets_other_sensor: None,
            azimuth_jumps: None,
            pose_latency_ms: None,
            deskewed: r.is_some_and(|r| r.deskewed),
            status: o.status().unwrap_or_default(),
        }
    }

    /// Fills the packet columns from a decoded sweep's statistics.
    pub fn with_packets(mut self, s: &SweepStats) -> Self {
        self.packets = Some(s.packets);
        self.packets_lost = Some(s.lost_packets);
        self.packets_out_of_order = Some(s.out_of_order);
        self.packets_bad = Some(s.bad_packets);
        self.packets_other_sensor = Some(s.other_sensor);
        self.azimuth_jumps = Some(s.azimuth_jumps);
        self
    }

    /// Adds packets refused or lost after the last sweep (a source's trailer) to this row's
    /// packet columns, so that the totals count them.
    pub fn add_packets(&mut self, s: &SweepStats) {
        let add = |c: &mut Option<u32>, n: u32| *c = Some(c.unwrap_or(0).saturating_add(n));
        add(&mut self.packets_lost, s.lost_packets);
        add(&mut self.packets_out_of_order, s.out_of_order);
        add(&mut self.packets_bad, s.bad_packets);
        add(&mut self.packets_other_sensor, s.other_sensor);
    }
}

/// The flag columns of a row: one per [`Flag`], named by [`Flag::name`], 0 or 1.
struct FlagColumns(Status);

impl Serialize for FlagColumns {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut st = s.serialize_struct("Flags", Flag::ALL.len())?;
        for flag in Flag::ALL {
            st.serialize_field(flag.name(), &u8::from(self.0.contains(flag)))?;
        }
        st.end()
    }
}

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

/// Sensor packets summed over the sweeps of a run (frames.csv has them per sweep).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct PacketTotals {
    /// Decoded.
    pub decoded: u64,
    /// Missing.
    pub lost: u64,
    /// Late or repeated (dropped), or Ouster columns out of order.
    pub out_of_order: u64,
    /// Refused as malformed.
    pub bad: u64,
    /// Refused as another sensor's.
    pub other_sensor: u64,
}

impl PacketTotals {
    /// The sums over `rows` that have packet columns; `None` when none has.
    fn of(rows: &[FrameRow]) -> Option<Self> {
        let mut t: Option<Self> = None;
        for r in rows.iter().filter(|r| r.packets.is_some()) {
            let t = t.get_or_insert_with(Self::default);
            let n = |v: Option<u32>| u64::from(v.unwrap_or(0));
            t.decoded += n(r.packets);
            t.lost += n(r.packets_lost);
            t.out_of_order += n(r.packets_out_of_order);
            t.bad += n(r.packets_bad);
            t.other_sensor += n(r.packets_other_sensor);
        }
        t
    }
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
    /// Bytes of the core's state (fixed at start).
    pub state_bytes: usize,
    /// Frames that could not be read (their pose is the constant-velocity prediction).
    pub skipped_frames: usize,
    /// Frames with no usable point (their pose is the prediction).
    pub empty_frames: usize,
    /// Registered frames by status flag (a frame counts once for each of its flags).
    pub degraded_frames: BTreeMap<&'static str, usize>,
    /// Largest buffer occupancy against capacity.
    pub high_water: serde_json::Value,
    /// The smallest radius the local map had after a frame, and the first frame that had it:
    /// `max_range` and no frame while the map never filled.
    pub map_radius: MapRadius,
    /// Warnings printed.
    pub warnings: usize,
    /// Sensor packets over the run's sweeps (a pcap recording or `live`).
    pub packets: Option<PacketTotals>,
    /// `live`: time from a sweep's last packet to its pose (ms).
    pub pose_latency_ms: Option<Latency>,
    /// Whether SIGINT or SIGTERM stopped the run (the outputs hold the frames before it).
    pub interrupted: bool,
    /// Why the run stopped early, if an error stopped it.
    pub stop_reason: Option<String>,
    /// Input path, format and settings summary.
    pub input: serde_json::Value,
    /// Metrics against ground truth, when it exists.
    pub metrics: Option<serde_json::Value>,
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
        let dir = &self.args.run.out;
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
                .and_then(|t| kiss_odom_io::write::write(&dir.join("config.toml"), t.as_bytes())),
        );
        if !o.rows.is_empty() {
            attempt(kiss_odom_io::write::write_with(
                &dir.join("frames.csv"),
                |w| {
                    let mut csv = csv::Writer::from_writer(w);
                    for row in &o.rows {
                        csv.serialize((row, FlagColumns(row.status)))?;
                    }
                    csv.flush()?;
                    Ok(())
                },
            ));
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
            attempt(self.write_poses());
            let title = self
                .args
                .path
                .file_name()
                .map_or_else(|| "trajectory".into(), |n| n.to_string_lossy().into_owned());
            let gt = self.in_estimate_frame(&rows);
            let paired: Vec<Isometry3<f64>> = gt.iter().flatten().copied().collect();
            let paired = (!paired.is_empty()).then_some(paired.as_slice());
            attempt(kiss_odom_io::write::write_via_path(
                &dir.join("trajectory.png"),
                |p| crate::plot::trajectory_png(p, &o.poses, paired, &title),
            ));
            let diagnostics = self.diagnostics(&gt);
            attempt(kiss_odom_io::write::write_via_path(
                &dir.join("diagnostics.png"),
                |p| crate::plot::diagnostics_png(p, &diagnostics, &title),
            ));
        }
        let mut summary = self.summary(metrics.filter(|_| o.registered() > 0));
        if let (None, Some(e)) = (&summary.stop_reason, &failed) {
            summary.stop_reason = Some(format!(
                "outputs incomplete: {}",
                kiss_odom_drive::one_line(e)
            ));
        }
        let json = serde_json::to_string_pretty(&summary)? + "\n";
        let written = kiss_odom_io::write::write(&dir.join("summary.json"), json.as_bytes());
        match failed {
            Some(e) => Err(e),
            None => written.map(|()| summary),
        }
    }

    fn write_poses(&self) -> Result<()> {
        let dir = &self.args.run.out;
        let o = self.record;
        let kitti = io::poses::format_kitti(&o.poses);
        kiss_odom_io::write::write(&dir.join("poses_kitti.txt"), kitti.as_bytes())?;
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
        kiss_odom_io::write::write(&dir.join("poses_tum.txt"), tum.as_bytes())
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
                "time x y z qx qy qz qw: the sensor at the {} of each sweep (--pose-time); \
                 times: {times}",
                self.args.run.pose_time.name()
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
        let (hw, c) = (d.high_water(), d.capacities());
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
            state_bytes: d.state_bytes(),
            skipped_frames: count(RowKind::Skipped),
            empty_frames: count(RowKind::Empty),
            degraded_frames: degraded,
            high_water: serde_json::json!({
                "merge_points": [hw.merge_points, c.merge_points],
                "source_points": [hw.source_points, c.source_points],
                "map_voxels": [hw.map_voxels, c.map_voxels],
                "map_point_slots": [hw.map_point_slots, c.map_points],
            }),
            map_radius: MapRadius::of(&o.rows, s.data.max_range),
            warnings: o.warnings,
            packets: PacketTotals::of(&o.rows),
            pose_latency_ms: Latency::of(o.rows.iter().filter_map(|r| r.pose_latency_ms).collect()),
            interrupted: self.interrupted.is_some(),
            stop_reason: self.stop.clone(),
            input: serde_json::json!({
                "path": self.args.path.display().to_string(),
                "format": self.info.format,
                "kitti_correction": self.info.kitti_correction,
                "ground_truth": self.info.ground_truth_path.as_ref().map(|p| p.display().to_string()),
                "scalar": s.runtime.scalar,
                "map_storage": s.runtime.map_storage,
                "threads": d.threads(),
                "tum_times": if self.tum_seconds() { "seconds" } else { "frame numbers" },
            }),
            metrics,
        }
    }
}

/// The two lines `run` prints.
pub(super) fn print_summary(s: &Summary) {
    println!(
        "{} frames, {:.1} Hz in the core (p50 {:.1} ms, p99 {:.1} ms, max {:.1} ms), state {:.1} MiB",
        s.frames,
        s.hz,
        s.latency_ms.p50,
        s.latency_ms.p99,
        s.latency_ms.max,
        s.state_bytes as f64 / (1 << 20) as f64
    );
    if let Some(l) = s.pose_latency_ms {
        println!(
            "last packet to pose: p50 {:.1} ms, p99 {:.1} ms, max {:.1} ms",
            l.p50, l.p99, l.max
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

#[cfg(test)]
mod tests {
    use super::*;
    use kiss_odom_drive::FrameMeta;

    #[test]
    fn frames_csv_has_a_column_per_flag_and_empty_cells_for_unregistered_frames() {
        let skipped = Outcome {
            meta: FrameMeta {
                index: 7,
                source: "a,b.bin".into(),
                time: None,
            },
            step: Step::Skipped("a,b.bin: truncated".into()),
            pose: Isometry3::identity(),
            sigma: 2.0,
            latency: std::time::Duration::ZERO,
            cpu: std::time::Duration::ZERO,
            input_points: 0,
            warnings: Vec::new(),
        };
        let mut row = FrameRow::of(&skipped);
        let mut csv = csv::Writer::from_writer(Vec::new());
        csv.serialize((&row, FlagColumns(row.status))).unwrap();
        row.status = Status::OK.with(Flag::Degenerate).with(Flag::Capacity);
        row.outcome = RowKind::Registered;
        csv.serialize((&row, FlagColumns(row.status))).unwrap();
        let text = String::from_utf8(csv.into_inner().unwrap()).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let flags: Vec<&str> = Flag::ALL.iter().map(|f| f.name()).collect();
        assert_eq!(&header[header.len() - flags.len()..], flags.as_slice());
        assert_eq!(&header[..3], ["index", "source", "outcome"]);
        let first = lines.next().unwrap();
        assert!(
            first.starts_with("7,\"a,b.bin\",skipped,,,,,2.0,,,,,"),
            "{first}"
        );
        assert!(
            first.ends_with(",,,,false,0,0,0,0,0,0,0,0,0,0,0,0"),
            "{first}"
        );
        let second = lines.next().unwrap();
        assert!(second.ends_with(",0,0,0,0,1,0,0,1,0,0,0,0"), "{second}");
    }
}
