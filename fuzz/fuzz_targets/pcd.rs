//! PCD scans (`io::folders::pcd::read`, path only: the bytes go to a tmpfs file). Any bytes give a cloud
//! or an error, never a panic; a cloud's stamps, if any, are one per point.
#![no_main]

mod common;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = common::scratch_file("scan.pcd", data);
    if let Ok(cloud) = kiss_odom_io::folders::pcd::read(&path) {
        if let Some(s) = &cloud.stamps {
            assert_eq!(s.len(), cloud.points.len());
        }
    }
});
