//! KITTI-style `.bin` scans: little-endian `f32` x, y, z, intensity, 16 bytes a point, no
//! header.
//!
//! The format has no per-point times and no length field, so the only check possible is the
//! file length: an empty file or one whose length is not a whole number of points is not a scan.
//! The length comes from the file system, so a frame is checked, and cut at the scan capacity,
//! before any byte of it is read.

use super::file_cloud::Cloud;
use anyhow::{Context, Result};
use std::fmt;
use std::io::Read;
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

/// Checks a file length: the number of points it holds.
pub fn points_in(len: u64) -> Result<usize, BinError> {
    let n = usize::try_from(len).unwrap_or(usize::MAX);
    if n == 0 {
        return Err(BinError::Empty);
    }
    if n % POINT_BYTES != 0 {
        return Err(BinError::Length(n));
    }
    Ok(n / POINT_BYTES)
}

/// Reads at most the first `max_points` points of the scan at `path`; only those bytes are
/// read, so a huge file costs no more memory than a full scan.
pub fn read_at_most(path: &Path, max_points: usize) -> Result<Cloud> {
    let file = std::fs::File::open(path)?;
    let declared = points_in(file.metadata()?.len())?;
    let keep = declared.min(max_points);
    let mut bytes = Vec::with_capacity(keep * POINT_BYTES);
    file.take((keep * POINT_BYTES) as u64)
        .read_to_end(&mut bytes)?;
    if bytes.len() != keep * POINT_BYTES {
        anyhow::bail!("file shrank while it was read");
    }
    Ok(Cloud {
        points: parse(&bytes)?,
        stamps: None,
        declared,
    })
}

/// Reads the whole scan at `path` (see [`parse`]).
pub fn read(path: &Path) -> Result<Vec<[f64; 3]>> {
    Ok(read_at_most(path, usize::MAX)?.points)
}

/// The `.bin` bytes of `points`, narrowed to `f32`, intensity 0.
pub fn encode(points: &[[f64; 3]]) -> Vec<u8> {
    encode_with_intensity(points, None)
}

/// The `.bin` bytes of `points`, narrowed to `f32`, with `intensity` (one per point; 0 for
/// points it has none for).
pub fn encode_with_intensity(points: &[[f64; 3]], intensity: Option<&[f32]>) -> Vec<u8> {
    let mut out = Vec::with_capacity(points.len() * POINT_BYTES);
    for (k, p) in points.iter().enumerate() {
        let i = intensity.and_then(|i| i.get(k)).copied().unwrap_or(0.0);
        for v in [p[0] as f32, p[1] as f32, p[2] as f32, i] {
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
    fn reading_at_most_n_points_reads_only_those() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.bin");
        let points = vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]];
        write(&path, &points).unwrap();
        let cloud = read_at_most(&path, 2).unwrap();
        assert_eq!(cloud.points, points[..2]);
        assert_eq!(cloud.declared, 3);
        let whole = read_at_most(&path, 3).unwrap();
        assert_eq!((whole.points.len(), whole.declared), (3, 3));
        std::fs::write(&path, [0u8; 20]).unwrap();
        let e = read_at_most(&path, 1).unwrap_err().to_string();
        assert!(e.contains("length 20"), "{e}");
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
