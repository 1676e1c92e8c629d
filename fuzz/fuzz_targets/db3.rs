//! ROS 2 sqlite3 bags (`io::ros::db3::open`, one `.db3` file: a tmpfs file), streamed to the
//! end or the first container error, whatever topic they hold (point clouds, sensor packets,
//! Livox points); then, where the source can seek, back to frame 0, which must read the same
//! as the first time (`common::stream`).
#![no_main]

mod common;

use kiss_odom_io::ros::db3;
use kiss_odom_io::OpenOptions;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = common::scratch_file("in.db3", data);
    if let Ok(mut dataset) = db3::open(&path, &OpenOptions::default()) {
        common::stream(dataset.frames.as_mut(), true);
    }
});
