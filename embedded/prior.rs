//! Build-script part of the `localize` profile: the prior map file `KISS_EMBED_MAP` (made by
//! `run.sh` with `kiss-odom map build` from the first drive and its ground truth) copied to
//! `$OUT_DIR/map.komap` for the firmware's flash, and the revisit's ground-truth pose at the end
//! of its first embedded sweep as the localizer's start.

use std::env;
use std::path::Path;

/// Copies the map and returns the Rust source of the start pose: frame `first`'s row of the
/// drive's `poses.txt` (KITTI 3x4, in the map frame for a revisit) as a translation and a unit
/// quaternion.
pub fn prior(dir: &Path, first: usize, out: &Path) -> String {
    println!("cargo:rerun-if-env-changed=KISS_EMBED_MAP");
    let map = env::var("KISS_EMBED_MAP").expect("KISS_EMBED_MAP: the prior map (run.sh makes it)");
    println!("cargo:rerun-if-changed={map}");
    std::fs::copy(&map, out.join("map.komap")).unwrap_or_else(|e| panic!("{map}: {e}"));
    let poses = dir.join("poses.txt");
    let text =
        std::fs::read_to_string(&poses).unwrap_or_else(|e| panic!("{}: {e}", poses.display()));
    let row: Vec<f64> = text
        .lines()
        .nth(first)
        .unwrap_or_else(|| panic!("{}: no row {first}", poses.display()))
        .split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(row.len(), 12, "{}: row {first} is not 3x4", poses.display());
    let r = |i: usize, j: usize| row[i * 4 + j];
    format!(
        "/// The revisit's pose at the end of the first embedded sweep, in the map frame (ground\n\
         /// truth): translation.\n\
         pub const START_T: [f64; 3] = [{:?}, {:?}, {:?}];\n\
         /// Its rotation, a unit quaternion `w, x, y, z`.\n\
         pub const START_Q: [f64; 4] = {:?};\n",
        r(0, 3),
        r(1, 3),
        r(2, 3),
        quaternion([
            [r(0, 0), r(0, 1), r(0, 2)],
            [r(1, 0), r(1, 1), r(1, 2)],
            [r(2, 0), r(2, 1), r(2, 2)],
        ])
    )
}

/// A rotation matrix's unit quaternion `w, x, y, z` (Shepperd: from the largest of the four
/// diagonal combinations, so it stays accurate at any angle, half a turn included).
fn quaternion(m: [[f64; 3]; 3]) -> [f64; 4] {
    let t = m[0][0] + m[1][1] + m[2][2];
    let q = if t > 0.0 {
        let s = 2.0 * (1.0 + t).sqrt();
        [
            0.25 * s,
            (m[2][1] - m[1][2]) / s,
            (m[0][2] - m[2][0]) / s,
            (m[1][0] - m[0][1]) / s,
        ]
    } else if m[0][0] > m[1][1] && m[0][0] > m[2][2] {
        let s = 2.0 * (1.0 + m[0][0] - m[1][1] - m[2][2]).sqrt();
        [
            (m[2][1] - m[1][2]) / s,
            0.25 * s,
            (m[0][1] + m[1][0]) / s,
            (m[0][2] + m[2][0]) / s,
        ]
    } else if m[1][1] > m[2][2] {
        let s = 2.0 * (1.0 + m[1][1] - m[0][0] - m[2][2]).sqrt();
        [
            (m[0][2] - m[2][0]) / s,
            (m[0][1] + m[1][0]) / s,
            0.25 * s,
            (m[1][2] + m[2][1]) / s,
        ]
    } else {
        let s = 2.0 * (1.0 + m[2][2] - m[0][0] - m[1][1]).sqrt();
        [
            (m[1][0] - m[0][1]) / s,
            (m[0][2] + m[2][0]) / s,
            (m[1][2] + m[2][1]) / s,
            0.25 * s,
        ]
    };
    let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    q.map(|v| v / n)
}
