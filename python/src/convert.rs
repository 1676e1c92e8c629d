//! numpy arrays in and out: Nx3 point arrays, 4x4 pose matrices, stacks of poses.
//!
//! Inputs go through `numpy.ascontiguousarray(x, dtype=float64)` first, so float32, integer
//! and non-contiguous arrays are converted; a wrong shape is a `ValueError` naming what was
//! expected and what came.

use kiss_odom_core::Pose;
use nalgebra::{Matrix3, Matrix4, Translation3};
use numpy::{PyArray1, PyArray2, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// `numpy.ascontiguousarray(obj, dtype=float64)` as an n-dimensional array.
pub fn float_array<'py>(
    obj: &Bound<'py, PyAny>,
    what: &str,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let np = obj.py().import("numpy")?;
    let arr = np
        .call_method1("ascontiguousarray", (obj, "float64"))
        .map_err(|e| PyValueError::new_err(format!("{what}: not an array of numbers ({e})")))?;
    Ok(arr.cast_into::<PyArrayDyn<f64>>()?)
}

/// An Nx3 array (or an empty one of any shape) as points.
pub fn points(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f64; 3]>> {
    let mut out = Vec::new();
    points_into(obj, what, &mut out)?;
    Ok(out)
}

/// [`points`] into a buffer that is reused from call to call.
pub fn points_into(obj: &Bound<'_, PyAny>, what: &str, out: &mut Vec<[f64; 3]>) -> PyResult<()> {
    out.clear();
    let arr = float_array(obj, what)?;
    let ro = arr.readonly();
    let shape = ro.shape();
    if ro.len() == 0 && (shape.len() == 1 || (shape.len() == 2 && shape[1] == 3)) {
        return Ok(());
    }
    if shape.len() != 2 || shape[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "{what} must be an Nx3 array of x, y, z; got shape {shape:?}{}",
            if shape.len() == 2 && shape[1] > 3 {
                " (pass frame[:, :3] to drop extra columns such as intensity)"
            } else {
                ""
            }
        )));
    }
    let flat = ro.as_slice()?;
    out.extend(flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
    Ok(())
}

/// A 1-D array of numbers (any shape is flattened, as kiss-icp's `timestamps.ravel()`).
pub fn values(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f64>> {
    let arr = float_array(obj, what)?;
    let ro = arr.readonly();
    Ok(ro.as_slice()?.to_vec())
}

/// A 4x4 homogeneous matrix of finite numbers.
pub fn matrix(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Matrix4<f64>> {
    let arr = float_array(obj, what)?;
    let ro = arr.readonly();
    if ro.shape() != [4, 4] {
        return Err(PyValueError::new_err(format!(
            "{what} must be a 4x4 matrix; got shape {:?}",
            ro.shape()
        )));
    }
    let m = Matrix4::from_row_slice(ro.as_slice()?);
    if m.iter().any(|v| !v.is_finite()) {
        return Err(PyValueError::new_err(format!(
            "{what} has a non-finite entry"
        )));
    }
    Ok(m)
}

/// Largest entry of `R^T R - I` accepted for a rotation block.
pub const ROTATION_TOLERANCE: f64 = 1e-6;

/// A 4x4 rigid transform as a pose, converting the rotation block to a quaternion without
/// re-projection, as Sophus does when kiss-icp's bindings receive a matrix. Anything that is
/// not a rigid transform (within [`ROTATION_TOLERANCE`]) is a `ValueError`.
pub fn pose(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Pose<f64>> {
    let m = matrix(obj, what)?;
    let r: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    let defect = (r.transpose() * r - Matrix3::identity()).amax();
    let bottom = [m[(3, 0)], m[(3, 1)], m[(3, 2)], m[(3, 3)]];
    if defect > ROTATION_TOLERANCE || r.determinant() < 0.0 || bottom != [0.0, 0.0, 0.0, 1.0] {
        return Err(PyValueError::new_err(format!(
            "{what} is not a rigid transform (rotation block off by {defect:.1e}, last row {bottom:?})"
        )));
    }
    let q = kiss_odom_io::pose::quaternion_of(&r);
    Ok(Pose::from_parts(
        Translation3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]),
        q,
    ))
}

/// A 3-vector (origin of a map update).
pub fn vector3(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<[f64; 3]> {
    let v = values(obj, what)?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok([*x, *y, *z]),
        _ => Err(PyValueError::new_err(format!(
            "{what} must be 3 finite numbers; got {} values",
            v.len()
        ))),
    }
}

/// A stack of 4x4 matrices (an Nx4x4 array or a list of 4x4 arrays).
pub fn matrices(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<Matrix4<f64>>> {
    let arr = float_array(obj, what)?;
    let ro = arr.readonly();
    let shape = ro.shape();
    if ro.len() == 0 {
        return Ok(Vec::new());
    }
    if shape.len() != 3 || shape[1] != 4 || shape[2] != 4 {
        return Err(PyValueError::new_err(format!(
            "{what} must be N 4x4 matrices; got shape {shape:?}"
        )));
    }
    Ok(ro
        .as_slice()?
        .chunks_exact(16)
        .map(Matrix4::from_row_slice)
        .collect())
}

/// Points as an Nx3 float64 array (the buffer is handed to numpy, not copied).
pub fn points_array<'py>(
    py: Python<'py>,
    pts: Vec<[f64; 3]>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let n = pts.len();
    let arr = numpy::ndarray::Array2::from_shape_vec((n, 3), pts.into_flattened())
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(PyArray2::from_owned_array(py, arr))
}

/// Points copied into a new Nx3 float64 array.
pub fn points_array_copy<'py>(
    py: Python<'py>,
    pts: &[[f64; 3]],
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    PyArray1::from_slice(py, pts.as_flattened()).reshape([pts.len(), 3])
}

/// A matrix as a 4x4 float64 array.
pub fn matrix_array<'py>(py: Python<'py>, m: &Matrix4<f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let flat: Vec<f64> = (0..16).map(|i| m[(i / 4, i % 4)]).collect();
    PyArray1::from_vec(py, flat).reshape([4, 4])
}
