//! A real ROS 2 sqlite3 bag of Hesai packets (`fixtures/nebula-xt32/`, see its README): `kiss-odom
//! convert` finds the sensor in the bag's `PandarScan` message, decodes it with Hesai's angle
//! correction file, and gives TIER IV nebula's points for it.

use crate::common::pcd_points;
use kiss_odom_tests::{kiss_odom, repo};
use std::ffi::OsString;
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    repo().join("fixtures/nebula-xt32").join(name)
}

/// The points of a converted frame (`velodyne/NNNNNN.bin`: f32 x y z intensity).
fn bin_points(path: &Path) -> Vec<[f64; 3]> {
    let bytes = std::fs::read(path).unwrap();
    bytes
        .chunks_exact(16)
        .map(|c| {
            let f = |i: usize| f64::from(f32::from_le_bytes(c[i..i + 4].try_into().unwrap()));
            [f(0), f(4), f(8)]
        })
        .collect()
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt()
}

/// Azimuth in degrees of a point in nebula's axes (x to azimuth 90 degrees, y to azimuth 0).
fn azimuth(p: &[f64; 3]) -> f64 {
    p[0].atan2(p[1]).to_degrees().rem_euclid(360.0)
}

/// The largest distance from a point of `from` to its nearest in `to`.
fn worst_nearest(from: &[[f64; 3]], to: &[[f64; 3]]) -> f64 {
    from.iter()
        .map(|p| to.iter().map(|q| dist(p, q)).fold(f64::INFINITY, f64::min))
        .fold(0.0, f64::max)
}

#[test]
fn convert_of_a_bag_of_pandar_packets_gives_nebulas_points() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let args: Vec<OsString> = vec![
        "convert".into(),
        fixture("bag").into(),
        "--out".into(),
        out.clone().into(),
        "--calibration".into(),
        fixture("PandarXT32.csv").into(),
        "--quiet".into(),
    ];
    let r = kiss_odom(&args, &out);
    assert_eq!(r.code, 0, "{}", r.stderr);
    // The packets end inside a turn: one partial sweep, as the stream ends.
    let frame = bin_points(&out.join("velodyne/000000.bin"));
    assert!(!out.join("velodyne/000001.bin").exists());
    // Nebula's axes and its range filter (0.05 to 120 m).
    let ours: Vec<[f64; 3]> = frame
        .iter()
        .map(|p| [-p[1], p[0], p[2]])
        .filter(|p| (0.05..=120.0).contains(&dist(p, &[0.0; 3])))
        .collect();
    let theirs = pcd_points(&std::fs::read(fixture("nebula-points.pcd")).unwrap());
    // Half a degree inside the packets' block azimuths (145.08 to 173.70 degrees).
    let inner = |p: &&[f64; 3]| (145.58..=173.2).contains(&azimuth(p));
    let ours_in: Vec<[f64; 3]> = ours.iter().filter(inner).copied().collect();
    let theirs_in: Vec<[f64; 3]> = theirs.iter().filter(inner).copied().collect();
    let to_ours = worst_nearest(&theirs_in, &ours);
    let to_theirs = worst_nearest(&ours_in, &theirs);
    println!(
        "XT32 sector: {} of our points and {} of nebula's half a degree inside it; worst \
         distance nebula to ours {to_ours:.2e} m, ours to nebula {to_theirs:.2e} m, tolerance \
         1e-5 m (float32 at up to 120 m)",
        ours_in.len(),
        theirs_in.len()
    );
    assert!(theirs_in.len() > 4_000, "the sector's points");
    assert_eq!(ours_in.len(), theirs_in.len());
    assert!(to_ours < 1e-5 && to_theirs < 1e-5);
}
