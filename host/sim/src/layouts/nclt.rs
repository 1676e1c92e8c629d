//! NCLT: `2012-01-08/velodyne_sync/<us>.bin` (8 bytes a point: x y z as unsigned 16-bit
//! `(v + 100) / 0.005`, intensity, laser; y and z stored negated) and
//! `ground_truth/groundtruth_2012-01-08.csv` (us, x, y, z, roll, pitch, yaw) with rows at
//! twice the scan rate and one beyond each end, so that every scan is inside its time span.
//! The CSV's poses are the LiDAR's with y and z negated (`S W L S`, `S = diag(1, -1, -1, 1)`),
//! which the loader turns back: its ground truth is `W L`, not re-based.

use super::{euler, matrix, num, put, stamp, translation, world, Source};
use anyhow::Result;
use nalgebra::{Matrix4, Vector4};
use std::path::Path;

/// The date folder written (a real NCLT date).
pub const DATE: &str = "2012-01-08";

/// The first scan's time (us): 2012-01-08.
pub const START_US: u64 = 1_326_030_975_000_000;

/// A coordinate as stored: `(v + 100) / 0.005` rounded, `None` outside 16 bits.
fn encode(v: f64) -> Option<u16> {
    let s = ((v + 100.0) / 0.005).round();
    (0.0..=65535.0).contains(&s).then_some(s as u16)
}

/// Writes the sequence into `dir`.
pub fn write(dir: &Path, source: &mut Source) -> Result<bool> {
    let sim = source.sim;
    let complete = source.each_frame(|frame| {
        let name = stamp(START_US, sim.end_time(frame.index), 1e6);
        let mut bytes = Vec::with_capacity(frame.points.len() * 8);
        for p in &frame.points {
            let [x, y, z, i] = p.map(f64::from);
            let (Some(x), Some(y), Some(z)) = (encode(x), encode(-y), encode(-z)) else {
                continue;
            };
            for v in [x, y, z] {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
            bytes.extend_from_slice(&[(i * 255.0) as u8, 0]);
        }
        put(
            &dir.join(format!("{DATE}/velodyne_sync/{name}.bin")),
            &bytes,
        )
    })?;
    if !complete {
        return Ok(false);
    }
    let flip = Matrix4::from_diagonal(&Vector4::new(1.0, -1.0, -1.0, 1.0));
    let w = world();
    let mut csv = String::new();
    let last = source.frames as f64;
    let mut half = -1.0;
    while half <= 2.0 * last {
        let t = source.end_time(0) + half * 0.5 * source.period();
        let pose = flip * w * matrix(&source.pose_at(t)) * flip;
        let [x, y, z] = translation(&pose);
        let (roll, pitch, yaw) = euler(&pose);
        let cells = [x, y, z, roll, pitch, yaw].map(num).join(",");
        csv.push_str(&format!("{},{cells}\n", stamp(START_US, t, 1e6)));
        half += 1.0;
    }
    put(
        &dir.join(format!("ground_truth/groundtruth_{DATE}.csv")),
        csv.as_bytes(),
    )?;
    Ok(true)
}
