//! Boreas: `lidar/<us>.bin` (float32 x y z intensity laser time, 24 bytes a point) and
//! `applanix/lidar_poses.csv` (a header, then t, easting, northing, altitude, velocities,
//! roll, pitch, heading, angular rates; one row a scan) of the LiDAR's global pose `W L`. The
//! loader builds the rotation as `R_roll R_pitch R_yaw` of transposed elementary rotations,
//! so the angles written are those of `(W L)^T`'s rotation about z, then y, then x.

use super::{euler, f32_bytes, matrix, num, put, stamp, translation, world, Source};
use anyhow::Result;
use nalgebra::Matrix4;
use std::path::Path;

/// The first scan's time (us): 2020-11-26, as Boreas's first sequences.
pub const START_US: u64 = 1_606_417_230_036_848;

/// The CSV's header, as Boreas writes it.
const HEADER: &str = "GPSTime,easting,northing,altitude,vel_east,vel_north,vel_up,roll,pitch,\
                      heading,angvel_z,angvel_y,angvel_x";

/// Writes the sequence into `dir`.
pub fn write(dir: &Path, source: &mut Source) -> Result<bool> {
    let sim = source.sim;
    let complete = source.each_frame(|frame| {
        let us = stamp(START_US, sim.end_time(frame.index), 1e6);
        let values = frame
            .points
            .iter()
            .zip(&frame.stamps)
            .flat_map(|(p, t)| [p[0], p[1], p[2], p[3], 0.0, *t as f32]);
        put(&dir.join(format!("lidar/{us}.bin")), &f32_bytes(values))
    })?;
    if !complete {
        return Ok(false);
    }
    let w = world();
    let mut csv = format!("{HEADER}\n");
    for k in 0..source.frames {
        let us = stamp(START_US, source.end_time(k), 1e6);
        let pose = w * matrix(&source.truth(k));
        let [x, y, z] = translation(&pose);
        let transposed: Matrix4<f64> = pose.transpose();
        let (roll, pitch, yaw) = euler(&transposed);
        let cells = [x, y, z, 0.0, 0.0, 0.0, roll, pitch, yaw, 0.0, 0.0, 0.0]
            .map(num)
            .join(",");
        csv.push_str(&format!("{us},{cells}\n"));
    }
    put(&dir.join("applanix/lidar_poses.csv"), csv.as_bytes())?;
    Ok(true)
}
