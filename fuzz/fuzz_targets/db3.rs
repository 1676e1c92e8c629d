//! ROS 2 sqlite3 bags (`io::ros::db3::open`, one `.db3` file: a tmpfs file), streamed to the
//! end or the first container error, whatever topic they hold (point clouds, sensor packets,
//! Livox points); then, where the source can seek, back to frame 0, which must read the same
//! as the first time (apart from warnings; compared as text, so NaN coordinates read twice
//! count as equal).
#![no_main]

mod common;

use kiss_odom_io::ros::db3;
use kiss_odom_io::{Item, OpenOptions};
use libfuzzer_sys::fuzz_target;

/// Items read at most.
const MAX_ITEMS: usize = 256;

fuzz_target!(|data: &[u8]| {
    let path = common::scratch_file("in.db3", data);
    let Ok(mut dataset) = db3::open(&path, &OpenOptions::default()) else {
        return;
    };
    let src = &mut dataset.frames;
    let mut first = None;
    for _ in 0..MAX_ITEMS {
        match src.next_item() {
            Ok(Some(item)) => {
                first.get_or_insert(item);
            }
            Ok(None) | Err(_) => break,
        }
    }
    if let Some(first) = first {
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
});

fn without_warnings(mut item: Item) -> Item {
    if let Item::Frame(f) = &mut item {
        f.warnings.clear();
    }
    item
}
