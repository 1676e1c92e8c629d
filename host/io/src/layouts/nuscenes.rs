//! nuScenes (`kiss_icp/datasets/nuscenes.py`, which needs `nuscenes-devkit`; the JSON tables
//! are read here directly).
//!
//! ```text
//! DATAROOT/v1.0-mini/scene.json, sample_data.json, calibrated_sensor.json, sensor.json,
//!                    ego_pose.json (and the other tables the devkit loads)
//! DATAROOT/samples/LIDAR_TOP/*.pcd.bin, sweeps/LIDAR_TOP/*.pcd.bin   float32 x y z intensity ring
//! ```
//!
//! `--sequence N` names the scene `scene-000N`. As the loader: the scene's `LIDAR_TOP` sweeps
//! from its first sample's key frame along the `next` links; each pose is the ego pose times
//! the LiDAR's calibration, stored as float32, then re-based to the first in float32 as numpy
//! does it ([`rebase_f32`]: the inverse in float64 rounded to float32, the product a float32
//! `sgemm`). The poses are about a kilometre from the map's origin, so each float32 rounding
//! there is about 1e-4 m: the arithmetic is replicated to the bit, with the fused
//! multiply-adds of the BLAS kernel OpenBLAS picks on x86-64 CPUs since Haswell
//! ([`Products`]); where kiss-icp's OpenBLAS rounds each product instead (its SSE kernels, on
//! a CPU it does not recognise) its ground truth differs from this by a few float32 steps (up
//! to about 5e-4 m at 2 km).
//! kiss-icp reads only the `v1.0-mini` tables' `mini_train` scenes; any version folder and
//! scene are read here. No per-point times.

use super::rotation::{product, quaternion_matrix_summed, rebase_f32, rigid, to_f32, Products};
use super::scans::read_f32_bin;
use super::{Layout, Scan, Truth};
use crate::dataset::Format;
use anyhow::{bail, Context, Result};
use nalgebra::Matrix4;
use serde::Deserialize;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The LiDAR channel the loader reads.
pub const CHANNEL: &str = "LIDAR_TOP";

#[derive(Deserialize)]
struct SceneRec {
    name: String,
    first_sample_token: String,
}

#[derive(Deserialize)]
struct SampleData {
    token: String,
    sample_token: String,
    ego_pose_token: String,
    calibrated_sensor_token: String,
    timestamp: i64,
    filename: String,
    is_key_frame: bool,
    next: String,
}

#[derive(Deserialize)]
struct Calibrated {
    token: String,
    sensor_token: String,
    translation: [f64; 3],
    rotation: [f64; 4],
}

#[derive(Deserialize)]
struct Sensor {
    token: String,
    channel: String,
}

#[derive(Deserialize)]
struct EgoPose {
    token: String,
    translation: [f64; 3],
    rotation: [f64; 4],
}

/// The table folder of `root`: `v1.0-mini` (the loader's) if it has `scene.json`, else the
/// only `v1.0-*` folder that has.
pub fn tables_dir(root: &Path) -> Option<PathBuf> {
    let mini = root.join("v1.0-mini");
    if mini.join("scene.json").is_file() {
        return Some(mini);
    }
    let mut found: Vec<PathBuf> = std::fs::read_dir(root)
        .ok()?
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with("v1.0-"))
        .map(|e| e.path())
        .filter(|p| p.join("scene.json").is_file())
        .collect();
    found.sort();
    (found.len() == 1).then(|| found.remove(0))
}

/// Whether `root` looks like a nuScenes data root.
pub fn detect(root: &Path) -> bool {
    tables_dir(root).is_some()
}

fn table<T: for<'de> Deserialize<'de>>(dir: &Path, name: &str) -> Result<Vec<T>> {
    let path = dir.join(format!("{name}.json"));
    let file = std::fs::File::open(&path)
        .with_context(|| format!("{}: cannot open (a nuScenes table)", path.display()))?;
    serde_json::from_reader(std::io::BufReader::new(file))
        .with_context(|| format!("{}: not a nuScenes {name} table", path.display()))
}

fn by_token<T>(rows: Vec<T>, token: impl Fn(&T) -> &str) -> HashMap<String, T> {
    rows.into_iter()
        .map(|r| (token(&r).to_string(), r))
        .collect()
}

/// The scene `sequence` names (`N` or `scene-N`, zero-padded to four digits as the loader
/// does), else the only scene.
fn scene<'a>(scenes: &'a [SceneRec], sequence: Option<&str>, dir: &Path) -> Result<&'a SceneRec> {
    let names = || {
        scenes
            .iter()
            .map(|s| s.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    match sequence {
        Some(asked) => {
            let number = asked.strip_prefix("scene-").unwrap_or(asked);
            let want = format!("scene-{number:0>4}");
            scenes.iter().find(|s| s.name == want).with_context(|| {
                format!(
                    "--sequence {asked}: no {want} in {} (scenes: {})",
                    dir.join("scene.json").display(),
                    names()
                )
            })
        }
        None => match scenes {
            [one] => Ok(one),
            _ => bail!(
                "{}: {} scenes; choose one with --sequence N (scenes: {})",
                dir.join("scene.json").display(),
                scenes.len(),
                names()
            ),
        },
    }
}

/// Opens the scene `sequence` names in the nuScenes data root `root`.
pub fn layout(root: &Path, sequence: Option<&str>) -> Result<Layout> {
    let scene = walk(root, sequence, Products::Fused)?;
    let matrices = rebase_f32(&scene.poses, Products::Fused, "the first LiDAR pose")?;
    Ok(Layout {
        format: Format::Nuscenes,
        scans: scene.scans,
        read: Box::new(|path, max| read_f32_bin(path, 5, max)),
        truth: Truth {
            path: scene.tables.join("ego_pose.json"),
            matrices,
        },
        warnings: Vec::new(),
    })
}

/// The LiDAR's global poses of the scene `sequence` names (`ego C`, each entry rounded to
/// float32 as the loader stores them), before the re-basing [`layout`] does, with numpy's
/// matrix products (pyquaternion's rotation matrices, `ego @ C`) summed as `products` says
/// ([`layout`]: fused).
pub fn global_poses(
    root: &Path,
    sequence: Option<&str>,
    products: Products,
) -> Result<Vec<Matrix4<f64>>> {
    Ok(walk(root, sequence, products)?.poses)
}

/// A scene's sweeps along the `next` links.
struct Scene {
    tables: PathBuf,
    scans: Vec<Scan>,
    poses: Vec<Matrix4<f64>>,
}

fn walk(root: &Path, sequence: Option<&str>, products: Products) -> Result<Scene> {
    let Some(dir) = tables_dir(root) else {
        bail!(
            "{}: no v1.0-mini/scene.json (nor one other v1.0-* table folder)",
            root.display()
        );
    };
    let scenes: Vec<SceneRec> = table(&dir, "scene")?;
    let scene = scene(&scenes, sequence, &dir)?;
    let data = by_token(table::<SampleData>(&dir, "sample_data")?, |r| &r.token);
    let calibrated = by_token(table::<Calibrated>(&dir, "calibrated_sensor")?, |r| {
        &r.token
    });
    let sensors = by_token(table::<Sensor>(&dir, "sensor")?, |r| &r.token);
    let egos = by_token(table::<EgoPose>(&dir, "ego_pose")?, |r| &r.token);
    let sd_path = dir.join("sample_data.json");
    let channel_of = |sd: &SampleData| -> Option<&str> {
        let cs = calibrated.get(&sd.calibrated_sensor_token)?;
        Some(sensors.get(&cs.sensor_token)?.channel.as_str())
    };
    let mut starts: Vec<&SampleData> = data
        .values()
        .filter(|sd| {
            sd.sample_token == scene.first_sample_token
                && sd.is_key_frame
                && channel_of(sd) == Some(CHANNEL)
        })
        .collect();
    starts.sort_by(|a, b| a.token.cmp(&b.token));
    let Some(mut sd) = starts.first().copied() else {
        bail!(
            "{}: no {CHANNEL} key frame for the first sample of {}",
            sd_path.display(),
            scene.name
        );
    };
    let mut scans = Vec::new();
    let mut matrices = Vec::new();
    loop {
        let cs = calibrated
            .get(&sd.calibrated_sensor_token)
            .with_context(|| {
                format!(
                    "{}: sample_data {} names a missing calibrated_sensor",
                    sd_path.display(),
                    sd.token
                )
            })?;
        let ego = egos.get(&sd.ego_pose_token).with_context(|| {
            format!(
                "{}: sample_data {} names a missing ego_pose",
                sd_path.display(),
                sd.token
            )
        })?;
        let [w, x, y, z] = cs.rotation;
        let car_to_velo = rigid(
            &quaternion_matrix_summed(w, x, y, z, products),
            cs.translation,
        );
        let [w, x, y, z] = ego.rotation;
        let pose_car = rigid(
            &quaternion_matrix_summed(w, x, y, z, products),
            ego.translation,
        );
        matrices.push(to_f32(&product(&pose_car, &car_to_velo, products)));
        scans.push(Scan {
            path: root.join(&sd.filename),
            time: Some(sd.timestamp as f64 * 1e-6),
        });
        if sd.next.is_empty() {
            break;
        }
        if scans.len() > data.len() {
            bail!(
                "{}: the next links of {} loop",
                sd_path.display(),
                scene.name
            );
        }
        sd = data.get(&sd.next).with_context(|| {
            format!(
                "{}: sample_data {} names a missing next {}",
                sd_path.display(),
                sd.token,
                sd.next
            )
        })?;
    }
    Ok(Scene {
        tables: dir,
        scans,
        poses: matrices,
    })
}
