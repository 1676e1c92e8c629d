//! `Odometry`: the core's pipeline on owned storage, the engine of `kiss_odom.KissICP`.
//!
//! One object per sequence. The settings are those of `kiss-odom run` (its `Settings` as JSON;
//! `kiss_odom.config` builds them from kiss-icp's configs, dicts and `config.toml` files), so
//! the same frames give the same poses, bit for bit, as `run`. The frame call copies the points out of numpy, then registers, deskews and
//! downsamples with the GIL released.

use crate::convert::{self, narrow, Numpy};
use kiss_odom_core::{
    Exact, Flag, FrameError, FrameReport, GyroPrior, ImuSample, Odometry as Core, PointCodec,
    Prior, Quantized, Real, StampProblem,
};
use kiss_odom_drive::pool::Pool;
use kiss_odom_drive::settings::{PresetName, Scalar, Settings, Storage};
use kiss_odom_drive::widen::{widen, widen_report};
use nalgebra::Matrix4;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

type Owned<T, P> = Core<T, P, Box<[u64]>>;

/// The four builds of the core a configuration can ask for.
enum Engine {
    F64Exact(Owned<f64, Exact>),
    F64Quantized(Owned<f64, Quantized>),
    F32Exact(Owned<f32, Exact>),
    F32Quantized(Owned<f32, Quantized>),
}

/// Runs `$body` with `$o` bound to whichever build `$e` holds.
macro_rules! each {
    ($e:expr, $o:ident => $body:expr) => {
        match $e {
            Engine::F64Exact($o) => $body,
            Engine::F64Quantized($o) => $body,
            Engine::F32Exact($o) => $body,
            Engine::F32Quantized($o) => $body,
        }
    };
}

/// What one frame call gives back besides the deskewed frame, in f64, ready for numpy.
struct Outcome {
    source: Vec<[f64; 3]>,
    /// `None` for an empty scan.
    report: Option<FrameReport<f64>>,
}

/// kiss-odom's odometry for one sequence (see `kiss_odom.KissICP` for the documented surface).
#[pyclass(module = "kiss_odom._native")]
pub struct Odometry {
    engine: Engine,
    pool: Pool,
    settings: Settings,
    /// The frame's points and its deskewed copy: kept from frame to frame so their memory is
    /// already mapped (fresh 3 MB buffers cost page faults on every frame), up to
    /// `scan_points` points each ([`trim`]).
    input: Vec<[f64; 3]>,
    deskewed: Vec<[f64; 3]>,
    /// The gyroscope prior (settings `imu.enabled`) in the engine's scalar, and the samples
    /// `add_imu` gave since the last frame.
    prior: Option<Gyro>,
    imu: Vec<ImuSample<f64>>,
}

/// The gyroscope prior in the scalar of the engine.
enum Gyro {
    F64(GyroPrior<f64>),
    F32(GyroPrior<f32>),
}

/// The prior's step before a frame ending at `end` (s), in `odom`'s scalar.
fn prior_before<T: Real, P: PointCodec<T>>(
    prior: &mut GyroPrior<T>,
    odom: &mut Owned<T, P>,
    samples: &[ImuSample<f64>],
    end: f64,
) -> Prior {
    let s: Vec<ImuSample<T>> = samples
        .iter()
        .map(|s| ImuSample {
            time: s.time,
            gyro: s.gyro.map(T::of),
            accel: s.accel.map(T::of),
        })
        .collect();
    prior.before_frame(odom, &s, end)
}

fn build<T: Numpy, P: PointCodec<T>>(s: &Settings) -> PyResult<Owned<T, P>> {
    let config = s.core_config::<T>().map_err(value_error)?;
    let caps = s.capacities().map_err(value_error)?;
    Owned::<T, P>::boxed(config, caps).map_err(|e| PyValueError::new_err(e.to_string()))
}

fn value_error(e: anyhow::Error) -> PyErr {
    PyValueError::new_err(kiss_odom_drive::one_line(&e))
}

impl Odometry {
    fn from_settings(settings: Settings) -> PyResult<Self> {
        let engine = match (settings.runtime.scalar, settings.runtime.map_storage) {
            (Scalar::F64, Storage::Exact) => Engine::F64Exact(build(&settings)?),
            (Scalar::F64, Storage::Quantized) => Engine::F64Quantized(build(&settings)?),
            (Scalar::F32, Storage::Exact) => Engine::F32Exact(build(&settings)?),
            (Scalar::F32, Storage::Quantized) => Engine::F32Quantized(build(&settings)?),
        };
        let pool = Pool::new(settings.threads()).map_err(value_error)?;
        let prior = match settings.runtime.scalar {
            Scalar::F64 => settings
                .imu
                .core()
                .map_err(value_error)?
                .map(|c| Gyro::F64(GyroPrior::new(c))),
            Scalar::F32 => settings
                .imu
                .core()
                .map_err(value_error)?
                .map(|c| Gyro::F32(GyroPrior::new(c))),
        };
        Ok(Self {
            engine,
            pool,
            settings,
            input: Vec::new(),
            deskewed: Vec::new(),
            prior,
            imu: Vec::new(),
        })
    }
}

/// One frame through the core: register (or, for an empty scan, advance on the
/// constant-velocity model as `kiss-odom run` and kiss-icp do), then the deskewed frame into
/// `deskewed`.
fn one_frame<T: Numpy, P: PointCodec<T>>(
    odom: &mut Owned<T, P>,
    pool: &Pool,
    points: &[[f64; 3]],
    stamps: Option<&[f64]>,
    deskewed: &mut Vec<[f64; 3]>,
) -> Result<Outcome, FrameError> {
    let pts = T::narrow_points(points);
    match odom.register_frame_with(pool, &pts[..], stamps) {
        Ok(r) => {
            T::fill(deskewed, pts.len(), |out| {
                odom.deskewed_scan(&pts, stamps, out).kept
            });
            Ok(Outcome {
                source: T::widen_points(odom.source().to_vec()),
                report: Some(widen_report(&r)),
            })
        }
        Err(FrameError::EmptyScan) => {
            odom.skip_frame();
            deskewed.clear();
            Ok(Outcome {
                source: Vec::new(),
                report: None,
            })
        }
        Err(e) => {
            deskewed.clear();
            Err(e)
        }
    }
}

/// Gives back the memory of a frame buffer beyond `keep` points (the core reads no more of a
/// scan), so one huge frame does not hold hundreds of MB until the object goes.
fn trim(buffer: &mut Vec<[f64; 3]>, keep: usize) {
    if buffer.capacity() > keep {
        buffer.clear();
        buffer.shrink_to(keep);
    }
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

fn pose_matrix<T: Real>(p: &kiss_odom_core::Pose<T>) -> Matrix4<f64> {
    widen(p).to_homogeneous()
}

fn map_points<T: Real, P: PointCodec<T>>(odom: &Owned<T, P>) -> Vec<[f64; 3]> {
    let map = odom.map();
    let mut out = Vec::with_capacity(map.points());
    map.for_each_point(|_, p| out.push([p.x.wide(), p.y.wide(), p.z.wide()]));
    out
}

impl Odometry {
    /// The gyroscope prior before a frame with `stamps` (its sweep ends at the latest): what it
    /// did and the samples it had; `None` when the prior is off or the frame has no times.
    fn prior_before(&mut self, stamps: Option<&[f64]>) -> Option<(Prior, usize)> {
        self.prior.as_ref()?;
        let end = stamps?.iter().copied().reduce(f64::max)?;
        let samples = core::mem::take(&mut self.imu);
        let prior = match (self.prior.as_mut()?, &mut self.engine) {
            (Gyro::F64(p), Engine::F64Exact(o)) => prior_before(p, o, &samples, end),
            (Gyro::F64(p), Engine::F64Quantized(o)) => prior_before(p, o, &samples, end),
            (Gyro::F32(p), Engine::F32Exact(o)) => prior_before(p, o, &samples, end),
            (Gyro::F32(p), Engine::F32Quantized(o)) => prior_before(p, o, &samples, end),
            _ => return None,
        };
        Some((prior, samples.len()))
    }

    /// The gyroscope prior after the frame: ICP's disagreement with it (rad/s), if used.
    fn prior_after(&mut self) -> Option<f64> {
        match (self.prior.as_mut()?, &self.engine) {
            (Gyro::F64(p), Engine::F64Exact(o)) => p.after_frame(o),
            (Gyro::F64(p), Engine::F64Quantized(o)) => p.after_frame(o),
            (Gyro::F32(p), Engine::F32Exact(o)) => p.after_frame(o).map(f64::from),
            (Gyro::F32(p), Engine::F32Quantized(o)) => p.after_frame(o).map(f64::from),
            _ => None,
        }
    }
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
        Self::from_settings(s)
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
        let index = self.frames();
        let prior = self.prior_before(stamps.as_deref());
        let (engine, pool, points) = (&mut self.engine, &self.pool, &self.input);
        let deskewed = &mut self.deskewed;
        let out = py
            .detach(|| each!(engine, o => one_frame(o, pool, points, stamps.as_deref(), deskewed)))
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        let residual = self.prior_after();
        let report = report_dict(py, out.report.as_ref(), index, self.input.len())?;
        if let Some((prior, samples)) = prior {
            report.set_item("imu_prior", prior.name())?;
            report.set_item("imu_samples", samples)?;
            report.set_item("gyro_bias", self.gyro_bias())?;
            report.set_item("imu_residual", residual)?;
        }
        let deskewed = convert::points_array_copy(py, &self.deskewed)?;
        let keep = each!(&self.engine, o => o.capacities().scan_points);
        trim(&mut self.input, keep);
        trim(&mut self.deskewed, keep);
        let source = convert::points_array(py, out.source)?;
        (deskewed, source, report).into_pyobject(py)
    }

    /// Adds one IMU sample for the gyroscope prior (settings `imu.enabled`): `time` in seconds
    /// on the clock of the frames' timestamps (plus `imu.time_offset`), `gyro` in rad/s and
    /// `accel` in m/s^2, IMU axes. The next frame uses those given since the last one.
    fn add_imu(&mut self, time: f64, gyro: [f64; 3], accel: [f64; 3]) -> PyResult<()> {
        if self.prior.is_none() {
            return Err(PyValueError::new_err(
                "add_imu needs the gyroscope prior: settings imu.enabled = true",
            ));
        }
        self.imu.push(ImuSample { time, gyro, accel });
        Ok(())
    }

    /// The gyroscope prior's bias estimate (rad/s, LiDAR axes), or `None` when it is off.
    fn gyro_bias(&self) -> Option<[f64; 3]> {
        match self.prior.as_ref()? {
            Gyro::F64(p) => Some(p.bias()),
            Gyro::F32(p) => Some(p.bias().map(f64::from)),
        }
    }

    /// The latest pose, 4x4 (kiss-icp's `last_pose`).
    fn last_pose<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let m = each!(&self.engine, o => pose_matrix(o.last_pose()));
        convert::matrix_array(py, &m)
    }

    /// The constant-velocity model, 4x4 (kiss-icp's `last_delta`).
    fn last_delta<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let m = each!(&self.engine, o => pose_matrix(o.last_delta()));
        convert::matrix_array(py, &m)
    }

    /// Replaces the latest pose (a 4x4 rigid transform).
    fn set_last_pose(&mut self, pose: &Bound<'_, PyAny>) -> PyResult<()> {
        let p = convert::pose(pose, "last_pose")?;
        each!(&mut self.engine, o => o.set_last_pose(narrow(&p)));
        Ok(())
    }

    /// Replaces the constant-velocity model (a 4x4 rigid transform).
    fn set_last_delta(&mut self, delta: &Bound<'_, PyAny>) -> PyResult<()> {
        let p = convert::pose(delta, "last_delta")?;
        each!(&mut self.engine, o => o.set_last_delta(narrow(&p)));
        Ok(())
    }

    /// Every map point (world frame), Nx3.
    fn map_points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let pts = each!(&self.engine, o => map_points(o));
        convert::points_array(py, pts)
    }

    /// Empties the local map, keeping poses and threshold.
    fn clear_map(&mut self) {
        each!(&mut self.engine, o => o.clear_map())
    }

    /// Whether the local map is empty.
    fn map_empty(&self) -> bool {
        each!(&self.engine, o => o.map().is_empty())
    }

    /// Back to the state of a new odometry.
    fn reset(&mut self) {
        each!(&mut self.engine, o => o.reset());
        self.imu.clear();
        match &mut self.prior {
            Some(Gyro::F64(p)) => p.reset(),
            Some(Gyro::F32(p)) => p.reset(),
            None => {}
        }
    }

    /// Frames registered or skipped so far.
    fn frames(&self) -> u64 {
        each!(&self.engine, o => o.frames())
    }

    /// The adaptive threshold's current sigma (m).
    fn sigma(&self) -> f64 {
        each!(&self.engine, o => o.sigma().wide())
    }

    /// Bytes of state, fixed at construction.
    fn state_bytes(&self) -> usize {
        each!(&self.engine, o => o.state_bytes())
    }

    /// Largest occupancy of each buffer since start, against its capacity.
    fn high_water<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (hw, c) = each!(&self.engine, o => (o.high_water(), *o.capacities()));
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
