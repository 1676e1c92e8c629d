//! Helpers shared by the fuzz targets.
#![allow(dead_code)]

use kiss_odom_io::{FrameSource, Item};
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

/// Items a container target reads at most (a container of many empty messages would otherwise
/// take long).
pub const MAX_ITEMS: usize = 256;

/// Streams `src` to its end, the first error or [`MAX_ITEMS`]; then, if `seek` and the source
/// can seek, back to frame 0, which must read as it did the first time (apart from warnings,
/// which a source may give once; compared as text: NaN coordinates are legal input and
/// NaN != NaN).
pub fn stream(src: &mut dyn FrameSource, seek: bool) {
    let mut first = None;
    for _ in 0..MAX_ITEMS {
        match src.next_item() {
            Ok(Some(item)) => {
                first.get_or_insert(item);
            }
            Ok(None) | Err(_) => break,
        }
    }
    let Some(first) = first.filter(|_| seek) else {
        return;
    };
    if src.seek(0) {
        let again = src
            .next_item()
            .expect("frame 0 read before")
            .expect("frame 0 exists");
        assert_eq!(
            format!("{:?}", without_warnings(again)),
            format!("{:?}", without_warnings(first)),
            "frame 0 reads differently after seek(0)"
        );
    }
}

fn without_warnings(mut item: Item) -> Item {
    if let Item::Frame(f) = &mut item {
        f.warnings.clear();
    }
    item
}
