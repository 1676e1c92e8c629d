//! What a run shows beside its poses: `--save-map` and `--save-cloud` files read
//! back with our readers and with independent ones (plyfile, pypcd4), `diagnostics.png`
//! decoded, and the `--rerun` recording read back with Rerun's own dataframe API. The
//! independent readers live in the venv `.ci/run` makes from `tests/rerun/requirements.txt`,
//! found through `KISS_ODOM_RERUN_PYTHON`; without it those parts print SKIP.

use crate::common;

use common::*;
use std::path::{Path, PathBuf};
use std::process::Command;

fn sample() -> PathBuf {
    repo().join("fixtures/kitti-05-reduced")
}

/// `tests/rerun/readback.py KIND PATH` in the venv, as JSON; `None` (after printing SKIP)
/// without `KISS_ODOM_RERUN_PYTHON`.
fn readback(kind: &str, path: &Path) -> Option<serde_json::Value> {
    let Some(python) = std::env::var_os("KISS_ODOM_RERUN_PYTHON") else {
        println!(
            "SKIP {kind} read-back of {}: KISS_ODOM_RERUN_PYTHON is not set \
             (a Python with tests/rerun/requirements.txt)",
            path.display()
        );
        return None;
    };
    let script = repo().join("tests/rerun/readback.py");
    let out = Command::new(python)
        .arg(script)
        .arg(kind)
        .arg(path)
        .output()
        .expect("the read-back Python starts");
    assert!(
        out.status.success(),
        "readback.py {kind} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    Some(serde_json::from_slice(&out.stdout).expect("readback.py prints JSON"))
}

#[test]
fn saved_map_has_the_last_frames_map_points_in_our_readers_and_others() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["map.ply", "map.pcd"] {
        let out = dir.path().join(name.replace('.', "-"));
        let map = dir.path().join(name);
        let r = run(&sample(), &out, &["--save-map", map.to_str().unwrap()]);
        r.succeeded_with_frames(10);
        let expected: usize = r.column("map_points").last().unwrap().parse().unwrap();
        let ours = match name {
            "map.ply" => kiss_odom_io::folders::ply::read(&map),
            _ => kiss_odom_io::folders::pcd::read(&map),
        }
        .unwrap();
        assert_eq!(ours.points.len(), expected, "{name}: our reader");
        assert!(expected > 1000, "a real map: {expected} points");
        if let Some(other) = readback("cloud", &map) {
            assert_eq!(other["points"], expected, "{name}: independent reader");
            let first: Vec<f64> = serde_json::from_value(other["first"].clone()).unwrap();
            assert_eq!(first, ours.points[0], "{name}: first point, bit for bit");
        }
    }
}

#[test]
fn saved_cloud_is_voxel_thinned_and_its_bound_drops_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let (out, cloud) = (dir.path().join("out"), dir.path().join("cloud.ply"));
    let c = cloud.to_str().unwrap();
    let r = run(
        &sample(),
        &out,
        &["--save-cloud", c, "--set", "output.cloud_voxel=0.5"],
    );
    r.succeeded_with_frames(10);
    assert!(r.warnings().is_empty(), "{}", r.stderr);
    let points = kiss_odom_io::folders::ply::read(&cloud).unwrap().points;
    // One point per 0.5 m voxel.
    let mut cells: Vec<[i64; 3]> = points
        .iter()
        .map(|p| p.map(|c| (c / 0.5).floor() as i64))
        .collect();
    cells.sort_unstable();
    cells.dedup();
    assert_eq!(cells.len(), points.len(), "two points share a voxel");
    assert!(points.len() > 1000, "{} points", points.len());
    if let Some(other) = readback("cloud", &cloud) {
        assert_eq!(other["points"], points.len(), "independent reader");
    }

    let bounded = dir.path().join("bounded.pcd");
    let r = run(
        &sample(),
        &dir.path().join("out2"),
        &[
            "--save-cloud",
            bounded.to_str().unwrap(),
            "--set",
            "output.cloud_max_points=100",
        ],
    );
    r.succeeded_with_frames(10);
    let w = r.warnings();
    assert!(
        w.len() == 1 && w[0].contains("output.cloud_max_points = 100"),
        "{}",
        r.stderr
    );
    assert_eq!(
        kiss_odom_io::folders::pcd::read(&bounded)
            .unwrap()
            .points
            .len(),
        100
    );
    assert_eq!(r.count("warnings"), 1);
}

#[test]
fn diagnostics_png_beside_the_trajectory_has_its_panels_drawn() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    run(&sample(), &out, &[]).succeeded_with_frames(10);
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(out.join("diagnostics.png")).unwrap(),
    ));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (1000, 1000));
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let pixels: Vec<&[u8]> = buf[..info.buffer_size()].chunks_exact(3).collect();
    let c = kiss_odom::plot::ESTIMATE_COLOR;
    let series = pixels.iter().filter(|p| **p == [c.0, c.1, c.2]).count();
    let inked = pixels.iter().filter(|p| **p != [255, 255, 255]).count();
    // Three panels (error, latency, iterations), each a 2-px line across ~850 px.
    assert!(series > 3 * 850, "series pixels: {series}");
    assert!(inked > 20_000, "non-white pixels: {inked}");
}

/// Whether this build has the `rerun` feature; prints SKIP if not.
fn rerun_built() -> bool {
    if !cfg!(feature = "rerun") {
        println!("SKIP: built without the `rerun` feature (cargo test --features rerun)");
    }
    cfg!(feature = "rerun")
}

#[test]
fn runs_with_and_without_rerun_give_byte_equal_poses() {
    if !rerun_built() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (plain, recorded) = (dir.path().join("plain"), dir.path().join("recorded"));
    run(&sample(), &plain, &[]).succeeded_with_frames(10);
    let rrd = dir.path().join("run.rrd");
    run(&sample(), &recorded, &["--rerun", rrd.to_str().unwrap()]).succeeded_with_frames(10);
    for name in ["poses_kitti.txt", "poses_tum.txt"] {
        let a = std::fs::read(plain.join(name)).unwrap();
        let b = std::fs::read(recorded.join(name)).unwrap();
        assert!(a == b, "{name} differs with --rerun");
    }
    assert!(std::fs::metadata(&rrd).unwrap().len() > 10_000);
}

#[test]
fn rerun_recording_reads_back_with_rerun_sdk() {
    if !rerun_built() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (out, rrd) = (dir.path().join("out"), dir.path().join("run.rrd"));
    let r = run(
        &sample(),
        &out,
        &[
            "--rerun",
            rrd.to_str().unwrap(),
            "--set",
            "output.rerun_map_every=4",
        ],
    );
    r.succeeded_with_frames(10);
    let Some(back) = readback("rrd", &rrd) else {
        return;
    };
    let entities = back["entities"].as_object().unwrap();
    let frames = |e: &str| -> Vec<u64> {
        serde_json::from_value(
            entities
                .get(e)
                .cloned()
                .unwrap_or_else(|| panic!("no entity {e} in the recording: {:?}", entities.keys())),
        )
        .unwrap()
    };
    let all: Vec<u64> = (0..10).collect();
    for e in [
        "/world/sensor",
        "/world/sensor/scan",
        "/world/source",
        "/metrics/latency_ms",
        "/metrics/iterations",
        "/metrics/sigma",
        "/metrics/model_error",
        "/metrics/map_voxels",
        "/metrics/map_points",
        "/metrics/dropped",
        "/flags/degenerate",
    ] {
        assert_eq!(frames(e), all, "{e}: one row per frame");
    }
    // Every 4th frame and after the last.
    for e in ["/world/map", "/world/trajectory", "/world/ground_truth"] {
        assert_eq!(frames(e), [0, 4, 8, 9], "{e}");
    }
    // Observability exists from the second frame on.
    assert_eq!(
        frames("/metrics/observability"),
        (1..10).collect::<Vec<_>>()
    );

    // A logged pose against poses_kitti.txt's line (Rerun stores f32).
    let poses = r.poses();
    let mut worst = 0.0_f64;
    for k in [1usize, 9] {
        let sensor = &back["sensor"][k.to_string()];
        let t: Vec<f64> = serde_json::from_value(sensor["translation"].clone()).unwrap();
        let m: Vec<f64> = serde_json::from_value(sensor["mat3x3"].clone()).unwrap();
        let p = &poses[k];
        for i in 0..3 {
            worst = worst.max((t[i] - p[(i, 3)]).abs());
            for j in 0..3 {
                // Column-major.
                worst = worst.max((m[j * 3 + i] - p[(i, j)]).abs());
            }
        }
    }
    let tolerance = 1e-6;
    println!("logged poses against poses_kitti.txt: worst {worst:.2e} (tolerance {tolerance:.0e})");
    assert!(worst <= tolerance);
}
