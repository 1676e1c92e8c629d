//! Pose datagrams (`sensors::pose_datagram::PoseDatagram::decode`), what `listen-poses` reads
//! off the network: accepted exactly when 160 bytes start with `KOPD` and version 1, and then
//! encoding gives back the very bytes (every byte is a field; NaN payloads included).
#![no_main]

use kiss_odom_sensors::pose_datagram::{field, PoseDatagram, MAGIC, VERSION};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let well_formed = data.len() == field::LEN
        && data[field::MAGIC] == MAGIC
        && data[field::VERSION] == VERSION.to_le_bytes();
    match PoseDatagram::decode(data) {
        Ok(d) => {
            assert!(well_formed);
            assert_eq!(&d.encode()[..], data);
        }
        Err(_) => assert!(!well_formed),
    }
});
