//! What kiss-icp 1.3.0's Python layer imports from its compiled `kiss_icp_pybind`, on the
//! core's stage functions: the same class and method names, argument names and return types,
//! so `kiss_odom.backend.install()` can put this module in its place and kiss-icp's own
//! `KissICP`, pipeline, dataloaders and metrics run unchanged.
//!
//! kiss-icp's map grows without bound; the core's `LocalMap` has fixed capacities. The map
//! here is rebuilt at twice the size, before an update, whenever the update could overflow
//! it (copying voxel by voxel keeps each voxel's points in order, so the admission rule and
//! the searches see the same map). Nothing is ever dropped.

use crate::convert::{self, points_array};
use kiss_odom_core::stages::{
    align_points_to_map, preprocess, scratch_words_for, voxel_downsample, work_words,
    AdaptiveThreshold, IcpParams, LocalMap, BLOCK,
};
use kiss_odom_core::{Exact, Point, Pose};
use kiss_odom_drive::pool::Pool;
use numpy::{PyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

/// kiss-icp's `std::vector<Eigen::Vector3d>`: a list of points, built from an Nx3 array and
/// read back with `numpy.asarray`.
#[pyclass(name = "_Vector3dVector", module = "kiss_odom._native")]
#[derive(Clone, Default)]
pub struct Vector3dVector {
    points: Vec<[f64; 3]>,
}

#[pymethods]
impl Vector3dVector {
    #[new]
    #[pyo3(signature = (points=None))]
    fn new(points: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let Some(obj) = points else {
            return Ok(Self::default());
        };
        if let Ok(v) = obj.cast::<Vector3dVector>() {
            return Ok(v.borrow().clone());
        }
        Ok(Self {
            points: convert::points(obj, "points")?,
        })
    }

    fn __len__(&self) -> usize {
        self.points.len()
    }

    #[pyo3(signature = (dtype=None, copy=None))]
    fn __array__<'py>(
        &self,
        py: Python<'py>,
        dtype: Option<&Bound<'py, PyAny>>,
        copy: Option<bool>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let _ = copy; // always a fresh array
        let arr = points_array(py, self.points.clone())?.into_any();
        match dtype {
            Some(d) if !d.is_none() => arr.call_method1("astype", (d,)),
            _ => Ok(arr),
        }
    }
}

fn vector(points: Vec<[f64; 3]>) -> Vector3dVector {
    Vector3dVector { points }
}

/// Room for this many points (and as many voxels) before the first growth.
const INITIAL_POINTS: usize = 1 << 14;

type Map = LocalMap<f64, Exact, Vec<u64>>;

/// kiss-icp's `VoxelHashMap` on the core's map, growing as needed.
#[pyclass(name = "_VoxelHashMap", module = "kiss_odom._native")]
pub struct VoxelHashMap {
    voxel_size: f64,
    max_distance: f64,
    max_points_per_voxel: u32,
    capacity: usize,
    map: Map,
}

fn new_map(v: f64, d: f64, n: u32, capacity: usize) -> PyResult<Map> {
    let words = vec![0u64; Map::words(capacity, capacity)];
    LocalMap::new(v, d, n, capacity, capacity, words)
        .map_err(|e| PyValueError::new_err(format!("voxel map: {e}")))
}

impl VoxelHashMap {
    /// Grows the map (rebuilding it at a larger capacity) until `incoming` more points fit
    /// whatever voxels they land in: each may open a voxel and need a block of its own.
    fn reserve(&mut self, incoming: usize) -> PyResult<()> {
        let view = self.map.view();
        let voxels = view.voxels() + incoming;
        let blocks = view.voxels() + view.points() / BLOCK + 1 + incoming;
        let need = voxels.max(blocks * BLOCK);
        if need <= self.capacity {
            return Ok(());
        }
        let capacity = need.max(2 * self.capacity);
        let mut grown = new_map(
            self.voxel_size,
            self.max_distance,
            self.max_points_per_voxel,
            capacity,
        )?;
        let mut old = Vec::with_capacity(view.points());
        view.for_each_point(|_, p| old.push(p));
        let st = grown.add_points(old.into_iter());
        if st.added != self.map.points() {
            return Err(PyRuntimeError::new_err("voxel map: growing lost points"));
        }
        self.map = grown;
        self.capacity = capacity;
        Ok(())
    }
}

#[pymethods]
impl VoxelHashMap {
    #[new]
    fn new(voxel_size: f64, max_distance: f64, max_points_per_voxel: u32) -> PyResult<Self> {
        if !(voxel_size.is_finite() && voxel_size > 0.0 && max_distance > 0.0) {
            return Err(PyValueError::new_err(
                "voxel_size and max_distance must be positive",
            ));
        }
        Ok(Self {
            voxel_size,
            max_distance,
            max_points_per_voxel,
            capacity: INITIAL_POINTS,
            map: new_map(
                voxel_size,
                max_distance,
                max_points_per_voxel,
                INITIAL_POINTS,
            )?,
        })
    }

    fn _clear(&mut self) {
        self.map.clear();
    }

    fn _empty(&self) -> bool {
        self.map.view().is_empty()
    }

    /// `(points, pose)`: adds the points moved by the 4x4 pose, then prunes around the pose;
    /// `(points, origin)`: adds world-frame points, then prunes around the 3-vector origin.
    fn _update(
        &mut self,
        points: PyRef<'_, Vector3dVector>,
        pose: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        self.reserve(points.points.len())?;
        if PyUntypedArrayMethods::len(&convert::float_array(pose, "pose")?) == 3 {
            let o = convert::vector3(pose, "origin")?;
            self.map
                .add_points(points.points.iter().map(|p| Point::from(*p)));
            self.map.remove_far_from(&Point::from(o));
        } else {
            let pose = convert::pose(pose, "pose")?;
            self.map.update(&points.points, &pose);
        }
        Ok(())
    }

    fn _add_points(&mut self, points: PyRef<'_, Vector3dVector>) -> PyResult<()> {
        self.reserve(points.points.len())?;
        self.map
            .add_points(points.points.iter().map(|p| Point::from(*p)));
        Ok(())
    }

    fn _remove_far_away_points(&mut self, origin: &Bound<'_, PyAny>) -> PyResult<()> {
        let o = convert::vector3(origin, "origin")?;
        self.map.remove_far_from(&Point::from(o));
        Ok(())
    }

    fn _point_cloud(&self) -> Vector3dVector {
        let mut out = Vec::with_capacity(self.map.points());
        self.map
            .view()
            .for_each_point(|_, p| out.push([p.x, p.y, p.z]));
        vector(out)
    }
}

/// kiss-icp's `Preprocessor`: deskew (when timestamps are given) and crop.
#[pyclass(name = "_Preprocessor", module = "kiss_odom._native")]
pub struct Preprocessor {
    max_range: f64,
    min_range: f64,
    deskew: bool,
}

#[pymethods]
impl Preprocessor {
    #[new]
    fn new(max_range: f64, min_range: f64, deskew: bool, max_num_threads: i64) -> Self {
        let _ = max_num_threads; // one pass over the points; threads would not help
        Self {
            max_range,
            min_range,
            deskew,
        }
    }

    fn _preprocess(
        &self,
        py: Python<'_>,
        points: PyRef<'_, Vector3dVector>,
        timestamps: &Bound<'_, PyAny>,
        relative_motion: &Bound<'_, PyAny>,
    ) -> PyResult<Vector3dVector> {
        let stamps = convert::values(timestamps, "timestamps")?;
        let motion = convert::pose(relative_motion, "relative_motion")?;
        let pts = &points.points;
        let out = py.detach(|| {
            let mut out = vec![[0.0; 3]; pts.len()];
            let stamps = (!stamps.is_empty()).then_some(stamps.as_slice());
            let r = preprocess(
                pts,
                stamps,
                &motion,
                self.min_range,
                self.max_range,
                self.deskew,
                &mut out,
            );
            out.truncate(r.kept.min(pts.len()));
            out
        });
        Ok(vector(out))
    }
}

/// kiss-icp's `Registration`: robust point-to-point ICP against a voxel map.
#[pyclass(name = "_Registration", module = "kiss_odom._native")]
pub struct Registration {
    params: IcpParams<f64>,
    pool: Pool,
}

#[pymethods]
impl Registration {
    #[new]
    fn new(
        max_num_iterations: u32,
        convergence_criterion: f64,
        max_num_threads: usize,
    ) -> PyResult<Self> {
        let threads = match max_num_threads {
            0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
            n => n,
        };
        Ok(Self {
            params: IcpParams {
                convergence_criterion,
                max_iterations: max_num_iterations,
                budget: None,
                planes: false,
                prior: None,
                stop_on_cycle: false,
            },
            pool: Pool::new(threads).map_err(|e| PyRuntimeError::new_err(e.to_string()))?,
        })
    }

    fn _align_points_to_map<'py>(
        &self,
        py: Python<'py>,
        points: PyRef<'py, Vector3dVector>,
        voxel_map: PyRef<'py, VoxelHashMap>,
        initial_guess: &Bound<'py, PyAny>,
        max_correspondance_distance: f64,
        kernel: f64,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let guess = convert::pose(initial_guess, "initial_guess")?;
        let (src, map) = (&points.points, &voxel_map.map);
        let pose: Pose<f64> = py.detach(|| {
            let mut work = vec![0u64; work_words::<f64>(src.len(), self.params.planes)];
            align_points_to_map(
                &self.pool,
                src,
                &mut work,
                &map.view(),
                &guess,
                max_correspondance_distance,
                kernel,
                &self.params,
            )
            .pose
        });
        convert::matrix_array(py, &pose.to_homogeneous())
    }
}

/// kiss-icp's `AdaptiveThreshold` (Sec. III-D).
#[pyclass(name = "_AdaptiveThreshold", module = "kiss_odom._native")]
pub struct Threshold {
    inner: AdaptiveThreshold<f64>,
}

#[pymethods]
impl Threshold {
    #[new]
    fn new(initial_threshold: f64, min_motion_th: f64, max_range: f64) -> Self {
        Self {
            inner: AdaptiveThreshold::new(initial_threshold, min_motion_th, max_range),
        }
    }

    fn _compute_threshold(&self) -> f64 {
        self.inner.sigma()
    }

    fn _update_model_deviation(&mut self, model_deviation: &Bound<'_, PyAny>) -> PyResult<()> {
        let d = convert::pose(model_deviation, "model_deviation")?;
        self.inner.update(&d);
        Ok(())
    }
}

/// kiss-icp's `VoxelDownsample`: the first point of each voxel, in the reference's order.
#[pyfunction]
fn _voxel_down_sample(
    py: Python<'_>,
    frame: PyRef<'_, Vector3dVector>,
    voxel_size: f64,
) -> PyResult<Vector3dVector> {
    if !(voxel_size.is_finite() && voxel_size > 0.0) {
        return Err(PyValueError::new_err("voxel_size must be positive"));
    }
    let input = &frame.points;
    py.detach(|| {
        let mut out = vec![[0.0; 3]; input.len()];
        let mut scratch = vec![0u64; scratch_words_for(out.len())];
        let r = voxel_downsample(input, voxel_size, &mut out, &mut scratch)?;
        out.truncate(r.kept);
        Some(out)
    })
    .map(vector)
    .ok_or_else(|| PyRuntimeError::new_err("voxel downsampling: scratch too small"))
}

/// kiss-icp's `CorrectKITTIScan` (the host's `io::folders::kitti::correct_scan`).
#[pyfunction]
fn _correct_kitti_scan(frame: PyRef<'_, Vector3dVector>) -> Vector3dVector {
    let mut pts = frame.points.clone();
    kiss_odom_io::folders::kitti::correct_scan(&mut pts);
    vector(pts)
}

/// Adds the classes and functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Vector3dVector>()?;
    m.add_class::<VoxelHashMap>()?;
    m.add_class::<Preprocessor>()?;
    m.add_class::<Registration>()?;
    m.add_class::<Threshold>()?;
    m.add_function(wrap_pyfunction!(_voxel_down_sample, m)?)?;
    m.add_function(wrap_pyfunction!(_correct_kitti_scan, m)?)?;
    Ok(())
}
