//! Talking to the reference: `tests/reference/driver.py` run by a Python that has kiss-icp
//! 1.3.0, with inputs and outputs exchanged as files in a private temporary folder.
//!
//! Points and scalars go out as raw little-endian `f64` (the driver's format for any extension
//! other than `.npy`/`.json`), poses as 16 row-major numbers printed in the shortest form that
//! parses back to the same bits, so both implementations see identical inputs.

use anyhow::{bail, Context, Result};
use nalgebra::{Isometry3, Matrix4};
use std::ffi::{OsStr, OsString};
use std::path::{Path, PathBuf};
use std::process::Command;

/// A driver session: the interpreter, the script and a temporary folder for the exchange.
pub struct Driver {
    python: PathBuf,
    script: PathBuf,
    dir: tempfile::TempDir,
    files: usize,
    /// `driver.py info`: versions of kiss-icp, numpy and Python.
    pub versions: serde_json::Value,
}

impl Driver {
    /// Starts a session and checks that the reference imports (`driver.py info`).
    pub fn new(python: PathBuf, script: PathBuf) -> Result<Self> {
        let dir = tempfile::Builder::new()
            .prefix("kiss-odom-crosscheck")
            .tempdir()
            .context("cannot create a temporary folder")?;
        let mut d = Self {
            python,
            script,
            dir,
            files: 0,
            versions: serde_json::Value::Null,
        };
        let out = d.output([OsStr::new("info")])?;
        d.versions = serde_json::from_slice(&out)
            .with_context(|| format!("{}: `info` did not print JSON", d.script.display()))?;
        Ok(d)
    }

    /// The versions as one line: `kiss-icp 1.3.0, numpy 2.4.6, Python 3.11.2`.
    pub fn versions_line(&self) -> String {
        let v = |k: &str| self.versions[k].as_str().unwrap_or("?").to_string();
        format!(
            "kiss-icp {}, numpy {}, Python {} ({})",
            v("kiss_icp"),
            v("numpy"),
            v("python"),
            self.python.display()
        )
    }

    /// A fresh file name in the session folder.
    pub fn file(&mut self, stem: &str) -> PathBuf {
        self.files += 1;
        self.dir.path().join(format!("{:04}_{stem}", self.files))
    }

    /// Writes points as raw `f64` and returns the file.
    pub fn write_points(&mut self, stem: &str, points: &[[f64; 3]]) -> Result<PathBuf> {
        let path = self.file(stem);
        let bytes: Vec<u8> = points
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        std::fs::write(&path, bytes).with_context(|| format!("{}", path.display()))?;
        Ok(path)
    }

    /// Writes scalars as raw `f64` and returns the file.
    pub fn write_f64s(&mut self, stem: &str, values: &[f64]) -> Result<PathBuf> {
        let path = self.file(stem);
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        std::fs::write(&path, bytes).with_context(|| format!("{}", path.display()))?;
        Ok(path)
    }

    /// Runs one driver command; fails with the end of its stderr.
    pub fn run<I, S>(&self, args: I) -> Result<()>
    where
        I: IntoIterator<Item = S>,
        S: AsRef<OsStr>,
    {
        self.output(args).map(|_| ())
    }

    /// Runs several commands in one interpreter (`driver.py batch`).
    pub fn batch(&mut self, commands: &[Vec<String>]) -> Result<()> {
        if commands.is_empty() {
            return Ok(());
        }
        let path = self.file("batch.json");
        std::fs::write(&path, serde_json::to_vec(commands)?)
            .with_context(|| format!("{}", path.display()))?;
        let mut args: Vec<OsString> = vec!["batch".into(), "--commands".into()];
        args.push(path.into_os_string());
        self.run(args)
    }

    fn output<I, S>(&self, args: I) -> Result<Vec<u8>>
    where
        I: IntoIterator<Item = S>,
        S: AsRef<OsStr>,
    {
        let args: Vec<OsString> = args.into_iter().map(|a| a.as_ref().to_owned()).collect();
        let what = args
            .first()
            .map(|a| a.to_string_lossy().into_owned())
            .unwrap_or_default();
        let out = Command::new(&self.python)
            .arg(&self.script)
            .args(&args)
            .output()
            .with_context(|| {
                format!(
                    "cannot start {} (set --python or KISS_ODOM_PYTHON to a Python with \
                     kiss-icp 1.3.0: tests/reference/requirements.txt)",
                    self.python.display()
                )
            })?;
        if !out.status.success() {
            let stderr = String::from_utf8_lossy(&out.stderr);
            if stderr.contains("No module named 'kiss_icp'")
                || stderr.contains("No module named 'numpy'")
            {
                bail!(
                    "{} cannot import the reference (kiss_icp/numpy); set --python or \
                     KISS_ODOM_PYTHON to a venv made from tests/reference/requirements.txt",
                    self.python.display()
                );
            }
            let tail: Vec<&str> = stderr.lines().rev().take(6).collect();
            let tail: Vec<&str> = tail.into_iter().rev().collect();
            bail!(
                "reference driver `{what}` failed ({}): {}",
                out.status,
                tail.join(" | ")
            );
        }
        Ok(out.stdout)
    }
}

/// A path as a driver argument (the batch file is JSON, so paths must be UTF-8).
pub fn arg(path: &Path) -> Result<String> {
    path.to_str()
        .map(str::to_string)
        .ok_or_else(|| anyhow::anyhow!("{}: path is not UTF-8", path.display()))
}

/// Reads raw `f64` points.
pub fn read_points(path: &Path) -> Result<Vec<[f64; 3]>> {
    let v = read_f64s(path)?;
    if v.len() % 3 != 0 {
        bail!("{}: not a whole number of points", path.display());
    }
    Ok(v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
}

/// Reads raw `f64` scalars.
pub fn read_f64s(path: &Path) -> Result<Vec<f64>> {
    let bytes = std::fs::read(path).with_context(|| format!("{}", path.display()))?;
    if bytes.len() % 8 != 0 {
        bail!("{}: not a whole number of f64", path.display());
    }
    Ok(bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
        .collect())
}

/// Reads a JSON output.
pub fn read_json(path: &Path) -> Result<serde_json::Value> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{}: invalid JSON", path.display()))
}

/// A 4x4 matrix as the driver's POSE argument (16 numbers, row-major, exact).
pub fn matrix_arg(m: &Matrix4<f64>) -> String {
    let mut s = Vec::with_capacity(16);
    for r in 0..4 {
        for c in 0..4 {
            s.push(format!("{:?}", m[(r, c)]));
        }
    }
    s.join(" ")
}

/// A pose as the driver's POSE argument.
pub fn pose_arg(p: &Isometry3<f64>) -> String {
    matrix_arg(&p.to_homogeneous())
}

/// A 4x4 row-major JSON nested list (the driver's `register` output) as a matrix.
pub fn matrix_from_json(v: &serde_json::Value) -> Result<Matrix4<f64>> {
    let rows = v.as_array().filter(|r| r.len() == 4);
    let mut m = Matrix4::zeros();
    let Some(rows) = rows else {
        bail!("expected a 4x4 nested list");
    };
    for (r, row) in rows.iter().enumerate() {
        let Some(row) = row.as_array().filter(|c| c.len() == 4) else {
            bail!("expected a 4x4 nested list");
        };
        for (c, x) in row.iter().enumerate() {
            m[(r, c)] = x.as_f64().ok_or_else(|| anyhow::anyhow!("not a number"))?;
        }
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pose_arguments_round_trip_exactly() {
        let p = Isometry3::new(
            nalgebra::Vector3::new(0.1, -1.0 / 3.0, 2e-17),
            nalgebra::Vector3::new(0.3, 0.2, -0.1),
        );
        let m = p.to_homogeneous();
        let back: Vec<f64> = pose_arg(&p)
            .split(' ')
            .map(|t| t.parse().unwrap())
            .collect();
        for r in 0..4 {
            for c in 0..4 {
                assert_eq!(back[4 * r + c].to_bits(), m[(r, c)].to_bits());
            }
        }
    }
}
