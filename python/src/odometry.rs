//! `Odometry`: the engine of `kiss_odom.KissICP`, `kiss_odom_drive::Driver` behind Python.
//!
//! One object per sequence. The settings are those of `kiss-odom run` (its `Settings` as JSON;
//! `kiss_odom.config` builds them from kiss-icp's configs, dicts and `config.toml` files), and
//! the frames go through the same driver as `run`'s, so the same frames give the same poses,
//! bit for bit, and the map grows as `run`'s does. The frame call copies the points out of
//! numpy, then registers, deskews and downsamples with the GIL released. With a prior map
//! ([`crate::localize`]) each frame is then localized in it, as `run --map` does.

use crate::convert;
use crate::localize::Prior;
use kiss_odom_core::{Flag, FrameReport, ImuSample, StampProblem};
use kiss_odom_drive::growth::trim_buffer;
use kiss_odom_drive::settings::{PresetName, Settings};
use kiss_odom_drive::{Driver, FrameMeta, Outcome};
use nalgebra::Isometry3;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// kiss-odom's odometry for one sequence (see `kiss_odom.KissICP` for the documented surface).
#[pyclass(module = "kiss_odom._native")]
pub struct Odometry {
    driver: Driver,
    settings: Settings,
    /// The frame's points and its deskewed copy: kept from frame to frame so their memory is
    /// already mapped (fresh 3 MB buffers cost page faults on every frame), up to the scan
    /// capacity the run started with (`trim_buffer`).
    input: Vec<[f64; 3]>,
    deskewed: Vec<[f64; 3]>,
    /// The IMU samples `add_imu` gave since the last frame with timestamps.
    imu: Vec<ImuSample<f64>>,
    /// The prior map the frames are localized in, if one was given.
    prior: Option<Prior>,
}

fn value_error(e: anyhow::Error) -> PyErr {
    PyValueError::new_err(kiss_odom_drive::one_line(&e))
}

fn stamp_problem_name(p: StampProblem) -> &'static str {
    match p {
        StampProblem::Length => "length",
        StampProblem::NonFinite => "non_finite",
        StampProblem::Constant => "constant",
    }
}

fn report_dict<'py>(
    py: Python<'py>,
    rep: Option<&FrameReport<f64>>,
    index: u64,
    input: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let Some(r) = rep else {
        d.set_item("index", index)?;
        d.set_item("status", "empty")?;
        d.set_item("flags", Vec::<&str>::new())?;
        d.set_item("input_points", input)?;
        return Ok(d);
    };
    let flags: Vec<&str> = r.status.flags().map(Flag::name).collect();
    d.set_item("index", r.index)?;
    d.set_item("status", r.status.to_string())?;
    d.set_item("flags", flags)?;
    d.set_item("iterations", r.iterations)?;
    d.set_item("correspondences", r.correspondences)?;
    d.set_item("plane_correspondences", r.plane_correspondences)?;
    d.set_item("sigma", r.sigma)?;
    d.set_item("rms", r.rms)?;
    d.set_item("model_error", r.model_error)?;
    d.set_item("observability", r.observability)?;
    d.set_item("input_points", r.input_points)?;
    d.set_item("out_of_range", r.out_of_range)?;
    d.set_item("merge_points", r.merge_points)?;
    d.set_item("source_points", r.source_points)?;
    d.set_item("map_voxels", r.map_voxels)?;
    d.set_item("map_points", r.map_points)?;
    d.set_item("pruned_voxels", r.pruned_voxels)?;
    d.set_item("deskewed", r.deskewed)?;
    d.set_item("redeskewed", r.redeskewed)?;
    d.set_item("stamp_problem", r.stamp_problem.map(stamp_problem_name))?;
    let dr = PyDict::new(py);
    dr.set_item("non_finite", r.dropped.non_finite)?;
    dr.set_item("truncated", r.dropped.truncated)?;
    dr.set_item("merge_full", r.dropped.merge_full)?;
    dr.set_item("source_full", r.dropped.source_full)?;
    dr.set_item("map_voxels_full", r.dropped.map_voxels_full)?;
    dr.set_item("map_points_full", r.dropped.map_points_full)?;
    d.set_item("dropped", dr)?;
    Ok(d)
}

fn matrix_of<'py>(
    py: Python<'py>,
    p: &Isometry3<f64>,
) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
    convert::matrix_array(py, &p.to_homogeneous())
}

/// One frame through the driver, with `samples` for the gyroscope prior when the frame has
/// timestamps (its sweep then ends at the latest); then the deskewed frame into `deskewed`.
fn one_frame(
    driver: &mut Driver,
    points: &[[f64; 3]],
    stamps: Option<&[f64]>,
    samples: &[ImuSample<f64>],
    deskewed: &mut Vec<[f64; 3]>,
) -> anyhow::Result<Outcome> {
    let meta = FrameMeta {
        index: driver.frames() as usize,
        source: "frame".into(),
        time: None,
    };
    let end = stamps.and_then(|s| s.iter().copied().reduce(f64::max));
    let outcome = driver.register_with_imu(meta, points, stamps, end, samples)?;
    match outcome.report() {
        Some(_) => driver.deskewed_scan_into(points, stamps, deskewed),
        None => deskewed.clear(),
    }
    Ok(outcome)
}

#[pymethods]
impl Odometry {
    /// An odometry with `kiss-odom run`'s settings given as JSON (the layout of its
    /// `config.toml`; unknown keys are errors).
    #[staticmethod]
    fn from_json(json: &str) -> PyResult<Self> {
        // The path names the setting: "runtime.scalar: unknown variant `f16`, ...".
        let de = &mut serde_json::Deserializer::from_str(json);
        let s: Settings = serde_path_to_error::deserialize(de)
            .map_err(|e| PyValueError::new_err(format!("invalid configuration: {e}")))?;
        s.validate().map_err(value_error)?;
        Ok(Self {
            driver: Driver::new(&s).map_err(value_error)?,
            settings: s,
            input: Vec::new(),
            deskewed: Vec::new(),
            imu: Vec::new(),
            prior: None,
        })
    }

    /// Localizes the frames to come in the map at `path` (a `.komap` of `kiss-odom map
    /// build`), starting at `initial_pose` (the sensor at the end of the first sweep, map
    /// frame: 4x4 or `X,Y,Z,ROLL,PITCH,YAW` text). A map the run cannot use is a `ValueError`
    /// naming the reason.
    fn open_map(
        &mut self,
        path: std::path::PathBuf,
        initial_pose: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        if self.driver.frames() > 0 {
            return Err(PyValueError::new_err(
                "the prior map is given before the first frame",
            ));
        }
        let initial = crate::localize::initial_pose(initial_pose)?;
        let prior =
            Prior::open(path, &self.settings, &self.driver, initial).map_err(value_error)?;
        self.prior = Some(prior);
        Ok(())
    }

    /// The last frame's pose in the prior map's frame, 4x4 (`None` without a map or before
    /// the first frame).
    fn map_pose<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, numpy::PyArray2<f64>>>> {
        let pose = self.prior.as_ref().and_then(Prior::pose);
        pose.map(|p| matrix_of(py, p)).transpose()
    }

    /// Registers one scan: `(deskewed_frame, source, report)`. The report is a dict; for a
    /// scan with no usable point its status is `"empty"` and the pose advanced on the
    /// constant-velocity model.
    #[pyo3(signature = (frame, timestamps=None))]
    fn register_frame<'py>(
        &mut self,
        py: Python<'py>,
        frame: &Bound<'py, PyAny>,
        timestamps: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, pyo3::types::PyTuple>> {
        convert::points_into(frame, "frame", &mut self.input)?;
        let stamps = match timestamps {
            Some(t) if !t.is_none() => Some(convert::values(t, "timestamps")?),
            _ => None,
        }
        .filter(|s| !s.is_empty());
        let index = self.driver.frames();
        // The samples go to the first frame whose sweep end is known.
        let samples = match stamps {
            Some(_) => std::mem::take(&mut self.imu),
            None => Vec::new(),
        };
        let (driver, points, deskewed) = (&mut self.driver, &self.input, &mut self.deskewed);
        let prior = &mut self.prior;
        let (outcome, located) = py
            .detach(|| {
                let outcome = one_frame(driver, points, stamps.as_deref(), &samples, deskewed)?;
                let located = prior.as_mut().map(|p| p.locate(driver, &outcome));
                anyhow::Ok((outcome, located))
            })
            .map_err(|e| PyRuntimeError::new_err(kiss_odom_drive::one_line(&e)))?;
        let report = report_dict(py, outcome.report(), index, self.input.len())?;
        if let (Some(u), Some(_)) = (outcome.imu, &stamps) {
            report.set_item("imu_prior", u.state())?;
            report.set_item("imu_samples", u.samples)?;
            report.set_item("gyro_bias", u.bias)?;
            report.set_item("imu_residual", u.residual)?;
            report.set_item("imu_disagreement", u.disagreement)?;
        }
        let mut warnings: Vec<String> = [
            self.driver.imu_check_warning(false),
            self.driver.one_plane_warning(&outcome),
        ]
        .into_iter()
        .flatten()
        .collect();
        if let (Some(p), Some(l)) = (self.prior.as_mut(), &located) {
            p.report(l, &report, &mut warnings)?;
        }
        report.set_item("warnings", warnings)?;
        let deskewed = convert::points_array_copy(py, &self.deskewed)?;
        let keep = self.driver.build().capacities.scan_points;
        trim_buffer(&mut self.input, keep);
        trim_buffer(&mut self.deskewed, keep);
        let source = match outcome.report() {
            Some(_) => self.driver.source_cloud(),
            None => Vec::new(),
        };
        let source = convert::points_array(py, source)?;
        (deskewed, source, report).into_pyobject(py)
    }

    /// Adds one IMU sample for the gyroscope prior (settings `imu.enabled`): `time` in seconds
    /// on the clock of the frames' timestamps (plus `imu.time_offset`), `gyro` in rad/s and
    /// `accel` in m/s^2, IMU axes. The next frame uses those given since the last one.
    fn add_imu(&mut self, time: f64, gyro: [f64; 3], accel: [f64; 3]) -> PyResult<()> {
        if self.driver.gyro_bias().is_none() {
            return Err(PyValueError::new_err(
                "add_imu needs the gyroscope prior: settings imu.enabled = true",
            ));
        }
        self.imu.push(ImuSample { time, gyro, accel });
        Ok(())
    }

    /// The gyroscope prior's bias estimate (rad/s, LiDAR axes), or `None` when it is off.
    fn gyro_bias(&self) -> Option<[f64; 3]> {
        self.driver.gyro_bias()
    }

    /// The latest pose, 4x4 (kiss-icp's `last_pose`).
    fn last_pose<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        matrix_of(py, &self.driver.pose())
    }

    /// The constant-velocity model, 4x4 (kiss-icp's `last_delta`).
    fn last_delta<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        matrix_of(py, &self.driver.last_delta())
    }

    /// Replaces the latest pose (a 4x4 rigid transform).
    fn set_last_pose(&mut self, pose: &Bound<'_, PyAny>) -> PyResult<()> {
        let p = convert::pose(pose, "last_pose")?;
        self.driver.set_last_pose(&p);
        Ok(())
    }

    /// Replaces the constant-velocity model (a 4x4 rigid transform).
    fn set_last_delta(&mut self, delta: &Bound<'_, PyAny>) -> PyResult<()> {
        let p = convert::pose(delta, "last_delta")?;
        self.driver.set_last_delta(&p);
        Ok(())
    }

    /// Every map point (world frame), Nx3.
    fn map_points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        convert::points_array(py, self.driver.map_points())
    }

    /// Empties the local map, keeping poses and threshold.
    fn clear_map(&mut self) {
        self.driver.clear_map()
    }

    /// Whether the local map is empty.
    fn map_empty(&self) -> bool {
        self.driver.map_is_empty()
    }

    /// Back to the state of a new odometry; with a prior map, localized from the initial pose
    /// again.
    fn reset(&mut self) {
        self.driver.reset();
        self.imu.clear();
        if let Some(p) = self.prior.as_mut() {
            p.reset();
        }
    }

    /// Frames registered or skipped so far.
    fn frames(&self) -> u64 {
        self.driver.frames()
    }

    /// The adaptive threshold's current sigma (m).
    fn sigma(&self) -> f64 {
        self.driver.sigma()
    }

    /// Bytes of state now (the map grows as the sequence needs, unless capacities are given).
    fn state_bytes(&self) -> usize {
        self.driver.memory().bytes
    }

    /// Largest occupancy of each buffer since start, against its capacity.
    fn high_water<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (hw, c) = (self.driver.high_water(), self.driver.memory().capacities);
        let d = PyDict::new(py);
        d.set_item("merge_points", (hw.merge_points, c.merge_points))?;
        d.set_item("source_points", (hw.source_points, c.source_points))?;
        d.set_item("map_voxels", (hw.map_voxels, c.map_voxels))?;
        d.set_item("map_point_slots", (hw.map_point_slots, c.map_points))?;
        Ok(d)
    }

    /// The settings in use as the TOML text `kiss-odom run` writes to `config.toml`.
    fn settings_toml(&self) -> PyResult<String> {
        self.settings.to_toml().map_err(value_error)
    }
}

/// The preset named `name` (`"default"` or `"accurate"`).
fn preset_named(name: &str) -> PyResult<PresetName> {
    serde_json::from_value(serde_json::Value::from(name)).map_err(|_| {
        PyValueError::new_err(format!(
            "preset must be 'default' or 'accurate', not {name:?}"
        ))
    })
}

/// `kiss-odom run`'s settings of a preset as JSON (the layout of its `config.toml`).
#[pyfunction]
#[pyo3(signature = (preset=None))]
fn default_settings_json(preset: Option<&str>) -> PyResult<String> {
    let err = |e: serde_json::Error| PyRuntimeError::new_err(e.to_string());
    let preset = preset.map(preset_named).transpose()?.unwrap_or_default();
    let mut v = serde_json::to_value(Settings::preset(preset)).map_err(err)?;
    // `config.toml` leaves the prior's section out while it is off; a dict may set it.
    v["imu"] = serde_json::to_value(kiss_odom_drive::Imu::default()).map_err(err)?;
    // Of the outputs' section only the frame a prior map must be in concerns `KissICP`.
    let frame = kiss_odom_drive::settings::Output::default().map_frame;
    v["output"] = serde_json::json!({ "map_frame": frame });
    serde_json::to_string(&v).map_err(err)
}

/// A settings file as settings JSON: a `config.toml` (as `kiss-odom run` writes it) or
/// kiss-icp's YAML (`.yaml`/`.yml`, read as `run --config` reads it), over the defaults of
/// `preset` when given (else of the file's); unknown keys are errors, and so are NaN and inf
/// (JSON would write them as `null`, "not given").
#[pyfunction]
#[pyo3(signature = (path, preset=None))]
fn load_settings_json(path: std::path::PathBuf, preset: Option<&str>) -> PyResult<String> {
    let preset = preset.map(preset_named).transpose()?;
    let s = Settings::load_as(&path, preset).map_err(value_error)?;
    s.refuse_non_finite()
        .map_err(|e| value_error(e.context(path.display().to_string())))?;
    serde_json::to_string(&s).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// The capacities of a preset (`"full"` or `"small"`) as a dict.
#[pyfunction]
fn capacity_preset<'py>(py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyDict>> {
    let c = match name {
        "full" => kiss_odom_core::Capacities::FULL_SCALE,
        "small" => kiss_odom_core::Capacities::SMALL,
        _ => {
            return Err(PyValueError::new_err(format!(
                "capacities preset must be 'full' or 'small', not {name:?}"
            )))
        }
    };
    let d = PyDict::new(py);
    d.set_item("scan_points", c.scan_points)?;
    d.set_item("merge_points", c.merge_points)?;
    d.set_item("source_points", c.source_points)?;
    d.set_item("map_voxels", c.map_voxels)?;
    d.set_item("map_points", c.map_points)?;
    Ok(d)
}

/// Adds the class and the settings helpers to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Odometry>()?;
    m.add_function(wrap_pyfunction!(default_settings_json, m)?)?;
    m.add_function(wrap_pyfunction!(load_settings_json, m)?)?;
    m.add_function(wrap_pyfunction!(capacity_preset, m)?)?;
    Ok(())
}
