//! What `build.rs` generated for this build's profile: the embedded frames' places and the
//! constants the workload is configured from (range, voxel size, work budget, and per profile
//! the packet length, the IMU samples' places or the pose port).

/// Where one frame sits in the embedded point data.
#[cfg_attr(any(feature = "packets", feature = "net"), allow(dead_code))]
pub struct FrameInfo {
    /// First point.
    pub start: usize,
    /// Points kept.
    pub len: usize,
    /// Points in the scan file.
    pub raw: usize,
    /// Points after the range crop.
    pub cropped: usize,
    /// First and last capture time of the sweep (`tiny`; 0 otherwise).
    pub t_min: f64,
    /// See `t_min`.
    pub t_max: f64,
}

include!(concat!(env!("OUT_DIR"), "/frames.rs"));
