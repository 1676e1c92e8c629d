//! MulRan: `Ouster/<ns>.bin` (float32 x y z intensity, a 64 x 1024 grid) and
//! `global_pose.csv` (ns, then the base pose's 3x4 row-major), with pose rows at twice the
//! scan rate as the dataset has more poses than scans. The base pose is the LiDAR's through
//! the loader's calibration: `P = W T_lb^-1 L T_lb`, so that the loader's
//! `T_lb inv(P_0) P T_lb^-1` is the LiDAR's ground truth `L`.

use super::{f32_bytes, inverse, matrix, num, ouster_grid, put, stamp, world, Source};
use anyhow::Result;
use nalgebra::Matrix4;
use std::fmt::Write as _;
use std::path::Path;

/// The first scan's time (ns): 2019-08-23, as MulRan's KAIST sequences.
pub const START_NS: u64 = 1_566_535_940_000_000_000;

/// MulRan's LiDAR-to-base calibration, as kiss-icp's loader writes it.
#[rustfmt::skip]
pub const T_LIDAR_TO_BASE: [f64; 16] = [
    -9.9998295e-01, -5.8398386e-03, -5.2257060e-06, 1.7042000e00,
    5.8398386e-03, -9.9998295e-01, 1.7758769e-06, -2.1000000e-02,
    -5.2359878e-06, 1.7453292e-06, 1.0000000e00, 1.8047000e00,
    0.0, 0.0, 0.0, 1.0,
];

/// Writes the sequence into `dir`.
pub fn write(dir: &Path, source: &mut Source) -> Result<bool> {
    let sim = source.sim;
    let complete = source.each_frame(|frame| {
        let name = stamp(START_NS, sim.end_time(frame.index), 1e9);
        let grid = ouster_grid(sim, frame);
        let path = dir.join(format!("Ouster/{name}.bin"));
        put(&path, &f32_bytes(grid.iter().flatten().copied()))
    })?;
    if !complete {
        return Ok(false);
    }
    let lb = Matrix4::from_row_slice(&T_LIDAR_TO_BASE);
    let bl = inverse(&lb)?;
    let w = world();
    let mut csv = String::new();
    for k in 0..source.frames {
        for half in [0.0, 0.5] {
            let t = source.end_time(k) + half * source.period();
            let l = if half == 0.0 {
                source.truth(k)
            } else {
                source.pose_at(t)
            };
            let p = w * bl * matrix(&l) * lb;
            let mut line = stamp(START_NS, t, 1e9).to_string();
            for r in 0..3 {
                for c in 0..4 {
                    let _ = write!(line, ",{}", num(p[(r, c)]));
                }
            }
            csv.push_str(&line);
            csv.push('\n');
        }
    }
    put(&dir.join("global_pose.csv"), csv.as_bytes())?;
    Ok(true)
}
