//! Writes a simulated sequence in the generic layout:
//!
//! ```text
//! DIR/velodyne/NNNNNN.bin    f32 LE x, y, z, intensity per point (sensor frame at capture time)
//! DIR/timestamps/NNNNNN.bin  f64 LE capture time per point (s, sequence time)
//! DIR/poses.txt              3x4 row-major end-of-sweep pose per frame, first one identity
//!                            (with --revisit: in the first run's frame)
//! DIR/times.txt              end-of-sweep time per frame (s)
//! DIR/sim.toml               the parameters used, for provenance
//! DIR/initial_pose.txt       with --revisit: frame 0's pose, X,Y,Z,ROLL,PITCH,YAW (m, degrees)
//! DIR/packets.pcap           with --format pcap: the same sweeps as sensor packets
//! DIR/packets.json           with --format pcap and an Ouster: its metadata
//! DIR/packets.csv            with --format pcap and a QT128 or OT128: its angle correction file
//! DIR/packets.yaml           with --format pcap and a HDL-64E or VLS-128: its calibration
//! DIR/points.bag             with --format bag: the frames (and IMU samples) as a ROS 1 bag
//! DIR/points.mcap            with --format mcap: the same as a ROS 2 MCAP file
//! DIR/points/                with --format db3: the same as a ROS 2 sqlite3 bag
//! ```
//!
//! Numbers in text files are written with Rust's shortest round-trip formatting, so parsing
//! them gives back the exact `f64`. These writers are private to the simulator on purpose: the
//! readers in `io/` are checked against them, not built from them.

use crate::replace::{Replacement, SIM_TOML, STAGING_PREFIX};
use crate::sensor::Frame;
use crate::trajectory::PoseM;
use anyhow::{bail, Context, Result};
use serde::Serialize;
use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The file beside `poses.txt` with a revisit's first pose: `X,Y,Z,ROLL,PITCH,YAW`.
pub const INITIAL_POSE: &str = "initial_pose.txt";

/// Files the layout owns, `sim.toml` last.
const OWNED_FILES: [&str; 12] = [
    "poses.txt",
    "times.txt",
    INITIAL_POSE,
    crate::capture::PCAP_NAME,
    crate::capture::META_NAME,
    crate::capture::ANGLES_NAME,
    crate::capture::CALIBRATION_NAME,
    crate::capture::CORRECTION_NAME,
    crate::imu::CSV_NAME,
    crate::ros::BAG_NAME,
    crate::ros::MCAP_NAME,
    SIM_TOML,
];
const OWNED_DIRS: [&str; 2] = ["velodyne", "timestamps"];
/// The sqlite3 bag's folder and the files in it.
const OWNED_BAG: (&str, [&str; 2]) = (crate::ros::DB3_NAME, ["metadata.yaml", "points_0.db3"]);

/// Shortest text that parses back to exactly `x` (exponent form for very small or large).
pub fn fmt_f64(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || (1e-4..1e16).contains(&a) || !x.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The [`INITIAL_POSE`] line of `pose`: `X,Y,Z,ROLL,PITCH,YAW` in metres and degrees,
/// `R = Rz(yaw) Ry(pitch) Rx(roll)`, each number the shortest text that parses back exactly.
pub fn initial_pose_line(pose: &PoseM) -> String {
    let t = pose.translation.vector;
    let [roll, pitch, yaw] = crate::revisit::roll_pitch_yaw(pose).map(f64::to_degrees);
    [t.x, t.y, t.z, roll, pitch, yaw].map(fmt_f64).join(",")
}

/// One `poses.txt` line: the top 3x4 of the pose matrix, row-major.
pub fn pose_line(pose: &PoseM) -> String {
    let m = pose.to_homogeneous();
    let mut s = String::with_capacity(12 * 24);
    for r in 0..3 {
        for c in 0..4 {
            if r + c > 0 {
                s.push(' ');
            }
            s.push_str(&fmt_f64(m[(r, c)]));
        }
    }
    s
}

/// The name of frame `k`'s files: six digits, zero-padded (more digits past 999999).
pub fn frame_name(k: u64) -> String {
    format!("{k:06}.bin")
}

/// Streams a dataset to a folder, frame by frame, through a hidden staging folder inside it:
/// the dataset appears in the folder only when [`Self::finish`] moves it there, frame folder
/// last, so a later `run` never reads half a data set; dropped unfinished (an error, an
/// interrupt), the staging folder goes and nothing appears, and an earlier data set stays.
pub struct DatasetWriter {
    dir: PathBuf,
    staging: tempfile::TempDir,
    poses: BufWriter<File>,
    times: BufWriter<File>,
    /// `sim.toml` but for the list of what was written, which [`Self::finish`] adds.
    provenance: String,
    /// The earlier data set, removed by [`Self::finish`].
    earlier: Replacement,
}

impl DatasetWriter {
    /// Prepares `dir` for a data set whose `sim.toml` records `provenance`. A folder that
    /// already holds a data set is refused unless `overwrite`, and then unless it is one
    /// `simulate` wrote, checked whole ([`Replacement::check`]); it is replaced when the new
    /// one is complete, so no stale frame survives a shorter run. Staging folders a killed
    /// run left are removed.
    pub fn create(dir: &Path, overwrite: bool, provenance: &impl Serialize) -> Result<Self> {
        let names: Vec<&str> = (OWNED_FILES.iter().chain([&OWNED_BAG.0]))
            .chain(&OWNED_DIRS)
            .copied()
            .collect();
        only_the_bag(&dir.join(OWNED_BAG.0))?;
        let earlier = Replacement::check(dir, &names, overwrite)?;
        fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let staging = tempfile::Builder::new()
            .prefix(STAGING_PREFIX)
            .tempdir_in(dir)
            .with_context(|| format!("creating a staging folder in {}", dir.display()))?;
        let root = staging.path();
        for sub in OWNED_DIRS {
            let d = root.join(sub);
            fs::create_dir_all(&d).with_context(|| format!("creating {}", d.display()))?;
        }
        let toml = toml::to_string(provenance).context("serialising sim.toml")?;
        let header = "# Written by `kiss-odom simulate`: the parameters that generated this \
                      dataset.\n# The same parameters (and kiss-odom version) give the same \
                      bytes.\n\n";
        let open = |name: &str| -> Result<BufWriter<File>> {
            let p = root.join(name);
            Ok(BufWriter::new(
                File::create(&p).with_context(|| format!("creating {}", p.display()))?,
            ))
        };
        Ok(Self {
            dir: dir.to_path_buf(),
            poses: open("poses.txt")?,
            times: open("times.txt")?,
            staging,
            provenance: format!("{header}{toml}"),
            earlier,
        })
    }

    /// The staging folder, for files beside the frames (moved into place by [`Self::finish`]).
    pub fn staging(&self) -> &Path {
        self.staging.path()
    }

    /// Writes one frame's scan and stamps and appends its ground truth.
    pub fn write_frame(&mut self, frame: &Frame, ground_truth: &PoseM) -> Result<()> {
        let name = frame_name(frame.index);
        let mut bytes = Vec::with_capacity(frame.points.len() * 16);
        for p in &frame.points {
            for v in p {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        let root = self.staging.path();
        let p = root.join("velodyne").join(&name);
        fs::write(&p, &bytes).with_context(|| format!("writing {}", p.display()))?;
        bytes.clear();
        for t in &frame.stamps {
            bytes.extend_from_slice(&t.to_le_bytes());
        }
        let p = root.join("timestamps").join(&name);
        fs::write(&p, &bytes).with_context(|| format!("writing {}", p.display()))?;
        writeln!(self.poses, "{}", pose_line(ground_truth)).context("writing poses.txt")?;
        writeln!(self.times, "{}", fmt_f64(frame.end_time)).context("writing times.txt")?;
        Ok(())
    }

    /// Flushes the text files, writes `sim.toml` with the list of what was written, removes
    /// the earlier data set and moves this one into place, the frame folder last.
    pub fn finish(mut self) -> Result<()> {
        self.poses.flush().context("writing poses.txt")?;
        self.times.flush().context("writing times.txt")?;
        let root = self.staging.path();
        let names: Vec<&str> = OWNED_FILES
            .iter()
            .chain([&OWNED_BAG.0])
            .chain(OWNED_DIRS.iter().rev())
            .copied()
            .collect();
        // The optional files (the capture, the metadata) only when written.
        let written: Vec<&str> = names
            .iter()
            .copied()
            .filter(|n| *n != SIM_TOML && root.join(n).exists())
            .collect();
        let toml = self.provenance.clone() + &crate::replace::written_table(&written)?;
        let p = root.join(SIM_TOML);
        fs::write(&p, toml).with_context(|| format!("writing {}", p.display()))?;
        self.earlier.remove_old()?;
        for name in names {
            let (from, to) = (root.join(name), self.dir.join(name));
            if !from.exists() {
                continue;
            }
            if fs::symlink_metadata(&to).is_ok() {
                bail!("{}: appeared while simulating; not replaced", to.display());
            }
            fs::rename(&from, &to)
                .with_context(|| format!("moving {} into place", to.display()))?;
        }
        Ok(())
    }
}

/// Refuses a sqlite3 bag folder that holds more than the bag `simulate` writes: replacing the
/// data set removes the folder whole.
fn only_the_bag(bag: &Path) -> Result<()> {
    let Ok(entries) = fs::read_dir(bag) else {
        return Ok(()); // none yet
    };
    for entry in entries {
        let entry = entry.with_context(|| format!("listing {}", bag.display()))?;
        let name = entry.file_name();
        if !OWNED_BAG.1.iter().any(|n| name.to_str() == Some(n)) {
            bail!(
                "{}: not the bag simulate writes; move it away or choose another --out",
                entry.path().display()
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Translation3, Vector3};

    #[test]
    fn numbers_round_trip_exactly_through_text() {
        let mut rng = crate::rng::Stream::from_key(3);
        for _ in 0..10_000 {
            let exp = rng.range(-30.0, 30.0);
            let x = rng.normal() * libm::pow(10.0, exp);
            let s = fmt_f64(x);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{s}");
        }
        assert_eq!(fmt_f64(1.0), "1");
        assert_eq!(fmt_f64(0.0), "0");
        assert_eq!(fmt_f64(1e-20), "1e-20");
    }

    #[test]
    fn identity_pose_line_is_short_and_exact() {
        assert_eq!(pose_line(&PoseM::identity()), "1 0 0 0 0 1 0 0 0 0 1 0");
        let p = PoseM::from_parts(
            Translation3::new(1.5, -2.0, 0.25),
            Rotation3::from_axis_angle(&Vector3::z_axis(), 0.3),
        );
        let v: Vec<f64> = pose_line(&p)
            .split(' ')
            .map(|s| s.parse().unwrap())
            .collect();
        let m = p.to_homogeneous();
        for r in 0..3 {
            for c in 0..4 {
                assert_eq!(v[4 * r + c].to_bits(), m[(r, c)].to_bits());
            }
        }
    }

    #[test]
    fn frame_names_are_six_digits() {
        assert_eq!(frame_name(0), "000000.bin");
        assert_eq!(frame_name(42), "000042.bin");
    }
}
