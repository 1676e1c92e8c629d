//! IMU samples as the readers hand them on with each frame, and `imu.csv`, the file `convert`
//! writes beside the frames: one row per sample, `time,gyro_x,gyro_y,gyro_z,accel_x,accel_y,
//! accel_z`, time in seconds on the sensor's clock (the frames' `stamps` clock), angular rate in
//! rad/s and specific force in m/s^2, both in the IMU's own axes as the sensor sends them.

pub mod attach;

/// One IMU sample: defined with the frames that carry it ([`crate::dataset`]), so that the
/// readers' vocabulary depends on nothing else of this crate.
pub use crate::dataset::ImuSample;

use anyhow::{bail, Context, Result};
use std::fmt::Write as _;
use std::path::Path;

/// Standard gravity, m/s^2: what one g is when a sensor sends specific force in g.
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// The file's name beside the frames.
pub const CSV_NAME: &str = "imu.csv";

/// Its header row.
pub const CSV_HEADER: &str = "time,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z";

/// A sample from a sensor's units, and its `imu.csv` row.
impl ImuSample {
    /// A sample from what a sensor sends: angular rate in rad/s, specific force in g.
    pub fn from_g(time_ns: u64, gyro: [f32; 3], accel_g: [f32; 3]) -> Self {
        Self {
            time_ns,
            gyro: gyro.map(f64::from),
            accel: accel_g.map(|a| f64::from(a) * STANDARD_GRAVITY),
        }
    }

    /// Its `imu.csv` row, with a line end: the time to the nanosecond, the rest as Rust prints
    /// an f64 (the shortest text that reads back to the same number).
    pub fn push_csv_row(&self, out: &mut String) {
        let (s, ns) = (self.time_ns / 1_000_000_000, self.time_ns % 1_000_000_000);
        let [gx, gy, gz] = self.gyro;
        let [ax, ay, az] = self.accel;
        let _ = writeln!(out, "{s}.{ns:09},{gx},{gy},{gz},{ax},{ay},{az}");
    }
}

/// Reads an `imu.csv`: the header, then one sample per row, times not decreasing.
pub fn read_csv(path: &Path) -> Result<Vec<ImuSample>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read", path.display()))?;
    let mut lines = text.lines();
    if lines.next().map(str::trim) != Some(CSV_HEADER) {
        bail!("{}: the first line is not `{CSV_HEADER}`", path.display());
    }
    let mut out: Vec<ImuSample> = Vec::new();
    for (n, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let row = n + 2;
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != 7 {
            bail!("{}:{row}: {} columns, not 7", path.display(), f.len());
        }
        let t = f[0];
        let num = |s: &str| -> Result<f64> {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .with_context(|| format!("{}:{row}: `{s}` is not a number", path.display()))
        };
        let time_ns = parse_time_ns(t)
            .with_context(|| format!("{}:{row}: `{t}` is not a time in seconds", path.display()))?;
        let v: Vec<f64> = f[1..].iter().map(|s| num(s)).collect::<Result<_>>()?;
        if out.last().is_some_and(|p| p.time_ns > time_ns) {
            bail!("{}:{row}: time goes back", path.display());
        }
        out.push(ImuSample {
            time_ns,
            gyro: [v[0], v[1], v[2]],
            accel: [v[3], v[4], v[5]],
        });
    }
    Ok(out)
}

/// Seconds with up to nine decimals, to whole nanoseconds.
fn parse_time_ns(t: &str) -> Option<u64> {
    let (s, frac) = t.split_once('.').unwrap_or((t, ""));
    if frac.len() > 9 || !frac.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let ns: u64 = format!("{frac:0<9}").parse().ok()?;
    s.parse::<u64>()
        .ok()?
        .checked_mul(1_000_000_000)?
        .checked_add(ns)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_read_back_to_the_same_samples() {
        let samples = [
            ImuSample::from_g(
                1_635_444_808_691_218_001,
                [0.45, -0.66, 0.14],
                [-0.001, 0.05, 1.01],
            ),
            ImuSample::from_g(
                1_635_444_808_701_218_000,
                [1e-7, 0.0, -3.25],
                [0.0, 0.0, -1.0],
            ),
        ];
        let mut text = format!("{CSV_HEADER}\n");
        for s in &samples {
            s.push_csv_row(&mut text);
        }
        assert!(text.contains("1635444808.691218001,"), "{text}");
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(CSV_NAME);
        std::fs::write(&path, &text).unwrap();
        assert_eq!(read_csv(&path).unwrap(), samples);
        assert_eq!(samples[1].accel[2], -STANDARD_GRAVITY);
        for bad in [
            "1.0,1,2,3,4,5",
            "x,1,2,3,4,5,6",
            "1.0,1,2,nan,4,5,6",
            "1.0000000001,1,2,3,4,5,6",
        ] {
            std::fs::write(&path, format!("{CSV_HEADER}\n{bad}\n")).unwrap();
            assert!(read_csv(&path).is_err(), "{bad}");
        }
        std::fs::write(
            &path,
            format!("{CSV_HEADER}\n2,0,0,0,0,0,0\n1,0,0,0,0,0,0\n"),
        )
        .unwrap();
        assert!(read_csv(&path)
            .unwrap_err()
            .to_string()
            .contains("time goes back"));
    }
}
