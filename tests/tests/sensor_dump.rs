//! The records `tests/sensors/dump_reference.py` (and `dump_generated.py`) write: one
//! reference point per 48 bytes (`RECORD` there), shared by the tests that read them.

// Each test binary uses a part of it.
#![allow(dead_code)]

use kiss_odom_sensors::Return;
use std::path::Path;

/// One reference point.
#[derive(Clone, Copy, Debug)]
pub struct RefPoint {
    pub sweep: u32,
    pub ring: u16,
    pub column: u16,
    pub ret: u8,
    pub dcol: u16,
    pub xyz: [f64; 3],
    pub t_ns: f64,
}

pub type Key = (u32, u16, u16, u8);

impl RefPoint {
    pub fn key(&self) -> Key {
        (self.sweep, self.ring, self.column, self.ret)
    }
}

/// The reference's return codes: velodyne-decoder's (1 strongest, 2 last, 3 both); for
/// Ouster 1 for RANGE, 2 for RANGE2.
pub fn code(r: Return) -> u8 {
    match r {
        Return::Strongest | Return::First => 1,
        Return::Last | Return::Second => 2,
        Return::Both => 3,
    }
}

/// Every record of a dump file.
pub fn read_dump(path: &Path) -> Vec<RefPoint> {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(bytes.len() % 48, 0, "{}", path.display());
    let f = |r: &[u8], at: usize| f64::from_le_bytes(r[at..at + 8].try_into().unwrap());
    let u16_at = |r: &[u8], at: usize| u16::from_le_bytes([r[at], r[at + 1]]);
    bytes
        .chunks_exact(48)
        .map(|r| RefPoint {
            sweep: u32::from_le_bytes(r[0..4].try_into().unwrap()),
            ring: u16_at(r, 4),
            column: u16_at(r, 6),
            ret: r[8],
            dcol: u16_at(r, 10),
            xyz: [f(r, 16), f(r, 24), f(r, 32)],
            t_ns: f(r, 40),
        })
        .collect()
}

/// The per-sweep point counts of a dump's JSON.
pub fn counts_of(json: &serde_json::Value) -> Vec<usize> {
    json["counts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_u64().unwrap() as usize)
        .collect()
}
