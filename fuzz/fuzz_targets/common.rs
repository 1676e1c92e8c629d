//! Helpers shared by the fuzz targets.
#![allow(dead_code)]

use std::path::PathBuf;

/// Writes `data` to a file on tmpfs (or the temp dir) named after this process and `name`, for
/// readers that only take a path. The same file is overwritten on every run of the target.
pub fn scratch_file(name: &str, data: &[u8]) -> PathBuf {
    let shm = std::path::Path::new("/dev/shm");
    let dir = if shm.is_dir() {
        shm.to_path_buf()
    } else {
        std::env::temp_dir()
    };
    let path = dir.join(format!("kiss-odom-fuzz-{}-{name}", std::process::id()));
    std::fs::write(&path, data).expect("cannot write the scratch file");
    path
}

/// Whether every coordinate of every point is finite.
pub fn all_finite(points: &[[f64; 3]]) -> bool {
    points.iter().flatten().all(|v| v.is_finite())
}

/// Same value, or both NaN (payloads may be quietened by conversions).
pub fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}
