//! What a per-file frame reader (`bin`, `ply`, `pcd`) hands to the generic layout: the points of
//! one file, their per-point times, and how many points the file had beyond the scan capacity.
//!
//! Readers take at most `max_points` points ([`crate::OpenOptions::scan_points`]) so that the
//! memory a frame costs is bounded by the configuration, not by the file; the core would ignore
//! the points past its scan capacity anyway.

/// Names of a per-point time field, in the order the reference looks them up
/// (`kiss_icp/datasets/generic.py`): the first one a file has is used.
pub const STAMP_FIELDS: [&str; 5] = ["t", "timestamp", "timestamps", "time", "stamps"];

/// Points of one file and their per-point times, if the file has them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Cloud {
    /// Points in metres, sensor frame.
    pub points: Vec<[f64; 3]>,
    /// One time per point, in the file's unit and offset.
    pub stamps: Option<Vec<f64>>,
    /// Points the file declares in all (more than `points.len()` when it was truncated).
    pub declared: usize,
}

impl Cloud {
    /// The warning for a cloud that was cut at the scan capacity, if it was.
    pub fn truncation_warning(&self) -> Option<String> {
        (self.declared > self.points.len())
            .then(|| truncation_warning(self.points.len(), self.declared))
    }
}

/// "read the first N of M points" with the reason, for a frame cut at the scan capacity.
pub fn truncation_warning(kept: usize, declared: usize) -> String {
    format!(
        "read the first {kept} of {declared} points (the scan capacity, `scan_points`); \
         the rest of the frame is ignored"
    )
}
