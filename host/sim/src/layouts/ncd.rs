//! Newer College: `raw_format/ouster_scan/cloud_<s>_<ns>.pcd` (binary PCD, x y z intensity
//! float32, a 64 x 1024 grid) and `ground_truth/registered_poses.csv` (s, ns, x, y, z, qx,
//! qy, qz, qw; one row a scan). The CSV holds the body pose `W L T_CL^-1`, with the loader's
//! `T_CL` as it stores it (float32), so that its `inv(P_0 T_CL) P T_CL` is `L`.

use super::{from_quaternion, inverse, matrix, num, ouster_grid, pcd, put, quaternion, stamp};
use super::{translation, world, Source};
use anyhow::Result;
use std::path::Path;

/// The first scan's time (ns): 2020-03-10, as the dataset's first sequences.
pub const START_NS: u64 = 1_583_836_591_182_590_976;

/// The loader's `T_CL` as it stores it: each entry rounded to float32.
pub fn t_cl() -> nalgebra::Matrix4<f64> {
    let n = (0.383f64 * 0.383 + 0.924 * 0.924).sqrt();
    let m = from_quaternion([0.383 / n, 0.0, 0.0, 0.924 / n], [-0.084, -0.025, 0.050]);
    m.map(|v| f64::from(v as f32))
}

/// `cloud_<s>_<ns>.pcd` of a time in ns.
fn name(ns: u64) -> String {
    format!("cloud_{}_{:09}.pcd", ns / 1_000_000_000, ns % 1_000_000_000)
}

/// Writes the sequence into `dir`.
pub fn write(dir: &Path, source: &mut Source) -> Result<bool> {
    let sim = source.sim;
    let complete = source.each_frame(|frame| {
        let ns = stamp(START_NS, sim.end_time(frame.index), 1e9);
        let grid = ouster_grid(sim, frame);
        put(
            &dir.join("raw_format/ouster_scan").join(name(ns)),
            &pcd(&grid),
        )
    })?;
    if !complete {
        return Ok(false);
    }
    let cl_inv = inverse(&t_cl())?;
    let w = world();
    let mut csv = String::from("#sec,nsec,x,y,z,qx,qy,qz,qw\n");
    for k in 0..source.frames {
        let ns = stamp(START_NS, source.end_time(k), 1e9);
        let body = w * matrix(&source.truth(k)) * cl_inv;
        let [x, y, z] = translation(&body);
        let [qw, qx, qy, qz] = quaternion(&body);
        let cells = [x, y, z, qx, qy, qz, qw].map(num).join(",");
        csv.push_str(&format!(
            "{},{},{cells}\n",
            ns / 1_000_000_000,
            ns % 1_000_000_000
        ));
    }
    put(
        &dir.join("ground_truth/registered_poses.csv"),
        csv.as_bytes(),
    )?;
    Ok(true)
}
