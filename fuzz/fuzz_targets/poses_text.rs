//! Trajectory and calibration text: KITTI poses (`parse_kitti_rows`, `isometry_from_rows`), TUM
//! poses (`parse_tum`) and KITTI `calib.txt` (`read_calib_tr`, path only: a tmpfs file). What is
//! accepted is finite and rigid, and writing it back reads back the same.
#![no_main]

mod common;

use kiss_odom_io::folders::kitti::read_calib_tr;
use kiss_odom_io::poses::{
    format_kitti, format_tum, isometry_from_rows, parse_kitti_rows, parse_tum, rows_from_isometry,
};
use libfuzzer_sys::fuzz_target;
use nalgebra::Isometry3;

fn rigid(p: &Isometry3<f64>) -> bool {
    p.translation.vector.iter().all(|v| v.is_finite())
        && p.rotation.coords.iter().all(|v| v.is_finite())
        && (p.rotation.coords.norm() - 1.0).abs() < 1e-12
}

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(rows) = parse_kitti_rows(&text, "fuzz") {
        assert!(rows.iter().flatten().all(|v| v.is_finite()));
        let poses: Vec<Isometry3<f64>> = rows
            .iter()
            .filter_map(|r| isometry_from_rows(r).ok())
            .collect();
        assert!(poses.iter().all(rigid), "KITTI gave a non-rigid pose");
        // Written and read back, every bit survives.
        let back = parse_kitti_rows(&format_kitti(&poses), "back").expect("written KITTI parses");
        for (pose, row) in poses.iter().zip(&back) {
            assert_eq!(*row, rows_from_isometry(pose));
        }
    }
    if let Ok(poses) = parse_tum(&text, "fuzz") {
        for p in &poses {
            assert!(p.time.is_finite() && rigid(&p.pose), "TUM gave {p:?}");
        }
        let back = parse_tum(&format_tum(&poses), "back").expect("written TUM parses");
        assert_eq!(back.len(), poses.len());
        for (a, b) in poses.iter().zip(&back) {
            assert_eq!(a.time, b.time);
            assert_eq!(a.pose.translation, b.pose.translation);
            assert!(a.pose.rotation.angle_to(&b.pose.rotation) < 1e-12);
        }
    }
    let path = common::scratch_file("calib.txt", data);
    if let Ok(tr) = read_calib_tr(&path) {
        assert!(tr.iter().all(|v| v.is_finite()), "calib Tr {tr}");
    }
});
