//! Apollo-SouthBay: `pcds/<n>.pcd` (binary PCD, x y z intensity float32, numbered from 1)
//! and `poses/gt_poses.txt` (n t x y z qx qy qz qw, one row a scan) of the LiDAR's global
//! pose `W L`.

use super::{matrix, num, pcd, put, quaternion, translation, world, Source};
use anyhow::Result;
use std::path::Path;

/// The first scan's time (s).
pub const START_S: f64 = 1_500_000_000.0;

/// Writes the sequence into `dir`.
pub fn write(dir: &Path, source: &mut Source) -> Result<bool> {
    let complete = source.each_frame(|frame| {
        let path = dir.join(format!("pcds/{}.pcd", frame.index + 1));
        put(&path, &pcd(&frame.points))
    })?;
    if !complete {
        return Ok(false);
    }
    let w = world();
    let mut text = String::new();
    for k in 0..source.frames {
        let pose = w * matrix(&source.truth(k));
        let [x, y, z] = translation(&pose);
        let [qw, qx, qy, qz] = quaternion(&pose);
        let t = START_S + source.end_time(k);
        let cells = [t, x, y, z, qx, qy, qz, qw].map(num).join(" ");
        text.push_str(&format!("{} {cells}\n", k + 1));
    }
    put(&dir.join("poses/gt_poses.txt"), text.as_bytes())?;
    Ok(true)
}
