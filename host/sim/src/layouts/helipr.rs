//! HeLiPR: the same sweeps as all four of its LiDARs' records, `LiDAR/<sensor>/<ns>.bin`,
//! and each sensor's `LiDAR_GT/global_<sensor>_gt.txt` (ns x y z qx qy qz qw, one row a scan,
//! the LiDAR's global pose `W L`). The first three scans are named at or before the time
//! from which Aeva records carry intensity, so both Aeva record layouts are written.

use super::{f32_bytes, matrix, num, put, quaternion, stamp, translation, world, Source};
use anyhow::Result;
use std::path::Path;

/// Aeva scans named up to this (ns) have no intensity field.
pub const AEVA_NO_INTENSITY_UNTIL: u64 = 1_691_936_557_946_849_179;

/// The sensors, as their folders are named.
pub const SENSORS: [&str; 4] = ["Ouster", "Velodyne", "Avia", "Aeva"];

/// One point as `sensor`'s record: `p` (x y z intensity) captured `dt` s after the sweep's
/// first point.
fn record(sensor: &str, ns: u64, p: &[f32; 4], dt: f64) -> Vec<u8> {
    let [x, y, z, i] = *p;
    let dt_ns = (dt * 1e9).round();
    let mut r = f32_bytes([x, y, z]);
    match sensor {
        "Ouster" => {
            r.extend(f32_bytes([i]));
            r.extend((dt_ns as u32).to_le_bytes());
            r.extend([0u8; 6]); // reflectivity, ring, ambient
        }
        "Velodyne" => {
            r.extend(f32_bytes([i]));
            r.extend(0u16.to_le_bytes()); // ring
            r.extend(f32_bytes([dt as f32]));
        }
        "Avia" => {
            r.extend([(i * 255.0) as u8, 0, 0]); // reflectivity, tag, line
            r.extend((dt_ns as u32).to_le_bytes());
        }
        _ => {
            r.extend(f32_bytes([i, 0.0])); // reflectivity, velocity
            r.extend((dt_ns as i32).to_le_bytes());
            r.push(0); // line index
            if ns > AEVA_NO_INTENSITY_UNTIL {
                r.extend(f32_bytes([i]));
            }
        }
    }
    r
}

/// Writes the sequence into `dir`.
pub fn write(dir: &Path, source: &mut Source) -> Result<bool> {
    let sim = source.sim;
    let start =
        AEVA_NO_INTENSITY_UNTIL - (sim.end_time(2.min(source.frames - 1)) * 1e9).round() as u64;
    let complete = source.each_frame(|frame| {
        let ns = stamp(start, sim.end_time(frame.index), 1e9);
        let first = frame.stamps.first().copied().unwrap_or(0.0);
        for sensor in SENSORS {
            let mut bytes = Vec::new();
            for (p, t) in frame.points.iter().zip(&frame.stamps) {
                bytes.extend(record(sensor, ns, p, t - first));
            }
            put(&dir.join(format!("LiDAR/{sensor}/{ns}.bin")), &bytes)?;
        }
        Ok(())
    })?;
    if !complete {
        return Ok(false);
    }
    let w = world();
    let mut text = String::new();
    for k in 0..source.frames {
        let ns = stamp(start, source.end_time(k), 1e9);
        let pose = w * matrix(&source.truth(k));
        let [x, y, z] = translation(&pose);
        let [qw, qx, qy, qz] = quaternion(&pose);
        let cells = [x, y, z, qx, qy, qz, qw].map(num).join(" ");
        text.push_str(&format!("{ns} {cells}\n"));
    }
    for sensor in SENSORS {
        put(
            &dir.join(format!("LiDAR_GT/global_{sensor}_gt.txt")),
            text.as_bytes(),
        )?;
    }
    Ok(true)
}
