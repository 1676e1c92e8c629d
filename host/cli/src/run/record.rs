//! What a run records, frame by frame: the rows of `frames.csv` (one typed row per frame, one
//! 0/1 column per status flag), the poses and times of the pose files.

use kiss_odom_core::{Flag, Status};
use kiss_odom_drive::{Outcome, Step};
use kiss_odom_sensors::SweepStats;
use nalgebra::Isometry3;
use serde::ser::SerializeStruct;
use serde::Serialize;

/// What the run produced, frame by frame.
#[derive(Default)]
pub struct Record {
    /// One row per frame.
    pub rows: Vec<FrameRow>,
    /// The pose after each frame.
    pub poses: Vec<Isometry3<f64>>,
    /// Each frame's time (its own, else `times.txt`'s), if known.
    pub times: Vec<Option<f64>>,
    /// Frame indices.
    pub indices: Vec<usize>,
    /// Warnings printed (dataset, frames, threads).
    pub warnings: usize,
    /// Whether the frames are sweeps decoded from sensor packets.
    pub sweeps: bool,
    /// With `--map`: the localizer's state bytes.
    pub localizer_bytes: Option<usize>,
    /// With `--map`: the most tiles and points of the prior map held at once.
    pub prior_held: (u32, u32),
    /// With `--map`: the localizer's bytes on a board (f32), whatever the map.
    pub localizer_board_bytes: Option<usize>,
}

impl Record {
    /// Frames the core registered.
    pub fn registered(&self) -> usize {
        self.rows
            .iter()
            .filter(|r| r.outcome == RowKind::Registered)
            .count()
    }
}

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
    /// Of those, the point-to-plane ones (robust mode and the `accurate` preset).
    pub plane_correspondences: Option<u32>,
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
    /// Moves of the core's state into larger storage this frame took (a host run whose
    /// capacities grow; see the book's outputs chapter).
    pub state_moves: u32,
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
    /// Whether it was deskewed a second time with the motion its first registration found.
    pub redeskewed: bool,
    /// With `--imu auto`: `used` (the gyroscope's rotation predicted and deskewed the frame),
    /// or why not (`first`, `no_samples`, `gap`, `bad_samples`, `rejected`: the IMU
    /// consistency check found the gyroscope disagreeing with ICP); empty otherwise.
    pub imu_prior: Option<&'static str>,
    /// With `--imu auto`: IMU samples that came with the frame.
    pub imu_samples: Option<usize>,
    /// With `--imu auto`: the gyroscope bias estimate after the frame, LiDAR axes (rad/s).
    pub gyro_bias_x: Option<f64>,
    /// See `gyro_bias_x`.
    pub gyro_bias_y: Option<f64>,
    /// See `gyro_bias_x`.
    pub gyro_bias_z: Option<f64>,
    /// With `--imu auto`, on frames that used the prior: how far ICP's rotation rate was from
    /// the gyroscope's (rad/s).
    pub imu_residual: Option<f64>,
    /// With `--imu auto`: the angle between the gyroscope's rotation over the frame and the
    /// rotation ICP registered (rad), which the IMU consistency check judges.
    pub imu_disagreement: Option<f64>,
    /// With `--map`: `localized`, `degraded` or `lost` (see the book's maps chapter).
    pub localization: Option<&'static str>,
    /// With `--map`: the share of the registration cloud off level ground that lies on the
    /// prior map at the pose.
    pub map_inlier_share: Option<f64>,
    /// With `--map`: the registration's conditioning, its observability ratio (empty when
    /// nothing was measured).
    pub map_observability: Option<f64>,
    /// With `--map`: how far registering to the prior map moved the predicted pose (m).
    pub map_correction_m: Option<f64>,
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
            plane_correspondences: r.map(|r| r.plane_correspondences),
            sigma: o.sigma,
            map_voxels: r.map(|r| r.map_voxels),
            map_points: r.map(|r| r.map_points),
            map_radius: r.map(|r| r.map_radius),
            evicted_voxels: r.map(|r| r.evicted_voxels),
            state_moves: o.moves,
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
            packets: None,
            packets_lost: None,
            packets_out_of_order: None,
            packets_bad: None,
            packets_other_sensor: None,
            azimuth_jumps: None,
            pose_latency_ms: None,
            deskewed: r.is_some_and(|r| r.deskewed),
            redeskewed: r.is_some_and(|r| r.redeskewed),
            imu_prior: o.imu.map(|u| u.state()),
            imu_samples: o.imu.map(|u| u.samples),
            gyro_bias_x: o.imu.map(|u| u.bias[0]),
            gyro_bias_y: o.imu.map(|u| u.bias[1]),
            gyro_bias_z: o.imu.map(|u| u.bias[2]),
            imu_residual: o.imu.and_then(|u| u.residual),
            imu_disagreement: o.imu.and_then(|u| u.disagreement),
            localization: None,
            map_inlier_share: None,
            map_observability: None,
            map_correction_m: None,
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

    /// Adds packets refused or lost after the last sweep, and those of an open sweep at the
    /// end that was not registered (a source's trailer), to this row's packet columns, so that
    /// the totals count them.
    pub fn add_packets(&mut self, s: &SweepStats) {
        let add = |c: &mut Option<u32>, n: u32| *c = Some(c.unwrap_or(0).saturating_add(n));
        add(&mut self.packets, s.packets);
        add(&mut self.packets_lost, s.lost_packets);
        add(&mut self.packets_out_of_order, s.out_of_order);
        add(&mut self.packets_bad, s.bad_packets);
        add(&mut self.packets_other_sensor, s.other_sensor);
    }
}

/// The flag columns of a row: one per [`Flag`], named by [`Flag::name`], 0 or 1.
pub(super) struct FlagColumns(pub(super) Status);

impl Serialize for FlagColumns {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut st = s.serialize_struct("Flags", Flag::ALL.len())?;
        for flag in Flag::ALL {
            st.serialize_field(flag.name(), &u8::from(self.0.contains(flag)))?;
        }
        st.end()
    }
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
    pub fn of(rows: &[FrameRow]) -> Option<Self> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use kiss_odom_drive::FrameMeta;
    use nalgebra::Isometry3;

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
            sweep: Default::default(),
            imu: None,
            moves: 0,
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
            first.starts_with("7,\"a,b.bin\",skipped,,,,,,2.0,,,,,"),
            "{first}"
        );
        // A skipped frame raises no flag; the registered one exactly the two it was given.
        let cells = |set: &[Flag]| -> String {
            let bit = |f: &Flag| if set.contains(f) { ",1" } else { ",0" };
            Flag::ALL.iter().map(bit).collect()
        };
        let unflagged = format!(",,,,false,false,,,,,,,,,,,{}", cells(&[]));
        assert!(first.ends_with(&unflagged), "{first}\n{unflagged}");
        let second = lines.next().unwrap();
        let flagged = cells(&[Flag::Degenerate, Flag::Capacity]);
        assert!(second.ends_with(&flagged), "{second}\n{flagged}");
        assert_eq!(flagged.matches(",1").count(), 2);
    }
}
