//! The PandarAT128's angle correction file (the `.dat` the sensor hands out and Hesai ships)
//! into the Hesai decoder's [`At128Correction`]: version 1.5, all fields little-endian.
//!
//! ```text
//! 0..2     delimiter EE FF
//! 2, 3     version, major 1 and minor 5
//! 4        channels (128)
//! 5        mirrors (3): how many start and end angles follow
//! 6        frames (3): how many of them the decoder uses
//! 7..15    frame configuration (not used)
//! 15       resolution: every angle below is in its multiples
//! 16..     start angles, mirrors x u32  (x resolution / 25,600 degree: the motor angle where
//!          each frame begins)
//!          end angles, mirrors x u32
//!          azimuth, channels x i32      (x resolution / 25,600 degree)
//!          elevation, channels x i32
//!          azimuth adjustment, channels x 180 i8    (x resolution / 100 degree, 2 degrees of
//!          elevation adjustment, channels x 180 i8   motor angle apart)
//!          SHA-256 of everything before it, 32 bytes
//! ```
//!
//! The layout is that of nebula's `HesaiCorrection::load_from_bytes` (version 1.5) and Hesai's
//! SDK 2.0 `Udp4_3Parser::LoadCorrectionString`; the SHA-256 covers the bytes before it in
//! every file they ship (nebula's `PandarAT128.dat` and `.dat.2209`, the SDK's `AT128E2X` and
//! `AT128E3X`). A file that does not begin with the delimiter is refused (an encrypted file,
//! or one of another format: this reader does not decrypt), as are other versions (1.3,
//! which nebula reads but marks "not worked", and the SDK's later ones) and a file whose
//! SHA-256 does not match (damaged or altered).

use anyhow::{bail, Context, Result};
use kiss_odom_sensors::hesai::{At128Correction, ADJUST_STEPS, AT128_CHANNELS, MAX_FRAMES};
use sha2::{Digest, Sha256};
use std::path::Path;

/// Byte offsets of the header.
pub mod field {
    use std::ops::Range;
    /// The delimiter, `EE FF`.
    pub const DELIMITER: Range<usize> = 0..2;
    /// Version, major then minor.
    pub const VERSION: Range<usize> = 2..4;
    /// Channels.
    pub const CHANNELS: usize = 4;
    /// Mirrors: start and end angles stored.
    pub const MIRRORS: usize = 5;
    /// Frames used.
    pub const FRAMES: usize = 6;
    /// Resolution: the multiple every angle is stored in.
    pub const RESOLUTION: usize = 15;
    /// Where the tables begin.
    pub const TABLES: usize = 16;
    /// The SHA-256 at the end.
    pub const SHA256_LEN: usize = 32;
}

/// The delimiter.
pub const DELIMITER: [u8; 2] = [0xEE, 0xFF];
/// The version read.
pub const VERSION: [u8; 2] = [1, 5];

/// The length of a version 1.5 file of `mirrors` mirrors and `channels` channels.
pub fn file_len(mirrors: usize, channels: usize) -> usize {
    field::TABLES + 8 * mirrors + 8 * channels + 2 * ADJUST_STEPS * channels + field::SHA256_LEN
}

/// Reads an AT128's angle correction file.
pub fn read(path: &Path) -> Result<At128Correction> {
    let bytes = std::fs::read(path).with_context(|| format!("{}", path.display()))?;
    parse(&bytes).with_context(|| {
        format!(
            "{}: not a PandarAT128 angle correction file (.dat, version 1.5)",
            path.display()
        )
    })
}

/// Parses the bytes of an AT128's angle correction file (see the module doc).
pub fn parse(b: &[u8]) -> Result<At128Correction> {
    if b.get(field::DELIMITER) != Some(&DELIMITER[..]) {
        bail!(
            "it does not begin with the delimiter EE FF: an encrypted file or another format \
             (this reader takes the plain .dat the sensor or Hesai's tools give)"
        );
    }
    let version = b.get(field::VERSION).unwrap_or_default();
    if version != VERSION {
        bail!(
            "version {}.{}: only version 1.5 is read",
            version.first().copied().unwrap_or(0),
            version.get(1).copied().unwrap_or(0)
        );
    }
    let byte = |at: usize| usize::from(b.get(at).copied().unwrap_or(0));
    let (channels, mirrors, frames) = (
        byte(field::CHANNELS),
        byte(field::MIRRORS),
        byte(field::FRAMES),
    );
    if channels != AT128_CHANNELS {
        bail!("{channels} channels: an AT128 has {AT128_CHANNELS}");
    }
    if !(1..=MAX_FRAMES).contains(&mirrors) || !(1..=mirrors).contains(&frames) {
        bail!("{frames} frames of {mirrors} mirrors: 1 to {MAX_FRAMES} frames, no more than the mirrors");
    }
    let want = file_len(mirrors, channels);
    if b.len() != want {
        bail!("{} bytes: its header's tables need {want}", b.len());
    }
    let (body, sha) = b.split_at(want - field::SHA256_LEN);
    if Sha256::digest(body).as_slice() != sha {
        bail!("its SHA-256 (the last 32 bytes) does not match its contents: damaged or altered");
    }
    let resolution = b.get(field::RESOLUTION).copied().unwrap_or(0);
    if resolution == 0 {
        bail!("resolution 0");
    }
    let mut c = At128Correction::empty();
    c.frames = frames;
    c.adjust_unit = resolution;
    let mut at = field::TABLES;
    let mut word = || {
        let w = b.get(at..at + 4).and_then(|w| w.try_into().ok());
        at += 4;
        w.map(i32::from_le_bytes).unwrap_or(0)
    };
    let scale = i64::from(resolution);
    let scaled = |v: i64| i32::try_from(v * scale).context("an angle beyond 32 bits");
    let starts: Vec<i64> = (0..mirrors).map(|_| i64::from(word() as u32)).collect();
    let ends: Vec<i64> = (0..mirrors).map(|_| i64::from(word() as u32)).collect();
    for (i, (s, e)) in starts.iter().zip(&ends).take(frames).enumerate() {
        c.start[i] = u32::try_from(s * scale).context("a frame angle beyond 32 bits")?;
        c.end[i] = u32::try_from(e * scale).context("a frame angle beyond 32 bits")?;
    }
    for a in c.azimuth.iter_mut() {
        *a = scaled(i64::from(word()))?;
    }
    for e in c.elevation.iter_mut() {
        *e = scaled(i64::from(word()))?;
    }
    for table in [&mut c.azimuth_adjust, &mut c.elevation_adjust] {
        for row in table.iter_mut() {
            let bytes = b.get(at..at + ADJUST_STEPS).unwrap_or_default();
            for (v, raw) in row.iter_mut().zip(bytes) {
                *v = *raw as i8;
            }
            at += ADJUST_STEPS;
        }
    }
    if c.validate().is_err() {
        bail!(
            "a frame angle at or beyond 360 degrees, a channel azimuth beyond 45 degrees or an \
             elevation beyond 90"
        );
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use kiss_odom_sensors::hesai::UNITS_PER_DEG;

    /// A file of 3 frames at resolution 2 with recognisable values.
    fn file() -> Vec<u8> {
        let mut b = vec![0xEE, 0xFF, 1, 5, 128, 3, 3, 1, 2, 4, 0, 0, 0, 0, 0, 2];
        for v in [
            10_000u32, 1_546_000, 3_082_000, 1_546_000, 3_082_000, 10_000,
        ] {
            b.extend(v.to_le_bytes());
        }
        for c in 0..128i32 {
            b.extend((if c % 2 == 0 { -30_720i32 } else { 8_320 }).to_le_bytes());
        }
        for c in 0..128i32 {
            b.extend((165_000 - 2_560 * c).to_le_bytes());
        }
        for c in 0..2 * 128 {
            b.extend((0..180).map(|i| ((i + c) % 7) as u8));
        }
        let sha = Sha256::digest(&b);
        b.extend(sha);
        b
    }

    #[test]
    fn a_file_fills_every_table_times_its_resolution() {
        let c = parse(&file()).unwrap();
        assert_eq!(c.frames, 3);
        assert_eq!(c.start[..3], [20_000, 3_092_000, 6_164_000]);
        assert_eq!(c.end[2], 20_000);
        assert_eq!((c.azimuth[0], c.azimuth[1]), (-61_440, 16_640));
        // Channel 0's elevation: 165,000 x 2 units, 12.89 degrees.
        assert_eq!(c.elevation[0], 330_000);
        assert!((f64::from(c.elevation[0]) / f64::from(UNITS_PER_DEG) - 12.890625).abs() < 1e-12);
        assert_eq!(c.adjust_unit, 2);
        assert_eq!(
            (c.azimuth_adjust[0][3], c.elevation_adjust[0][0]),
            (3, (128 % 7) as i8)
        );
    }

    #[test]
    fn encrypted_damaged_and_other_files_are_refused_with_the_reason() {
        let good = file();
        let why = |b: &[u8]| format!("{:#}", parse(b).unwrap_err());
        // Encrypted (no cleartext delimiter) or another format.
        let mut enc = good.clone();
        enc[..4].copy_from_slice(&[0x9C, 0x41, 0x07, 0xD2]);
        assert!(why(&enc).contains("encrypted"), "{}", why(&enc));
        let mut v13 = good.clone();
        v13[3] = 3;
        assert!(why(&v13).contains("version 1.3"));
        let mut flipped = good.clone();
        flipped[5000] ^= 1;
        assert!(why(&flipped).contains("SHA-256"));
        assert!(why(&good[..good.len() - 1]).contains("bytes"));
        let mut wide = good.clone();
        wide[4] = 64;
        assert!(why(&wide).contains("64 channels"));
        let mut frames = good.clone();
        frames[6] = 4;
        assert!(why(&frames).contains("4 frames of 3 mirrors"));
    }
}
