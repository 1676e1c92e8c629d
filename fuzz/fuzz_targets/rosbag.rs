//! ROS 1 bags (`io::ros::bag::open`, path only: a tmpfs file), streamed to the end or the first
//! container error; then, where the source can seek, back to frame 0, which must read the same
//! as the first time (apart from warnings about the whole bag, which are given once; compared as text, so
//! NaN coordinates read twice count as equal).
#![no_main]

mod common;

use kiss_odom_io::ros::bag as rosbag;
use kiss_odom_io::{Item, OpenOptions};
use libfuzzer_sys::fuzz_target;

/// Items read at most (a bag of many empty messages would otherwise take long).
const MAX_ITEMS: usize = 256;

fuzz_target!(|data: &[u8]| {
    let path = common::scratch_file("in.bag", data);
    let Ok(mut dataset) = rosbag::open(&path, &OpenOptions::default()) else {
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
            // Compared as text: NaN coordinates are legal input and NaN != NaN.
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
