//! Warnings for the capacity rules that can change a pose: each rule warns once per run, on
//! the first frame it fires, naming the capacity and the remedy. The columns of `frames.csv`
//! say the rest frame by frame.

use crate::outcome::Outcome;
use kiss_odom_core::{Capacities, Flag, FrameReport};

/// What to tell a user whose buffers are too small.
const REMEDY: &str = "give larger capacities (or none: they then grow with the run up to \
                      runtime.memory_limit), a larger mapping.voxel_size or a smaller --max-range";

/// The rules already warned about in this run, for a core with those capacities and range.
#[derive(Clone, Copy, Debug)]
pub struct CapacityWarnings {
    caps: Capacities,
    max_range: f64,
    evicted: bool,
    map_full: bool,
    merge_full: bool,
    source_full: bool,
}

impl CapacityWarnings {
    /// None said yet, for a core with `caps` and range `max_range`.
    pub fn new(caps: Capacities, max_range: f64) -> Self {
        Self {
            caps,
            max_range,
            evicted: false,
            map_full: false,
            merge_full: false,
            source_full: false,
        }
    }

    /// The warnings `outcome` raises for the first time in this run, whose core has the
    /// capacities `caps` now (they grow on a host: see `growth`).
    pub fn check(&mut self, outcome: &Outcome, caps: &Capacities) -> Vec<String> {
        self.caps = *caps;
        let (caps, max_range) = (self.caps, self.max_range);
        let Some(r) = outcome.report() else {
            return Vec::new();
        };
        let at = format!("frame {} ({})", outcome.meta.index, outcome.meta.source);
        let mut out = Vec::new();
        let mut once = |said: &mut bool, fired: bool, text: &dyn Fn() -> String| {
            if fired && !*said {
                *said = true;
                out.push(format!("{at}: {}; {REMEDY}", text()));
            }
        };
        once(&mut self.evicted, r.status.contains(Flag::Evicted), &|| {
            evicted(r, &caps, max_range)
        });
        let map_dropped = r.dropped.map_voxels_full + r.dropped.map_points_full;
        once(&mut self.map_full, map_dropped > 0, &|| {
            format!(
                "the sensor's near field alone overfills the local map: {map_dropped} of the \
                 scan's points dropped (map_voxels = {}, map_points = {})",
                caps.map_voxels, caps.map_points
            )
        });
        once(&mut self.merge_full, r.dropped.merge_full > 0, &|| {
            format!(
                "the merge cloud is full (merge_points = {}): {} voxels of the scan not added \
                 to the map",
                caps.merge_points, r.dropped.merge_full
            )
        });
        once(&mut self.source_full, r.dropped.source_full > 0, &|| {
            format!(
                "the registration cloud is full (source_points = {}): {} voxels of the scan \
                 not registered",
                caps.source_points, r.dropped.source_full
            )
        });
        out
    }
}

/// What an eviction did, in words.
fn evicted(r: &FrameReport<f64>, caps: &Capacities, max_range: f64) -> String {
    let filled = r.map_filled.map_or("the map", |c| c.name());
    let size = match r.map_filled {
        Some(kiss_odom_core::MapCapacity::Points) => caps.map_points,
        _ => caps.map_voxels,
    };
    let radius = if r.map_radius < max_range {
        format!(
            "its radius shrank to {:.1} m of max_range {max_range} m, as a smaller max_range \
             would have it, and the poses now differ from an unbounded map's",
            r.map_radius
        )
    } else {
        format!("its radius stays max_range {max_range} m")
    };
    format!(
        "the local map filled ({filled} = {size}) and gave up its {} farthest voxels: {radius}",
        r.evicted_voxels
    )
}
