//! Sensor recordings (`io::capture::sweeps::open`, path only: a tmpfs file): the capture reader,
//! the Ethernet/IP/UDP parsing with reassembly, sensor detection and the Velodyne decoder, read
//! to the end or the first error.
#![no_main]

mod common;

use kiss_odom_io::capture::sweeps::open;
use kiss_odom_io::SensorOptions;
use libfuzzer_sys::fuzz_target;

/// Sweeps read at most.
const MAX_SWEEPS: usize = 64;

fuzz_target!(|data: &[u8]| {
    let path = common::scratch_file("in.pcap", data);
    let Ok(sweeps) = open(&path, &SensorOptions::default()) else {
        return;
    };
    for s in sweeps.take(MAX_SWEEPS) {
        match s {
            Ok(s) => assert!(s.points.len() == s.times.len() && s.times.len() == s.meta.len()),
            Err(_) => break,
        }
    }
});
