//! The readers and metrics from Python: the trajectory metrics (under kiss-icp's names too),
//! the KITTI scan correction and ground truth.

use crate::convert;
use kiss_odom_io::metrics::{absolute_trajectory_error, kitti_relative_error};
use kiss_odom_io::poses::isometry_from_matrix;
use kiss_odom_io::{Format, OpenOptions};
use nalgebra::Isometry3;
use numpy::{PyArray1, PyArray3, PyArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

fn poses(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<Isometry3<f64>>> {
    convert::matrices(obj, what)?
        .iter()
        .enumerate()
        .map(|(i, m)| {
            isometry_from_matrix(m).map_err(|e| PyValueError::new_err(format!("{what}[{i}]: {e}")))
        })
        .collect()
}

fn metrics_error(e: kiss_odom_io::metrics::MetricsError) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// KITTI relative errors of `estimate` against `ground_truth` (N 4x4 poses each, same
/// frame): `(translation %, rotation deg/m, segments)`, NaN and 0 segments when the ground
/// truth is shorter than 100 m.
#[pyfunction]
fn kitti_relative_error_segments(
    estimate: &Bound<'_, PyAny>,
    ground_truth: &Bound<'_, PyAny>,
) -> PyResult<(f64, f64, usize)> {
    let est = poses(estimate, "estimate")?;
    let gt = poses(ground_truth, "ground_truth")?;
    Ok(
        match kitti_relative_error(&est, &gt).map_err(metrics_error)? {
            Some(k) => (k.t_err_pct, k.r_err_deg_per_m, k.segments),
            None => (f64::NAN, f64::NAN, 0),
        },
    )
}

/// kiss-icp's `_kitti_seq_error(gt_poses, results_poses)`: `(translation %, rotation deg/m)`.
#[pyfunction]
fn _kitti_seq_error(
    gt_poses: &Bound<'_, PyAny>,
    results_poses: &Bound<'_, PyAny>,
) -> PyResult<(f64, f64)> {
    let (t, r, _) = kitti_relative_error_segments(results_poses, gt_poses)?;
    Ok((t, r))
}

/// kiss-icp's `_absolute_trajectory_error(gt_poses, results_poses)`: `(ARE rad, ATE m)`.
#[pyfunction]
fn _absolute_trajectory_error(
    gt_poses: &Bound<'_, PyAny>,
    results_poses: &Bound<'_, PyAny>,
) -> PyResult<(f64, f64)> {
    let gt = poses(gt_poses, "gt_poses")?;
    let est = poses(results_poses, "results_poses")?;
    let a = absolute_trajectory_error(&est, &gt).map_err(metrics_error)?;
    Ok((a.are_rad, a.ate_m))
}

/// The KITTI vertical-angle correction `kiss-odom run` applies to KITTI scans, on an Nx3 array.
#[pyfunction]
fn correct_kitti_scan<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
    let mut pts = convert::points(points, "points")?;
    kiss_odom_io::folders::kitti::correct_scan(&mut pts);
    convert::points_array(py, pts)
}

/// The ground truth `kiss-odom run` finds for a dataset (LiDAR frame, one 4x4 pose per
/// frame, as stored: not re-based), or `None`.
#[pyfunction]
fn ground_truth<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
) -> PyResult<Option<Bound<'py, PyArray3<f64>>>> {
    let ds = kiss_odom_io::open(&path, Format::Auto, &OpenOptions::default())
        .map_err(|e| PyRuntimeError::new_err(kiss_odom_drive::one_line(&e)))?;
    let Some(gt) = ds.info.ground_truth else {
        return Ok(None);
    };
    let flat: Vec<f64> = gt
        .iter()
        .flat_map(|p| {
            let m = p.to_homogeneous();
            (0..16).map(move |i| m[(i / 4, i % 4)])
        })
        .collect();
    Ok(Some(PyArray1::from_vec(py, flat).reshape([
        gt.len(),
        4,
        4,
    ])?))
}

/// Adds the functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(kitti_relative_error_segments, m)?)?;
    m.add_function(wrap_pyfunction!(_kitti_seq_error, m)?)?;
    m.add_function(wrap_pyfunction!(_absolute_trajectory_error, m)?)?;
    m.add_function(wrap_pyfunction!(correct_kitti_scan, m)?)?;
    m.add_function(wrap_pyfunction!(ground_truth, m)?)?;
    Ok(())
}
