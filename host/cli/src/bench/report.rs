//! What `bench` measured: the timed runs of each side, their statistics, the memory figures
//! and the whole report (printed by `print`, written as JSON).

use crate::stats::{median, percentile};
use kiss_odom_drive::settings::{Scalar, Storage};
use nalgebra::Isometry3;
use serde::Serialize;

/// One timed run of ours.
#[derive(Clone, Debug, Serialize)]
pub struct OurRun {
    /// Seconds in the core's frame call, per frame.
    pub seconds: Vec<f64>,
    /// The calling thread's CPU seconds in that call, per frame.
    pub cpu_seconds: Vec<f64>,
    /// RSS when the run started (frames loaded).
    pub rss_before_bytes: Option<u64>,
    /// Peak RSS during the run.
    pub peak_rss_bytes: Option<u64>,
    /// Poses, widened to f64.
    #[serde(skip)]
    pub poses: Vec<Isometry3<f64>>,
    /// ICP iterations per frame.
    #[serde(skip)]
    pub iterations: Vec<u32>,
    /// Frames whose status was not ok.
    pub degraded_frames: usize,
    /// Empty frames (no usable point).
    pub empty_frames: usize,
    /// What the memory figures are made of.
    #[serde(skip)]
    pub memory: Option<Memory>,
}

/// Frame rate and latency of one implementation over the timed runs.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SideStats {
    /// Frames per second of odometry time, per timed run.
    pub fps_runs: Vec<f64>,
    /// Their median.
    pub fps: f64,
    /// Per-frame latency percentiles (ms) of the per-frame median over runs.
    pub p50_ms: f64,
    /// 99th percentile.
    pub p99_ms: f64,
    /// Worst frame.
    pub max_ms: f64,
    /// Worst single frame time over every timed run (ms), noise included.
    pub max_any_run_ms: f64,
    /// The same percentiles of the calling thread's CPU time (ours, one thread): what the
    /// frame costs without the time other processes took the core away.
    pub cpu: Option<Spread>,
    /// Largest peak RSS of a timed run.
    pub peak_rss_bytes: Option<u64>,
    /// Largest growth of RSS during a timed run (peak minus RSS at its start).
    pub rss_growth_bytes: Option<u64>,
}

/// Per-frame time percentiles (ms) of the per-frame median over runs (wall-clock or CPU).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Spread {
    /// Median frame.
    pub p50_ms: f64,
    /// 99th percentile.
    pub p99_ms: f64,
    /// Worst frame.
    pub max_ms: f64,
}

/// The first frame the latency figures count: `from`, or the last frame of a shorter run (so
/// every figure is taken over at least one frame, never reported as 0).
pub fn first_counted(from: usize, frames: usize) -> usize {
    from.min(frames.saturating_sub(1))
}

/// Each frame's median over the runs (ms), from frame `from` on, sorted.
fn per_frame_medians(runs: &[&[f64]], from: usize) -> Vec<f64> {
    let n = runs.first().map_or(0, |r| r.len());
    let mut v: Vec<f64> = (first_counted(from, n)..n)
        .map(|i| median(&runs.iter().map(|r| r[i]).collect::<Vec<_>>()) * 1e3)
        .collect();
    v.sort_by(f64::total_cmp);
    v
}

impl Spread {
    pub fn of(runs: &[&[f64]], from: usize) -> Self {
        let v = per_frame_medians(runs, from);
        Self {
            p50_ms: percentile(&v, 50.0),
            p99_ms: percentile(&v, 99.0),
            max_ms: v.last().copied().unwrap_or(0.0),
        }
    }
}

impl SideStats {
    pub fn of(runs: &[(Vec<f64>, Option<u64>, Option<u64>)], latency_from: usize) -> Self {
        let mut s = SideStats::default();
        if runs.is_empty() {
            return s;
        }
        s.fps_runs = runs
            .iter()
            .map(|(sec, _, _)| sec.len() as f64 / sec.iter().sum::<f64>().max(1e-12))
            .collect();
        s.fps = median(&s.fps_runs);
        let seconds: Vec<&[f64]> = runs.iter().map(|r| r.0.as_slice()).collect();
        let wall = Spread::of(&seconds, latency_from);
        (s.p50_ms, s.p99_ms, s.max_ms) = (wall.p50_ms, wall.p99_ms, wall.max_ms);
        s.max_any_run_ms = runs
            .iter()
            .flat_map(|r| r.0.iter().skip(first_counted(latency_from, r.0.len())))
            .fold(0.0f64, |a, &b| a.max(b * 1e3));
        s.peak_rss_bytes = runs.iter().filter_map(|r| r.2).max();
        s.rss_growth_bytes = runs
            .iter()
            .filter_map(|r| Some(r.2?.saturating_sub(r.1?)))
            .max();
        s
    }
}

/// Memory figures of ours and the reference's local map.
#[derive(Clone, Debug, Serialize)]
pub struct Memory {
    /// Bytes of our whole core state, fixed at start.
    pub state_bytes: usize,
    /// Bytes the state would need with capacities equal to the high-water marks.
    pub state_high_water_bytes: Option<usize>,
    /// Bytes of our local map (voxel table and point pool), fixed at start.
    pub map_bytes: usize,
    /// Bytes of a map sized to the high-water marks.
    pub map_high_water_bytes: usize,
    /// High-water marks against capacities: merge, source, voxels, point slots.
    pub high_water: serde_json::Value,
    /// The reference's most voxels (after any frame).
    pub reference_voxels: Option<usize>,
    /// The reference's most points.
    pub reference_points: Option<usize>,
    /// Its point buffers: `max_points_per_voxel` x 24 B reserved per voxel.
    pub reference_map_bytes: Option<usize>,
    /// Plus malloc chunk headers and the robin-map bucket array (estimate, see BENCHMARKS.md).
    pub reference_map_bytes_with_table: Option<usize>,
}

/// Everything `bench` measured.
#[derive(Debug, Serialize)]
pub struct Report {
    /// Dataset path.
    pub dataset: String,
    /// Frames timed.
    pub frames: usize,
    /// Points in them.
    pub points: usize,
    /// Threads on both sides.
    pub threads: usize,
    /// f64 or f32.
    pub scalar: Scalar,
    /// Map point storage.
    pub storage: Storage,
    /// Timed runs per side.
    pub repeats: usize,
    /// First frame in the latency statistics (`--latency-from`, or the last frame of a shorter
    /// dataset).
    pub latency_from: usize,
    /// Ours.
    pub ours: SideStats,
    /// The reference.
    pub reference: Option<SideStats>,
    /// Median of the per-repeat ratios ours/reference of frames per second.
    pub speed_ratio: Option<f64>,
    /// The per-repeat ratios.
    pub speed_ratio_runs: Vec<f64>,
    /// Memory.
    pub memory: Memory,
    /// Worst-case nearest-neighbour distance evaluations per frame from the capacities.
    pub worst_case_distance_evaluations: u64,
    /// Most ICP iterations of a frame.
    pub max_iterations_seen: u32,
    /// Largest position difference of our poses from the reference's (m).
    pub pose_diff_m: Option<f64>,
    /// Largest rotation difference (rad).
    pub pose_diff_rad: Option<f64>,
    /// Whether every run of ours gave the same poses bit for bit.
    pub ours_repeatable: bool,
    /// Frames with a non-ok status in our warm-up run.
    pub degraded_frames: usize,
    /// Share of the reference's frame time spent converting the input frame to a C++ vector.
    pub reference_binding_share: Option<f64>,
    /// Versions of the reference.
    pub reference_versions: Option<serde_json::Value>,
    /// Per-frame seconds of each timed run, ours then the reference's.
    pub per_frame_seconds: serde_json::Value,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_takes_each_frames_median_over_runs_from_the_first_counted_frame() {
        // Frame 0 is the warm-up and left out; frame 3's outlier in one run is voted down.
        let a = [9.0, 0.125, 0.25, 0.375];
        let b = [9.0, 0.375, 0.5, 4.0];
        let c = [9.0, 0.25, 0.75, 0.5];
        let s = Spread::of(&[&a, &b, &c], 1);
        // Medians (ms): 250, 500, 500.
        assert_eq!(
            per_frame_medians(&[&a, &b, &c], 1),
            vec![250.0, 500.0, 500.0]
        );
        assert_eq!((s.p50_ms, s.max_ms), (500.0, 500.0));
        assert_eq!(per_frame_medians(&[&a, &b, &c], 0).last(), Some(&9000.0));
    }

    #[test]
    fn latency_from_past_the_last_frame_counts_the_last_frame_not_nothing() {
        let run = |t: &[f64]| (t.to_vec(), None, None);
        let s = SideStats::of(&[run(&[0.5, 0.25]), run(&[0.5, 0.125])], 10);
        // Both figures from frame 1 alone: median 187.5 ms, worst single run 250 ms.
        assert_eq!(
            (s.p50_ms, s.max_ms, s.max_any_run_ms),
            (187.5, 187.5, 250.0)
        );
        let s = SideStats::of(&[run(&[0.5, 0.25]), run(&[0.5, 0.125])], 0);
        assert_eq!(s.max_any_run_ms, 500.0);
    }
}
