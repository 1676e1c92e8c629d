//! Point clouds a run leaves for other tools: the local map after the last frame
//! (`--save-map`) and the whole run's registered points (`--save-cloud`), as PLY or PCD with
//! `f64` coordinates through the readers' own writers ([`kiss_odom_io::folders::ply`], [`kiss_odom_io::folders::pcd`]).
//!
//! The whole-run cloud is each registered frame's merge cloud moved to the world frame by the
//! frame's pose, thinned to the first point per voxel and bounded in count, so a long run costs
//! at most `max_points` points of memory; what the bound drops is counted and warned about.

use crate::run::observe::{Observer, Seen};
use crate::run::record::FrameRow;
use anyhow::{bail, Result};
use kiss_odom_drive::Driver;
use nalgebra::Point3;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// A point-cloud file type, chosen by the file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ply,
    Pcd,
}

impl Format {
    fn of(path: &Path) -> Result<Self> {
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        match ext.to_ascii_lowercase().as_str() {
            "ply" => Ok(Self::Ply),
            "pcd" => Ok(Self::Pcd),
            _ => bail!("{}: give a .ply or .pcd file name", path.display()),
        }
    }
}

/// Writes `points` to `path` atomically in the format its extension names.
pub fn write_cloud(path: &Path, points: &[[f64; 3]]) -> Result<()> {
    let format = Format::of(path)?;
    kiss_odom_io::write::write_via_path(path, |tmp| match format {
        Format::Ply => kiss_odom_io::folders::ply::write(tmp, points, None),
        Format::Pcd => kiss_odom_io::folders::pcd::write(tmp, points, None),
    })
}

/// `--save-map`: the local map (world frame) once the last frame is processed.
pub struct MapExport {
    path: PathBuf,
}

impl MapExport {
    /// An export to `path` (.ply or .pcd).
    pub fn new(path: &Path) -> Result<Self> {
        Format::of(path)?;
        Ok(Self { path: path.into() })
    }
}

impl Observer for MapExport {
    fn frame(&mut self, _: &Seen<'_>, _: &mut FrameRow) -> Result<()> {
        Ok(())
    }

    fn finish(&mut self, driver: &Driver) -> Result<Vec<String>> {
        write_cloud(&self.path, &driver.map_points())?;
        Ok(Vec::new())
    }
}

/// Points kept one per voxel, at most `max` of them.
#[derive(Debug)]
pub struct VoxelCloud {
    voxel: f64,
    max: usize,
    cells: HashMap<[i64; 3], usize>,
    points: Vec<[f64; 3]>,
    dropped: u64,
}

impl VoxelCloud {
    /// An empty cloud of voxel edge `voxel` (m, positive and finite) holding at most `max`
    /// points.
    pub fn new(voxel: f64, max: usize) -> Result<Self> {
        if !(voxel.is_finite() && voxel > 0.0) {
            bail!("output.cloud_voxel must be a positive number of metres, not {voxel}");
        }
        Ok(Self {
            voxel,
            max,
            cells: HashMap::new(),
            points: Vec::new(),
            dropped: 0,
        })
    }

    /// Adds `p` if its voxel is empty and there is room; a point in a new voxel past the bound
    /// is counted as dropped; non-finite points are ignored.
    pub fn add(&mut self, p: [f64; 3]) {
        let cell = p.map(|c| (c / self.voxel).floor());
        if cell.iter().any(|c| !c.is_finite()) {
            return;
        }
        // Saturating casts: a point 1e18 voxels away shares a cell with its neighbours.
        let key = cell.map(|c| c as i64);
        if self.cells.contains_key(&key) {
            return;
        }
        if self.points.len() >= self.max {
            self.dropped += 1;
            return;
        }
        self.cells.insert(key, self.points.len());
        self.points.push(p);
    }

    /// The points kept, in the order they came.
    pub fn points(&self) -> &[[f64; 3]] {
        &self.points
    }

    /// Points in new voxels refused because the cloud was full.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }
}

/// `--save-cloud`: the whole run's registered points (see the module doc).
pub struct CloudExport {
    path: PathBuf,
    cloud: VoxelCloud,
}

impl CloudExport {
    /// An export to `path` (.ply or .pcd) of voxel edge `voxel` (m), at most `max_points`.
    pub fn new(path: &Path, voxel: f64, max_points: usize) -> Result<Self> {
        Format::of(path)?;
        Ok(Self {
            path: path.into(),
            cloud: VoxelCloud::new(voxel, max_points)?,
        })
    }
}

impl Observer for CloudExport {
    fn frame(&mut self, seen: &Seen<'_>, _: &mut FrameRow) -> Result<()> {
        if seen.outcome.report().is_none() {
            return Ok(());
        }
        let pose = seen.outcome.pose;
        for p in seen.driver.merge_cloud() {
            let w = pose * Point3::from(p);
            self.cloud.add([w.x, w.y, w.z]);
        }
        Ok(())
    }

    fn finish(&mut self, _: &Driver) -> Result<Vec<String>> {
        write_cloud(&self.path, self.cloud.points())?;
        let dropped = self.cloud.dropped();
        Ok((dropped > 0)
            .then(|| {
                format!(
                    "{}: {dropped} points in new voxels dropped past output.cloud_max_points = {} \
                     (raise it or output.cloud_voxel)",
                    self.path.display(),
                    self.cloud.max
                )
            })
            .into_iter()
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_point_per_voxel_and_the_bound_counts_what_it_drops() {
        let mut c = VoxelCloud::new(1.0, 3).unwrap();
        for p in [
            [0.1, 0.1, 0.1],
            [0.9, 0.5, 0.2],
            [-0.1, 0.0, 0.0],
            [1.5, 0.0, 0.0],
        ] {
            c.add(p);
        }
        // The second point shares the first's voxel; -0.1 floors to voxel -1.
        assert_eq!(
            c.points(),
            [[0.1, 0.1, 0.1], [-0.1, 0.0, 0.0], [1.5, 0.0, 0.0]]
        );
        c.add([5.0, 5.0, 5.0]);
        c.add([6.0, 5.0, 5.0]);
        c.add([0.2, 0.2, 0.2]); // an occupied voxel is not a drop
        c.add([f64::NAN, 0.0, 0.0]);
        assert_eq!((c.points().len(), c.dropped()), (3, 2));
    }

    #[test]
    fn a_bad_voxel_or_file_type_is_an_error() {
        assert!(VoxelCloud::new(0.0, 1).is_err());
        assert!(VoxelCloud::new(f64::NAN, 1).is_err());
        assert!(MapExport::new(Path::new("map.xyz")).is_err());
        assert!(CloudExport::new(Path::new("cloud"), 1.0, 1).is_err());
        assert!(MapExport::new(Path::new("MAP.PCD")).is_ok());
    }

    #[test]
    fn written_clouds_read_back_exactly_through_our_readers() {
        let dir = tempfile::tempdir().unwrap();
        let pts = vec![[1.0, -2.5, 1e-9], [std::f64::consts::PI, 0.0, -7.25]];
        let ply = dir.path().join("c.ply");
        write_cloud(&ply, &pts).unwrap();
        assert_eq!(kiss_odom_io::folders::ply::read(&ply).unwrap().points, pts);
        let pcd = dir.path().join("c.pcd");
        write_cloud(&pcd, &pts).unwrap();
        assert_eq!(kiss_odom_io::folders::pcd::read(&pcd).unwrap().points, pts);
    }
}
