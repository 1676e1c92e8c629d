//! ROS 2 MCAP files (`io::ros::mcap::open`, path only: a tmpfs file), streamed to the end or the
//! first container error.
#![no_main]

mod common;

use kiss_odom_io::ros::mcap;
use kiss_odom_io::OpenOptions;
use libfuzzer_sys::fuzz_target;

/// Items read at most.
const MAX_ITEMS: usize = 256;

fuzz_target!(|data: &[u8]| {
    let path = common::scratch_file("in.mcap", data);
    let Ok(mut dataset) = mcap::open(&path, &OpenOptions::default()) else {
        return;
    };
    for _ in 0..MAX_ITEMS {
        match dataset.frames.next_item() {
            Ok(Some(_)) => {}
            Ok(None) | Err(_) => break,
        }
    }
});
