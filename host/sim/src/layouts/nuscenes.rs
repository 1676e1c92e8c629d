//! nuScenes: the `v1.0-mini` tables of one scene, `scene-0061` (one of the `mini_train`
//! scenes kiss-icp's loader reads), its `LIDAR_TOP` sweeps as `.pcd.bin` files (float32 x y z
//! intensity ring), every second one a key frame under `samples/`, the others under `sweeps/`;
//! the split's other seven scenes are named without samples, as the devkit needs them.
//! Each `ego_pose` is the car's global pose `W L C^-1`, `C` the LiDAR's calibration, so that
//! the loader's `ego C` is `W L`. The tables the devkit loads but the loader does not use are
//! written empty.

use super::{from_quaternion, inverse, matrix, put, quaternion, stamp, translation, world, Source};
use anyhow::Result;
use serde_json::{json, Value};
use std::path::Path;

/// The scene written.
pub const SCENE: &str = "scene-0061";

/// The scenes of the devkit's `mini_train` split.
const MINI_TRAIN: [&str; 8] = [
    "scene-0061",
    "scene-0553",
    "scene-0655",
    "scene-0757",
    "scene-0796",
    "scene-1077",
    "scene-1094",
    "scene-1100",
];

/// The first sweep's time (us): 2018-07-24, as scene-0061.
pub const START_US: u64 = 1_532_402_927_647_951;

/// The LiDAR's calibration in the car: nuScenes' `LIDAR_TOP` (translation, `[w, x, y, z]`).
pub const LIDAR_TOP: ([f64; 3], [f64; 4]) = (
    [0.943713, 0.0, 1.84023],
    [
        0.7077955119163518,
        -0.006492242056004365,
        0.010646214713995808,
        -0.7063073142877817,
    ],
);

/// A 1 x 1 grey PNG: the map mask the devkit wants to find.
const MAP_PNG: [u8; 67] = [
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52,
    0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x01, 0x08, 0x00, 0x00, 0x00, 0x00, 0x3a, 0x7e, 0x9b,
    0x55, 0x00, 0x00, 0x00, 0x0a, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0x60, 0x00, 0x00, 0x00,
    0x02, 0x00, 0x01, 0x48, 0xaf, 0xa4, 0x71, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae,
    0x42, 0x60, 0x82,
];

fn filename(k: u64, us: u64) -> String {
    let folder = if k % 2 == 0 { "samples" } else { "sweeps" };
    format!("{folder}/LIDAR_TOP/n015-2018-07-24-11-22-45+0800__LIDAR_TOP__{us}.pcd.bin")
}

fn save(dir: &Path, name: &str, rows: &[Value]) -> Result<()> {
    let text = serde_json::to_string_pretty(rows)?;
    put(&dir.join(format!("v1.0-mini/{name}.json")), text.as_bytes())
}

/// Writes the sequence into `dir`.
pub fn write(dir: &Path, source: &mut Source) -> Result<bool> {
    let sim = source.sim;
    let complete = source.each_frame(|frame| {
        let us = stamp(START_US, sim.end_time(frame.index), 1e6);
        let values = frame
            .points
            .iter()
            .flat_map(|p| [p[0], p[1], p[2], p[3] * 255.0, 0.0]);
        put(
            &dir.join(filename(frame.index, us)),
            &super::f32_bytes(values),
        )
    })?;
    if !complete {
        return Ok(false);
    }
    let n = source.frames;
    let (ct, cq) = LIDAR_TOP;
    let norm = cq.iter().map(|v| v * v).sum::<f64>().sqrt();
    let car_to_velo = from_quaternion(cq.map(|v| v / norm), ct);
    let velo_to_car = inverse(&car_to_velo)?;
    let w = world();
    let sample = |k: u64| format!("sample-{:04}", k / 2);
    let link = |k: Option<u64>, name: &dyn Fn(u64) -> String| {
        k.filter(|&k| k < n).map_or(String::new(), name)
    };
    let (mut egos, mut data, mut samples) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..n {
        let us = stamp(START_US, source.end_time(k), 1e6);
        let ego = w * matrix(&source.truth(k)) * velo_to_car;
        egos.push(json!({
            "token": format!("ego-{k:04}"), "timestamp": us,
            "rotation": quaternion(&ego), "translation": translation(&ego),
        }));
        data.push(json!({
            "token": format!("sd-{k:04}"), "sample_token": sample(k),
            "ego_pose_token": format!("ego-{k:04}"), "calibrated_sensor_token": "cs-lidar-top",
            "timestamp": us, "fileformat": "pcd", "is_key_frame": k % 2 == 0,
            "height": 0, "width": 0, "filename": filename(k, us),
            "prev": link(k.checked_sub(1), &|k| format!("sd-{k:04}")),
            "next": link(Some(k + 1), &|k| format!("sd-{k:04}")),
        }));
        if k % 2 == 0 {
            samples.push(json!({
                "token": sample(k), "timestamp": us, "scene_token": "scene-token-0061",
                "prev": link(k.checked_sub(2), &sample), "next": link(Some(k + 2), &sample),
            }));
        }
    }
    let scene = json!({
        "token": "scene-token-0061", "log_token": "log-0", "nbr_samples": samples.len(),
        "first_sample_token": sample(0), "last_sample_token": sample((n - 1) / 2 * 2),
        "name": SCENE, "description": "kiss-odom simulate",
    });
    // The devkit maps every scene of the `mini_train` split to its log before kiss-icp's
    // loader picks one, so the others are named too, without samples.
    let mut scenes = vec![scene];
    for other in MINI_TRAIN.iter().filter(|s| **s != SCENE) {
        scenes.push(json!({
            "token": format!("scene-token-{other}"), "log_token": "log-0", "nbr_samples": 0,
            "first_sample_token": "", "last_sample_token": "", "name": other,
            "description": "named by the mini_train split; no samples",
        }));
    }
    save(dir, "scene", &scenes)?;
    save(dir, "sample", &samples)?;
    save(dir, "sample_data", &data)?;
    save(dir, "ego_pose", &egos)?;
    save(
        dir,
        "calibrated_sensor",
        &[json!({
            "token": "cs-lidar-top", "sensor_token": "sensor-lidar-top",
            "translation": ct, "rotation": cq, "camera_intrinsic": [],
        })],
    )?;
    save(
        dir,
        "sensor",
        &[json!({
            "token": "sensor-lidar-top", "channel": "LIDAR_TOP", "modality": "lidar",
        })],
    )?;
    save(
        dir,
        "log",
        &[json!({
            "token": "log-0", "logfile": "n015-2018-07-24-11-22-45+0800", "vehicle": "n015",
            "date_captured": "2018-07-24", "location": "singapore-onenorth",
        })],
    )?;
    save(
        dir,
        "map",
        &[json!({
            "token": "map-0", "log_tokens": ["log-0"], "category": "semantic_prior",
            "filename": "maps/map-0.png",
        })],
    )?;
    // The devkit checks that the map's mask image is there (it loads it only when asked).
    put(&dir.join("maps/map-0.png"), &MAP_PNG)?;
    for empty in [
        "category",
        "attribute",
        "visibility",
        "instance",
        "sample_annotation",
    ] {
        save(dir, empty, &[])?;
    }
    Ok(true)
}
