//! Localization in a prior map for `kiss_odom.KissICP(map=..., initial_pose=...)`.
//!
//! The drive crate's `MapLocalizer`, opened as `kiss-odom run --map` opens it (the run's `f64`
//! configuration, `output.map_frame`, the build's registration cloud capacity) and run after
//! each frame the driver answers, so the map-frame poses are `run`'s, bit for bit. The frame's
//! report gains `run`'s three `frames.csv` columns; the odometry's own poses stay kiss-icp's.

use kiss_odom_core::localize::Located;
use kiss_odom_drive::localize::MapLocalizer;
use kiss_odom_drive::settings::Settings;
use kiss_odom_drive::{Driver, Outcome};
use nalgebra::Isometry3;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// A prior map and the localizer in it, with what `reset` needs to start again.
pub struct Prior {
    localizer: MapLocalizer,
    initial: Isometry3<f64>,
    /// Whether a frame was localized since the map was opened or reset (before, the
    /// localizer's pose is the initial one, which no frame has answered).
    located: bool,
}

/// The start in the map frame: a 4x4 rigid transform, or `run --initial-pose`'s text
/// `X,Y,Z,ROLL,PITCH,YAW` (m, degrees) read by `run`'s parser, so a run started from the same
/// text starts from the same pose, bit for bit.
pub fn initial_pose(obj: &Bound<'_, PyAny>) -> PyResult<Isometry3<f64>> {
    match obj.extract::<String>() {
        Ok(text) => kiss_odom_io::poses::parse_xyz_rpy(&text)
            .map_err(|e| PyValueError::new_err(format!("initial_pose: {e}"))),
        Err(_) => crate::convert::pose(obj, "initial_pose"),
    }
}

impl Prior {
    /// Opens the map at `path`; a map the run cannot use (unreadable, damaged header or
    /// index, another voxel size or frame) is an error naming the reason.
    pub fn open(
        path: PathBuf,
        settings: &Settings,
        driver: &Driver,
        initial: Isometry3<f64>,
    ) -> anyhow::Result<Self> {
        Ok(Self {
            localizer: MapLocalizer::for_driver(&path, settings, driver, initial)?,
            initial,
            located: false,
        })
    }

    /// Starts again at the initial pose, as a new localizer does.
    pub fn reset(&mut self) {
        self.localizer.reseed(self.initial);
        self.located = false;
    }

    /// Localizes the frame `outcome` answered (no Python object is touched: it runs with the
    /// GIL released).
    pub fn locate(&mut self, driver: &Driver, outcome: &Outcome) -> Located<f64> {
        let located = self.localizer.locate(driver, outcome);
        self.located = true;
        located
    }

    /// `located`'s entries into the frame's `report`, a damaged tile's warning (once) into
    /// `warnings`.
    pub fn report(
        &mut self,
        located: &Located<f64>,
        report: &Bound<'_, PyDict>,
        warnings: &mut Vec<String>,
    ) -> PyResult<()> {
        report.set_item("localization", located.state.name())?;
        report.set_item("map_inlier_share", located.inlier_share)?;
        report.set_item("map_observability", located.observability)?;
        report.set_item("map_correction_m", located.correction)?;
        warnings.extend(self.localizer.damaged_warning());
        Ok(())
    }

    /// The last frame's pose in the map frame (`None` before the first frame since the map
    /// was opened or reset).
    pub fn pose(&self) -> Option<&Isometry3<f64>> {
        self.located.then(|| self.localizer.pose())
    }
}
