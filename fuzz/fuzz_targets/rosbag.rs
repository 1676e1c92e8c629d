//! ROS 1 bags (`io::ros::bag::open`, path only: a tmpfs file), streamed to the end or the first
//! container error; then, where the source can seek, back to frame 0, which must read the same
//! as the first time (`common::stream`).
#![no_main]

mod common;

use kiss_odom_io::ros::bag as rosbag;
use kiss_odom_io::OpenOptions;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = common::scratch_file("in.bag", data);
    if let Ok(mut dataset) = rosbag::open(&path, &OpenOptions::default()) {
        common::stream(dataset.frames.as_mut(), true);
    }
});
