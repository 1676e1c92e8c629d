//! Trajectory metrics: the last stage of a run, scoring the
//! estimated poses against ground truth the way the reference `kiss-icp` 1.3.0 scores them
//! (`cpp/kiss_icp/metrics/Metrics.cpp`: KITTI relative errors and ATE/ARE), plus the final
//! position error and the per-frame relative pose error.
//!
//! All functions take two trajectories of the same length, expressed in the same frame, one
//! pose per frame (sensor pose in the world). They validate their input and answer bad input
//! (lengths that differ, no poses, NaN or inf) with a [`MetricsError`], never a panic.

use crate::pose::quaternion_of;
use anyhow::Result;
use kiss_odom_core::stages::rotation_angle;
use nalgebra::{Isometry3, Matrix3, Translation3, Vector3};
use serde::Serialize;
use std::fmt;

/// Segment lengths of the KITTI odometry benchmark, metres.
pub const KITTI_SEGMENT_LENGTHS_M: [f64; 8] =
    [100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0];

/// Segments start every this many frames (one second at 10 Hz), as in the KITTI devkit.
pub const KITTI_STEP_FRAMES: usize = 10;

/// The value of pi the reference uses to turn radians into degrees in its KITTI rotation error
/// (`/ 3.14 * 180.0` in the devkit port). Kept so that our deg/m figures compare 1:1 with the
/// reference's; they are pi/3.14 = 1.000507 times (0.05 %) larger than with the true pi.
#[allow(clippy::approx_constant)] // deliberately not PI: the reference's value
pub const KITTI_DEVKIT_PI: f64 = 3.14;

/// Why a metric could not be computed. The caller should fix the input: pass two trajectories of
/// the same, non-zero length with finite values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MetricsError {
    /// The two trajectories have different lengths.
    LengthMismatch {
        /// Poses in the estimate.
        estimate: usize,
        /// Poses in the ground truth.
        ground_truth: usize,
    },
    /// There are no poses at all.
    Empty,
    /// A pose holds NaN or inf.
    NonFinite {
        /// Which trajectory (`"estimate"` or `"ground truth"`).
        which: &'static str,
        /// 0-based frame index.
        frame: usize,
    },
    /// The SVD of the Umeyama cross-covariance did not converge.
    SvdFailed,
}

impl fmt::Display for MetricsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::LengthMismatch {
                estimate,
                ground_truth,
            } => write!(
                f,
                "the estimate has {estimate} poses but the ground truth has {ground_truth}"
            ),
            Self::Empty => write!(f, "no poses to evaluate"),
            Self::NonFinite { which, frame } => {
                write!(f, "{which} pose at frame {frame} is not finite")
            }
            Self::SvdFailed => write!(f, "trajectory alignment failed (SVD did not converge)"),
        }
    }
}

impl std::error::Error for MetricsError {}

/// Everything `kiss-odom eval` reports.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Metrics {
    /// KITTI average relative translation error, percent; `None` when no 100 m segment fits.
    pub kitti_t_err_pct: Option<f64>,
    /// KITTI average relative rotation error, deg/m (with [`KITTI_DEVKIT_PI`]); `None` when no
    /// 100 m segment fits.
    pub kitti_r_err_deg_per_m: Option<f64>,
    /// Absolute trajectory error: translation RMSE after rigid alignment, metres.
    pub ate_m: f64,
    /// Absolute rotational error: rotation-angle RMSE after rigid alignment, radians. The
    /// alignment only sees positions, so on a short, nearly straight drive the roll about the
    /// direction of travel is barely determined and ARE can be large (1.36 rad on kitti-mini 04,
    /// in the reference too) while every per-frame error is small.
    pub are_rad: f64,
    /// Distance between estimated and true position at the last frame, no alignment, metres.
    pub final_error_m: f64,
    /// Mean per-frame relative translation error, metres.
    pub rpe_m_mean: f64,
    /// Largest per-frame relative translation error, metres.
    pub rpe_m_max: f64,
    /// Mean per-frame relative rotation error, radians.
    pub rpe_rad_mean: f64,
    /// Number of poses evaluated.
    pub frames: usize,
}

impl Metrics {
    /// The first metric that is not a finite number (finite poses far enough apart overflow
    /// the error sums), with its value; `None` when all are finite.
    pub fn non_finite(&self) -> Option<(&'static str, f64)> {
        let optional = [
            ("kitti_t_err_pct", self.kitti_t_err_pct),
            ("kitti_r_err_deg_per_m", self.kitti_r_err_deg_per_m),
        ];
        [
            ("ate_m", self.ate_m),
            ("are_rad", self.are_rad),
            ("final_error_m", self.final_error_m),
            ("rpe_m_mean", self.rpe_m_mean),
            ("rpe_m_max", self.rpe_m_max),
            ("rpe_rad_mean", self.rpe_rad_mean),
        ]
        .into_iter()
        .chain(optional.into_iter().filter_map(|(n, v)| Some((n, v?))))
        .find(|(_, v)| !v.is_finite())
    }
}

/// KITTI relative error averaged over all segments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KittiError {
    /// Mean of t_err/len over segments, percent.
    pub t_err_pct: f64,
    /// Mean of r_err/len over segments, converted with [`KITTI_DEVKIT_PI`], deg/m.
    pub r_err_deg_per_m: f64,
    /// Number of (start frame, length) segments averaged.
    pub segments: usize,
}

/// Absolute trajectory and rotational error after rigid alignment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AbsoluteError {
    /// Translation RMSE, metres.
    pub ate_m: f64,
    /// Rotation-angle RMSE, radians.
    pub are_rad: f64,
    /// The rigid transform applied to the estimate (`gt ≈ alignment * est`).
    pub alignment: Isometry3<f64>,
}

/// Per-frame relative pose error over consecutive frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RelativeError {
    /// Mean translation error, metres.
    pub t_mean_m: f64,
    /// Largest translation error, metres.
    pub t_max_m: f64,
    /// Mean rotation error, radians.
    pub r_mean_rad: f64,
    /// Largest rotation error, radians.
    pub r_max_rad: f64,
    /// Number of consecutive pairs (frames - 1).
    pub pairs: usize,
}

/// Checks that both trajectories have the same non-zero length and only finite values.
fn check(est: &[Isometry3<f64>], gt: &[Isometry3<f64>]) -> Result<(), MetricsError> {
    if est.len() != gt.len() {
        return Err(MetricsError::LengthMismatch {
            estimate: est.len(),
            ground_truth: gt.len(),
        });
    }
    if est.is_empty() {
        return Err(MetricsError::Empty);
    }
    for (which, poses) in [("estimate", est), ("ground truth", gt)] {
        if let Some(frame) = poses.iter().position(|p| !is_finite(p)) {
            return Err(MetricsError::NonFinite { which, frame });
        }
    }
    Ok(())
}

fn is_finite(p: &Isometry3<f64>) -> bool {
    p.translation.vector.iter().all(|v| v.is_finite())
        && p.rotation.coords.iter().all(|v| v.is_finite())
}

/// KITTI relative errors exactly as the reference's port of the KITTI devkit computes them:
/// for every start frame `f` that is a multiple of [`KITTI_STEP_FRAMES`] and every length `len`
/// of [`KITTI_SEGMENT_LENGTHS_M`], the end frame `l` is the first frame whose distance travelled
/// along the *ground truth* exceeds `dist[f] + len`; the segment's error is
/// `E = (est_f^-1 est_l)^-1 (gt_f^-1 gt_l)`, with `t_err = |t(E)| / len` and
/// `r_err = acos((trace R(E) - 1) / 2) / len`. Both are averaged over all segments (not per
/// length first) and reported in percent and in degrees per metre, using `3.14` for pi like the
/// reference ([`KITTI_DEVKIT_PI`]).
///
/// `Ok(None)` when no segment fits (ground truth shorter than 100 m), where the reference divides
/// by zero and reports NaN.
pub fn kitti_relative_error(
    est: &[Isometry3<f64>],
    gt: &[Isometry3<f64>],
) -> Result<Option<KittiError>, MetricsError> {
    check(est, gt)?;
    // Distance travelled along the ground truth up to each frame.
    let mut dist = Vec::with_capacity(gt.len());
    let mut acc = 0.0;
    dist.push(acc);
    for w in gt.windows(2) {
        acc += (w[1].translation.vector - w[0].translation.vector).norm();
        dist.push(acc);
    }

    let (mut t_sum, mut r_sum, mut segments) = (0.0, 0.0, 0usize);
    for first in (0..gt.len()).step_by(KITTI_STEP_FRAMES) {
        for len in KITTI_SEGMENT_LENGTHS_M {
            let Some(last) = (first..gt.len()).find(|&i| dist[i] > dist[first] + len) else {
                continue;
            };
            let delta_gt = gt[first].inv_mul(&gt[last]);
            let delta_est = est[first].inv_mul(&est[last]);
            let error = delta_est.inv_mul(&delta_gt);
            // The devkit's rotation error: acos of the trace, clamped.
            let trace = error.rotation.to_rotation_matrix().matrix().trace();
            let r_err = (0.5 * (trace - 1.0)).clamp(-1.0, 1.0).acos();
            let t_err = error.translation.vector.norm();
            t_sum += t_err / len;
            r_sum += r_err / len;
            segments += 1;
        }
    }
    if segments == 0 {
        return Ok(None);
    }
    let n = segments as f64;
    Ok(Some(KittiError {
        t_err_pct: 100.0 * (t_sum / n),
        r_err_deg_per_m: (r_sum / n) / KITTI_DEVKIT_PI * 180.0,
        segments,
    }))
}

/// The rigid transform `T` (rotation and translation, no scale) minimising
/// `sum |dst_i - T src_i|^2`: Umeyama (1991), as `Eigen::umeyama(src, dst, false)` computes it.
/// With `Sigma = (1/n) sum (dst_i - mu_dst)(src_i - mu_src)^T = U D V^T` (Eq. 38),
/// `R = U S V^T` with `S = diag(1, 1, -1)` when `det(U) det(V) < 0` (a reflection would fit
/// better, Eq. 39) and `S = I` otherwise (Eq. 40), and `t = mu_dst - R mu_src` (Eq. 41).
///
/// When the points are collinear (or all equal) the rotation about that line is not determined;
/// the result is then one of the optimal transforms, not necessarily Eigen's.
pub fn umeyama(src: &[Vector3<f64>], dst: &[Vector3<f64>]) -> Result<Isometry3<f64>, MetricsError> {
    if src.len() != dst.len() {
        return Err(MetricsError::LengthMismatch {
            estimate: src.len(),
            ground_truth: dst.len(),
        });
    }
    if src.is_empty() {
        return Err(MetricsError::Empty);
    }
    for (which, pts) in [("estimate", src), ("ground truth", dst)] {
        if let Some(frame) = pts.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
            return Err(MetricsError::NonFinite { which, frame });
        }
    }
    let one_over_n = 1.0 / src.len() as f64;
    let mean = |pts: &[Vector3<f64>]| pts.iter().sum::<Vector3<f64>>() * one_over_n;
    let (src_mean, dst_mean) = (mean(src), mean(dst));
    let sigma = src
        .iter()
        .zip(dst)
        .map(|(s, d)| (d - dst_mean) * (s - src_mean).transpose())
        .sum::<Matrix3<f64>>()
        * one_over_n;

    // nalgebra's dedicated 3x3 SVD works on the eigenvectors of Sigma^T Sigma, which squares the
    // condition number: on a near-straight drive (singular values 14 and 1e-6 on kitti-mini 04)
    // that moves the ARE in the fifth digit. The general (bidiagonalisation) path on a dynamic
    // matrix is as accurate as Eigen's JacobiSVD. try_new sorts the singular values, largest
    // first, so the sign flip below hits the smallest one.
    let dynamic = nalgebra::DMatrix::from_column_slice(3, 3, sigma.as_slice());
    let svd = nalgebra::SVD::try_new(dynamic, true, true, 5.0 * f64::EPSILON, 10_000)
        .ok_or(MetricsError::SvdFailed)?;
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return Err(MetricsError::SvdFailed);
    };
    let u: Matrix3<f64> = u.fixed_view::<3, 3>(0, 0).into_owned();
    let v_t: Matrix3<f64> = v_t.fixed_view::<3, 3>(0, 0).into_owned();
    let mut s = Vector3::new(1.0, 1.0, 1.0);
    if u.determinant() * v_t.determinant() < 0.0 {
        s[2] = -1.0;
    }
    let r = u * Matrix3::from_diagonal(&s) * v_t;
    let rotation = quaternion_of(&r);
    let t = dst_mean - rotation * src_mean;
    if !t.iter().all(|v| v.is_finite()) || !rotation.coords.iter().all(|v| v.is_finite()) {
        return Err(MetricsError::SvdFailed);
    }
    Ok(Isometry3::from_parts(Translation3::from(t), rotation))
}

/// ATE and ARE as the reference computes them: align the estimated positions to the true ones
/// with [`umeyama`] (rigid, no scale), then for every frame take `D = (A est_j)^-1 gt_j` and
/// report the RMSE of `|t(D)|` (metres) and of the rotation angle of `D` (radians).
pub fn absolute_trajectory_error(
    est: &[Isometry3<f64>],
    gt: &[Isometry3<f64>],
) -> Result<AbsoluteError, MetricsError> {
    check(est, gt)?;
    let src: Vec<Vector3<f64>> = est.iter().map(|p| p.translation.vector).collect();
    let dst: Vec<Vector3<f64>> = gt.iter().map(|p| p.translation.vector).collect();
    let alignment = umeyama(&src, &dst)?;
    let (mut t_sq, mut r_sq) = (0.0, 0.0);
    for (e, g) in est.iter().zip(gt) {
        let delta = (alignment * e).inv_mul(g);
        t_sq += delta.translation.vector.norm_squared();
        r_sq += rotation_angle(&delta.rotation).powi(2);
    }
    let n = est.len() as f64;
    Ok(AbsoluteError {
        ate_m: (t_sq / n).sqrt(),
        are_rad: (r_sq / n).sqrt(),
        alignment,
    })
}

/// `|t_est - t_gt|` at the last frame, without any alignment (both trajectories are assumed to
/// start in the same frame, as odometry does).
pub fn final_position_error(
    est: &[Isometry3<f64>],
    gt: &[Isometry3<f64>],
) -> Result<f64, MetricsError> {
    check(est, gt)?;
    match (est.last(), gt.last()) {
        (Some(e), Some(g)) => Ok((e.translation.vector - g.translation.vector).norm()),
        _ => Err(MetricsError::Empty),
    }
}

/// Per-frame relative pose error: for every consecutive pair,
/// `E_i = (gt_i^-1 gt_{i+1})^-1 (est_i^-1 est_{i+1})`; mean and max of `|t(E_i)|` and of the
/// rotation angle of `E_i`. A single pose has no pairs and all four figures are 0.
pub fn relative_pose_error(
    est: &[Isometry3<f64>],
    gt: &[Isometry3<f64>],
) -> Result<RelativeError, MetricsError> {
    check(est, gt)?;
    let mut out = RelativeError {
        t_mean_m: 0.0,
        t_max_m: 0.0,
        r_mean_rad: 0.0,
        r_max_rad: 0.0,
        pairs: 0,
    };
    for (e, g) in est.windows(2).zip(gt.windows(2)) {
        let error = g[0].inv_mul(&g[1]).inv_mul(&e[0].inv_mul(&e[1]));
        let t = error.translation.vector.norm();
        let r = rotation_angle(&error.rotation);
        out.t_mean_m += t;
        out.r_mean_rad += r;
        out.t_max_m = out.t_max_m.max(t);
        out.r_max_rad = out.r_max_rad.max(r);
        out.pairs += 1;
    }
    if out.pairs > 0 {
        out.t_mean_m /= out.pairs as f64;
        out.r_mean_rad /= out.pairs as f64;
    }
    Ok(out)
}

/// All metrics of `est` against `gt` (same length, same frame).
pub fn evaluate(est: &[Isometry3<f64>], gt: &[Isometry3<f64>]) -> Result<Metrics> {
    check(est, gt)?;
    let kitti = kitti_relative_error(est, gt)?;
    let ate = absolute_trajectory_error(est, gt)?;
    let rpe = relative_pose_error(est, gt)?;
    Ok(Metrics {
        kitti_t_err_pct: kitti.map(|k| k.t_err_pct),
        kitti_r_err_deg_per_m: kitti.map(|k| k.r_err_deg_per_m),
        ate_m: ate.ate_m,
        are_rad: ate.are_rad,
        final_error_m: final_position_error(est, gt)?,
        rpe_m_mean: rpe.t_mean_m,
        rpe_m_max: rpe.t_max_m,
        rpe_rad_mean: rpe.r_mean_rad,
        frames: est.len(),
    })
}
