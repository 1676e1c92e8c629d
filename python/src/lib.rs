//! `kiss_odom._native`: the compiled half of the `kiss_odom` Python package.
//!
//! Four groups, each a thin layer over code that already exists in Rust:
//! - [`odometry`]: `Odometry`, the engine behind `kiss_odom.KissICP` (the core's `Odometry`
//!   on owned storage; every frame runs with the GIL released);
//! - [`stages`]: the classes and functions kiss-icp 1.3.0's Python layer imports from its
//!   compiled `kiss_icp_pybind`, on the core's stage functions (`kiss_odom.backend`);
//! - [`io`]: the trajectory metrics, the KITTI scan correction and ground truth, from
//!   `kiss-odom-io`;
//! - [`localize`]: localization in a prior map for `Odometry`, as `kiss-odom run --map`.
//!
//! Conversions between numpy arrays and points or poses live in [`convert`]; anything that
//! is not an Nx3 or 4x4 array of numbers becomes a `ValueError`, never a crash.

use pyo3::prelude::*;

pub mod convert;
pub mod io;
pub mod localize;
pub mod odometry;
pub mod stages;

/// The extension module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    odometry::register(m)?;
    stages::register(m)?;
    io::register(m)?;
    Ok(())
}
