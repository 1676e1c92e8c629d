//! KITTI-style `.bin` scans: little-endian `f32` x, y, z, intensity, 16 bytes a point, no
//! header.
//!
//! The format has no per-point times and no length field, so the only check possible is the
//! file length: an empty file or one whose length is not a whole number of points is not a scan.

use anyhow::{Context, Result};
use std::fmt;
use std::path::Path;

/// Bytes per point: x, y, z, intensity as little-endian `f32`.
pub const POINT_BYTES: usize = 16;

/// Why bytes are not a `.bin` scan. The caller skips the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinError {
    /// The file has no bytes.
    Empty,
    /// The length (in bytes) is not a multiple of [`POINT_BYTES`]: truncated or not a scan.
    Length(usize),
}

impl fmt::Display for BinError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BinError::Empty => write!(f, "empty file"),
            BinError::Length(n) => {
                write!(f, "length {n} is not a multiple of {POINT_BYTES} bytes")
            }
        }
    }
}

impl std::error::Error for BinError {}

/// The points in `bytes`, widened to `f64`; intensity is dropped.
pub fn parse(bytes: &[u8]) -> Result<Vec<[f64; 3]>, BinError> {
    if bytes.is_empty() {
        return Err(BinError::Empty);
    }
    if bytes.len() % POINT_BYTES != 0 {
        return Err(BinError::Length(bytes.len()));
    }
    let f32_at = |b: &[u8], i: usize| f32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
    Ok(bytes
        .chunks_exact(POINT_BYTES)
        .map(|p| [f32_at(p, 0), f32_at(p, 4), f32_at(p, 8)].map(f64::from))
        .collect())
}

/// Reads the scan at `path` (see [`parse`]).
pub fn read(path: &Path) -> Result<Vec<[f64; 3]>> {
    let bytes = std::fs::read(path)?;
    Ok(parse(&bytes)?)
}

/// The `.bin` bytes of `points`, narrowed to `f32`, intensity 0.
pub fn encode(points: &[[f64; 3]]) -> Vec<u8> {
    let mut out = Vec::with_capacity(points.len() * POINT_BYTES);
    for p in points {
        for v in [p[0] as f32, p[1] as f32, p[2] as f32, 0.0] {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// Writes `points` as a `.bin` scan (see [`encode`]; coordinates lose precision to `f32`).
pub fn write(path: &Path, points: &[[f64; 3]]) -> Result<()> {
    std::fs::write(path, encode(points)).with_context(|| format!("{}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_exact_in_f32_round_trip_exactly() {
        let points = vec![[1.5, -2.25, 1e-3_f32 as f64], [0.0, 80.0, -1.75]];
        let bytes = encode(&points);
        assert_eq!(bytes.len(), 2 * POINT_BYTES);
        assert_eq!(parse(&bytes).unwrap(), points);
    }

    #[test]
    fn layout_is_little_endian_xyzi() {
        let mut bytes = Vec::new();
        for v in [1.0f32, 2.0, 3.0, 0.5] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        assert_eq!(parse(&bytes).unwrap(), vec![[1.0, 2.0, 3.0]]);
    }

    #[test]
    fn empty_and_partial_points_are_errors() {
        assert_eq!(parse(&[]), Err(BinError::Empty));
        assert_eq!(parse(&[0; 1000]), Err(BinError::Length(1000)));
        assert_eq!(
            BinError::Length(1000).to_string(),
            "length 1000 is not a multiple of 16 bytes"
        );
    }
}
