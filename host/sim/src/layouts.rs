//! A simulated sequence written in a public dataset's own layout (`simulate --layout`), with
//! its ground truth in that dataset's convention (its frame, calibration, time base and pose
//! encoding), so that every dataset reader has a sequence whose truth is known.
//!
//! Each dataset's module writes its files from the same simulation: the scans as the dataset
//! stores them (binary records, PCD, int16), the poses as its ground-truth file states them.
//! Read back as kiss-icp's loader reads them, the poses are the simulator's ground truth (the
//! LiDAR at each sweep's end) up to the loader's first-pose convention and a fixed world
//! offset ([`world`]) that makes global poses look global. Like [`crate::writer`], the files are
//! written into a hidden staging folder and moved into place only when complete.

pub mod apollo;
pub mod boreas;
pub mod helipr;
pub mod kitti_raw;
pub mod mulran;
pub mod ncd;
pub mod nclt;
pub mod nuscenes;
#[cfg(test)]
mod tests;

use crate::sensor::Frame;
use crate::simulation::Simulation;
use crate::trajectory::PoseM;
use anyhow::{bail, Context, Result};
use nalgebra::{Matrix3, Matrix4, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::Serialize;
use std::path::Path;

/// Which layout a sequence is written in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Layout {
    /// kiss-odom's generic layout (velodyne/, timestamps/, poses.txt, times.txt).
    #[default]
    Generic,
    /// MulRan: `Ouster/<ns>.bin` (a 64 x 1024 grid), `global_pose.csv`.
    Mulran,
    /// NCLT: `2012-01-08/velodyne_sync/<us>.bin`, `ground_truth/groundtruth_2012-01-08.csv`.
    Nclt,
    /// Newer College: `raw_format/ouster_scan/cloud_<s>_<ns>.pcd` (64 x 1024),
    /// `ground_truth/registered_poses.csv`.
    Ncd,
    /// HeLiPR: `LiDAR/{Ouster,Velodyne,Avia,Aeva}/<ns>.bin`, `LiDAR_GT/global_<sensor>_gt.txt`.
    Helipr,
    /// Boreas: `lidar/<us>.bin`, `applanix/lidar_poses.csv`.
    Boreas,
    /// nuScenes: v1.0-mini/*.json, samples/ and sweeps/LIDAR_TOP/*.pcd.bin (scene-0061).
    Nuscenes,
    /// Apollo-SouthBay: `pcds/<n>.pcd`, `poses/gt_poses.txt`.
    Apollo,
    /// KITTI raw: 2011_10_03/2011_10_03_drive_0027_sync/ (odometry sequence 00), OXTS poses.
    KittiRaw,
}

impl Layout {
    /// Whether the layout stores whole 64 x 1024 Ouster scans ([`OUSTER_GRID`]; the sensor
    /// may have fewer beams and columns, not more).
    pub fn ouster_grid(self) -> bool {
        matches!(self, Layout::Mulran | Layout::Ncd)
    }

    /// The top-level files and folders the layout writes into the output folder.
    pub fn owned(self) -> &'static [&'static str] {
        match self {
            Layout::Generic => &[],
            Layout::Mulran => &["Ouster", "global_pose.csv"],
            Layout::Nclt => &[nclt::DATE, "ground_truth"],
            Layout::Ncd => &["raw_format", "ground_truth"],
            Layout::Helipr => &["LiDAR", "LiDAR_GT"],
            Layout::Boreas => &["lidar", "applanix"],
            Layout::Nuscenes => &["v1.0-mini", "samples", "sweeps", "maps"],
            Layout::Apollo => &["pcds", "poses"],
            Layout::KittiRaw => &[kitti_raw::DATE],
        }
    }
}

/// What a layout writer draws from: the simulation and its frames.
pub struct Source<'a> {
    /// The simulation.
    pub sim: &'a Simulation,
    /// Frames to write.
    pub frames: u64,
    stop: &'a dyn Fn() -> bool,
    progress: &'a mut dyn FnMut(u64),
    /// Frames written so far and their points.
    done: (u64, usize),
}

impl Source<'_> {
    /// The LiDAR pose at sequence time `t` in the ground-truth frame (the sensor at the first
    /// sweep's end), what [`Simulation::ground_truth`] gives at sweep ends.
    pub fn pose_at(&self, t: f64) -> PoseM {
        self.sim.ground_truth_origin().inverse() * self.sim.world_pose(t)
    }

    /// Frame `k`'s ground truth.
    pub fn truth(&self, k: u64) -> PoseM {
        self.sim.ground_truth(k)
    }

    /// Frame `k`'s end time (s, sequence time).
    pub fn end_time(&self, k: u64) -> f64 {
        self.sim.end_time(k)
    }

    /// Seconds a sweep lasts.
    pub fn period(&self) -> f64 {
        1.0 / self.sim.params().sensor.rate_hz
    }

    /// Ray casts every frame in order and hands each to `write`; `false` when a stop was
    /// asked for before the last.
    pub fn each_frame(&mut self, mut write: impl FnMut(&Frame) -> Result<()>) -> Result<bool> {
        for k in 0..self.frames {
            if (self.stop)() {
                return Ok(false);
            }
            let frame = self.sim.frame(k);
            write(&frame)?;
            self.done = (k + 1, self.done.1 + frame.points.len());
            (self.progress)(k + 1);
        }
        Ok(true)
    }
}

/// The fixed offset between a dataset's global frame and the ground-truth frame: 1.2 km,
/// 0.7 km and 35 m away, turned 0.6 rad about the vertical.
pub fn world() -> Matrix4<f64> {
    let r = Rotation3::from_axis_angle(&Vector3::z_axis(), 0.6);
    rigid(r.matrix(), [1234.5, 678.25, 35.0])
}

/// A pose as a 4x4 matrix.
pub fn matrix(p: &PoseM) -> Matrix4<f64> {
    p.to_homogeneous()
}

/// The 4x4 matrix of rotation `r` and translation `t`.
pub fn rigid(r: &Matrix3<f64>, t: [f64; 3]) -> Matrix4<f64> {
    let mut m = Matrix4::identity();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(r);
    for (i, v) in t.into_iter().enumerate() {
        m[(i, 3)] = v;
    }
    m
}

/// The translation of `m`.
pub fn translation(m: &Matrix4<f64>) -> [f64; 3] {
    [m[(0, 3)], m[(1, 3)], m[(2, 3)]]
}

/// The nearest rotation to `m`'s rotation block.
pub fn rotation(m: &Matrix4<f64>) -> Rotation3<f64> {
    let block: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    Rotation3::from_matrix_eps(&block, 1e-15, 100, Rotation3::identity())
}

/// `[w, x, y, z]` of `m`'s rotation.
pub fn quaternion(m: &Matrix4<f64>) -> [f64; 4] {
    let q = UnitQuaternion::from_rotation_matrix(&rotation(m));
    [q.w, q.i, q.j, q.k]
}

/// `(roll, pitch, yaw)` with `Rz(yaw) Ry(pitch) Rx(roll)` = `m`'s rotation.
pub fn euler(m: &Matrix4<f64>) -> (f64, f64, f64) {
    rotation(m).euler_angles()
}

/// The rigid transform of a unit quaternion `[w, x, y, z]` and a translation.
pub fn from_quaternion(q: [f64; 4], t: [f64; 3]) -> Matrix4<f64> {
    let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]));
    rigid(q.to_rotation_matrix().matrix(), t)
}

/// A general 4x4 inverse.
pub fn inverse(m: &Matrix4<f64>) -> Result<Matrix4<f64>> {
    m.try_inverse().context("a calibration is not invertible")
}

/// Little-endian bytes of `f32`s.
pub fn f32_bytes(values: impl IntoIterator<Item = f32>) -> Vec<u8> {
    values.into_iter().flat_map(f32::to_le_bytes).collect()
}

/// Shortest round-trip text of `x`.
pub fn num(x: f64) -> String {
    crate::writer::fmt_f64(x)
}

/// Writes `bytes` to `path`, creating its folder.
pub fn put(path: &Path, bytes: &[u8]) -> Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    std::fs::write(path, bytes).with_context(|| format!("writing {}", path.display()))
}

/// `start + seconds` in whole units of `1 / per_second` (ns: 1e9, us: 1e6).
pub fn stamp(start: u64, seconds: f64, per_second: f64) -> u64 {
    start.saturating_add((seconds * per_second).round().max(0.0) as u64)
}

/// Rows and columns of the Ouster OS1-64 scans MulRan and Newer College store.
pub const OUSTER_GRID: (u32, u32) = (64, 1024);

/// A frame's points as a column-major 64 x 1024 grid, as an Ouster OS1-64 writes them: each
/// column's returns in its first rows, zeros (no return) after; a point's column from its
/// capture time (a sensor with fewer columns leaves the columns between its firings empty).
pub fn ouster_grid(sim: &Simulation, frame: &Frame) -> Vec<[f32; 4]> {
    const H: usize = OUSTER_GRID.0 as usize;
    const W: usize = OUSTER_GRID.1 as usize;
    let mut grid = vec![[0.0f32; 4]; H * W];
    let mut rows = vec![0usize; W];
    let start = sim.params().start_time;
    let rate = sim.params().sensor.rate_hz;
    let k = frame.index;
    for (p, &t) in frame.points.iter().zip(&frame.stamps) {
        let c = ((t - start) * rate * W as f64).round() - (k as f64) * W as f64;
        let c = c.clamp(0.0, (W - 1) as f64) as usize;
        if rows[c] < H {
            grid[c * H + rows[c]] = *p;
            rows[c] += 1;
        }
    }
    grid
}

/// A binary PCD file of x y z intensity float32.
pub fn pcd(points: &[[f32; 4]]) -> Vec<u8> {
    let n = points.len();
    let header = format!(
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z intensity\n\
         SIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\nWIDTH {n}\nHEIGHT 1\n\
         VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA binary\n"
    );
    let mut bytes = header.into_bytes();
    bytes.extend(f32_bytes(points.iter().flatten().copied()));
    bytes
}

/// How writing a layout ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Outcome {
    /// Whether every frame was written (else a stop was asked for and nothing was left).
    pub complete: bool,
    /// Frames ray cast.
    pub frames: u64,
    /// Their points.
    pub points: usize,
}

/// Writes the sequence of `sim` in `layout` into `out`; when `stop` asks to end before the
/// last frame nothing is left in `out`. `sim_toml` is the provenance text.
pub fn write(
    sim: &Simulation,
    layout: Layout,
    out: &Path,
    overwrite: bool,
    sim_toml: &str,
    stop: &dyn Fn() -> bool,
    progress: &mut dyn FnMut(u64),
) -> Result<Outcome> {
    let owned = layout.owned();
    let existing: Vec<&str> = owned
        .iter()
        .chain(["sim.toml"].iter())
        .copied()
        .filter(|n| out.join(n).exists())
        .collect();
    if !existing.is_empty() && !overwrite {
        bail!(
            "{} already holds {}; pass --overwrite to replace it",
            out.display(),
            existing.join(", ")
        );
    }
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let staging = tempfile::Builder::new()
        .prefix(".kiss-odom-simulate-")
        .tempdir_in(out)
        .with_context(|| format!("creating a staging folder in {}", out.display()))?;
    let dir = staging.path();
    let mut source = Source {
        sim,
        frames: sim.params().frames,
        stop,
        progress,
        done: (0, 0),
    };
    let complete = match layout {
        Layout::Generic => bail!("the generic layout is written by `writer`"),
        Layout::Mulran => mulran::write(dir, &mut source)?,
        Layout::Nclt => nclt::write(dir, &mut source)?,
        Layout::Ncd => ncd::write(dir, &mut source)?,
        Layout::Helipr => helipr::write(dir, &mut source)?,
        Layout::Boreas => boreas::write(dir, &mut source)?,
        Layout::Nuscenes => nuscenes::write(dir, &mut source)?,
        Layout::Apollo => apollo::write(dir, &mut source)?,
        Layout::KittiRaw => kitti_raw::write(dir, &mut source)?,
    };
    let (frames, points) = source.done;
    let outcome = Outcome {
        complete,
        frames,
        points,
    };
    if !complete {
        return Ok(outcome);
    }
    put(&dir.join("sim.toml"), sim_toml.as_bytes())?;
    for name in owned.iter().chain(["sim.toml"].iter()) {
        let (from, to) = (dir.join(name), out.join(name));
        if !from.exists() {
            continue;
        }
        if to.is_dir() {
            std::fs::remove_dir_all(&to)
                .with_context(|| format!("{}: cannot remove the earlier output", to.display()))?;
        } else if to.exists() {
            std::fs::remove_file(&to)
                .with_context(|| format!("{}: cannot remove the earlier output", to.display()))?;
        }
        std::fs::rename(&from, &to)
            .with_context(|| format!("moving {} into place", to.display()))?;
    }
    Ok(outcome)
}

/// A translation as a vector.
pub fn vec3(t: [f64; 3]) -> Vector3<f64> {
    Vector3::new(t[0], t[1], t[2])
}

/// A pose from a rotation and a translation.
pub fn pose(r: Rotation3<f64>, t: [f64; 3]) -> PoseM {
    PoseM::from_parts(Translation3::from(vec3(t)), r)
}
