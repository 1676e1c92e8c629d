//! What every stage check uses: the inputs of a sequence's checks, the frames they pick, the
//! tolerances, the reference run's motion model, and the commands and rows they share.

use super::compare::max_point_difference;
use super::driver::arg;
use super::report::{sci, Row};
use anyhow::Result;
use kiss_odom_core::stages::{scratch_words_for, voxel_downsample};
use kiss_odom_core::Config;
use kiss_odom_drive::settings::Settings;
use kiss_odom_io::Frame;
use nalgebra::{Isometry3, Matrix4, Translation3, UnitQuaternion, Vector3};

/// Tolerance of cropping and deskewing with synthetic or no timing (m).
pub const TOL_PREPROCESS_M: f64 = 1e-9;
/// Tolerance of deskewing real sensor timing (m).
pub const TOL_REAL_DESKEW_M: f64 = 1e-6;
/// Tolerance of one registration from identical inputs (m and rad).
pub const TOL_REGISTRATION: f64 = 1e-6;
/// Tolerance of the adaptive threshold's sigma, relative, per frame.
pub const TOL_SIGMA_REL: f64 = 1e-9;
/// Tolerance of map point coordinates (each side transforms the points itself) (m).
pub const TOL_MAP_M: f64 = 1e-9;
/// Frames of map history the map, correspondence and registration checks use.
pub const MAP_FRAMES: usize = 5;
/// The perturbation of the second registration: a few cm and 0.5 degree off the prediction.
pub fn perturbation() -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(0.04, -0.03, 0.02),
        UnitQuaternion::from_axis_angle(
            &nalgebra::Unit::new_normalize(Vector3::new(0.3, -0.5, 0.8)),
            0.5f64.to_radians(),
        ),
    )
}

/// What the stage checks of a sequence start from.
pub struct SequenceInput<'a> {
    /// The selected frames, preloaded (sensor frame, KITTI-corrected where that applies).
    pub frames: &'a [Frame],
    /// The reference's poses for (at least) the first frames.
    pub ref_poses: &'a [Isometry3<f64>],
    /// The reference's sigma before each frame.
    pub ref_sigmas: &'a [f64],
    /// Settings shared by both implementations.
    pub settings: &'a Settings,
}

/// The reference's constant-velocity model before frame `k`: the last relative motion.
pub fn delta_before(poses: &[Isometry3<f64>], k: usize) -> Isometry3<f64> {
    if k < 2 {
        Isometry3::identity()
    } else {
        poses[k - 2].inverse() * poses[k - 1]
    }
}

/// The model deviation of every frame of a run, from its poses (the first is the identity).
pub fn model_deviations(poses: &[Isometry3<f64>]) -> Vec<Isometry3<f64>> {
    (0..poses.len())
        .map(|k| {
            if k == 0 {
                Isometry3::identity()
            } else {
                let prediction = poses[k - 1] * delta_before(poses, k);
                prediction.inverse() * poses[k]
            }
        })
        .collect()
}

/// A number as the reference driver reads it back exactly.
pub fn s(v: f64) -> String {
    format!("{v:?}")
}

/// Which stage frames: the first, and a pair `(b - 1, b)` with `b` the middle frame of the
/// run, but at least frame 9 (or the last): in motion, with a few frames of map behind it.
pub fn stage_frames(n: usize) -> (Vec<usize>, Option<(usize, usize)>) {
    if n == 0 {
        return (vec![], None);
    }
    let b = (n - 1).min(9).max(n / 2);
    if b == 0 {
        return (vec![0], None);
    }
    let mut picks = vec![0, b - 1, b];
    picks.dedup();
    (picks, Some((b - 1, b)))
}

/// Frames the stage checks need reference poses for.
pub fn frames_needed(n: usize) -> usize {
    stage_frames(n).0.last().map_or(0, |b| b + 1)
}

/// A 4x4 matrix from the reference driver's JSON.
pub fn matrix_of(v: &serde_json::Value) -> Result<Matrix4<f64>> {
    super::driver::matrix_from_json(v)
}

/// A map command with the map options of `cfg`.
pub fn map_cmd(cfg: &Config<f64>, command: &str) -> Vec<String> {
    vec![
        command.into(),
        "--voxel-size".into(),
        s(cfg.voxel_size),
        "--max-distance".into(),
        s(cfg.max_range),
        "--max-points-per-voxel".into(),
        cfg.max_points_per_voxel.to_string(),
    ]
}

/// `downsample --points IN --voxel V --out OUT`.
pub fn downsample_cmd(
    input: &std::path::Path,
    voxel: f64,
    out: &std::path::Path,
) -> Result<Vec<String>> {
    Ok(vec![
        "downsample".into(),
        "--points".into(),
        arg(input)?,
        "--voxel".into(),
        s(voxel),
        "--out".into(),
        arg(out)?,
    ])
}

/// Our voxel downsampling of `input`.
pub fn downsample(input: &[[f64; 3]], voxel: f64) -> Result<Vec<[f64; 3]>> {
    let mut out = vec![[0.0; 3]; input.len()];
    let mut scratch = vec![0u64; scratch_words_for(out.len())];
    let r = voxel_downsample(input, voxel, &mut out, &mut scratch)
        .ok_or_else(|| anyhow::anyhow!("downsampling scratch too small"))?;
    out.truncate(r.kept);
    Ok(out)
}

/// A row comparing two point lists position by position (same count required).
pub fn points_row(what: &str, ours: &[[f64; 3]], want: &[[f64; 3]], tol: f64) -> Row {
    if ours.len() != want.len() {
        return Row::broken(
            what,
            format!("{} vs {} points", ours.len(), want.len()),
            "same points",
        );
    }
    let d = max_point_difference(ours, want);
    Row::check(
        what,
        d,
        tol,
        format!("{} points, worst {} m", want.len(), sci(d)),
        format!("same points, <= {} m", sci(tol)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stage_frames_are_the_first_and_a_pair_in_motion() {
        assert_eq!(stage_frames(0), (vec![], None));
        assert_eq!(stage_frames(1), (vec![0], None));
        assert_eq!(stage_frames(2), (vec![0, 1], Some((0, 1))));
        assert_eq!(stage_frames(10), (vec![0, 8, 9], Some((8, 9))));
        assert_eq!(stage_frames(600), (vec![0, 299, 300], Some((299, 300))));
        assert_eq!(frames_needed(600), 301);
    }

    #[test]
    fn model_deviations_of_a_constant_velocity_run_vanish_after_the_second_frame() {
        let step = Isometry3::new(Vector3::new(1.0, 0.1, 0.0), Vector3::new(0.0, 0.0, 0.05));
        let mut poses = vec![Isometry3::identity()];
        for _ in 0..5 {
            let last = *poses.last().unwrap();
            poses.push(last * step);
        }
        let devs = model_deviations(&poses);
        assert_eq!(devs.len(), 6);
        // Frame 1 is predicted as standing still: its deviation is the whole step.
        assert!((devs[1].translation.vector - step.translation.vector).norm() < 1e-12);
        for d in &devs[2..] {
            assert!(d.translation.vector.norm() < 1e-12 && d.rotation.angle() < 1e-12);
        }
    }
}
