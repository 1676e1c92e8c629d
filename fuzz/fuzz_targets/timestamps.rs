//! The generic layout's time files: per-point `timestamps/<stem>.bin` (`parse_timestamps`, f64
//! little-endian) and per-frame `times.txt` (`read_times`, path only: a tmpfs file).
#![no_main]

mod common;

use kiss_odom_io::folders::generic::{parse_timestamps, read_times};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    match parse_timestamps(data) {
        Ok(t) => {
            assert_eq!(t.len() * 8, data.len());
            for (v, c) in t.iter().zip(data.chunks_exact(8)) {
                assert_eq!(v.to_le_bytes(), c);
            }
        }
        Err(_) => assert!(data.len() % 8 != 0),
    }
    let path = common::scratch_file("times.txt", data);
    if let Ok(times) = read_times(&path) {
        assert!(
            times.iter().all(|t| t.is_finite()),
            "non-finite time accepted"
        );
    }
});
