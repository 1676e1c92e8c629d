//! ROS 2 MCAP files (`io::ros::mcap::open`, path only: a tmpfs file), streamed to the end or the
//! first container error.
#![no_main]

mod common;

use kiss_odom_io::ros::mcap;
use kiss_odom_io::OpenOptions;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = common::scratch_file("in.mcap", data);
    if let Ok(mut dataset) = mcap::open(&path, &OpenOptions::default()) {
        common::stream(dataset.frames.as_mut(), false);
    }
});
