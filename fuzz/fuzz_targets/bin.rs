//! KITTI `.bin` scans (`io::folders::bin::parse`): accepted exactly when the length is a positive
//! multiple of 16, one point per 16 bytes, and `encode` then `parse` gives the points back.
#![no_main]

mod common;

use kiss_odom_io::folders::bin::{encode, parse, POINT_BYTES};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    match parse(data) {
        Ok(points) => {
            assert!(!data.is_empty() && data.len() == points.len() * POINT_BYTES);
            let back = parse(&encode(&points)).expect("encoded points parse");
            assert_eq!(back.len(), points.len());
            for (a, b) in points.iter().flatten().zip(back.iter().flatten()) {
                assert!(common::same(*a, *b), "{a:e} came back as {b:e}");
            }
        }
        Err(_) => assert!(data.is_empty() || data.len() % POINT_BYTES != 0),
    }
});
