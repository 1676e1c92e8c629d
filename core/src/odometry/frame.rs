//! One scan through the paper's steps (Sec. III), once its points have arrived.
//!
//! [`Odometry::register`] reads like the paper; what the paper leaves out (the convergence
//! floor of a finite scalar, the fallback for a non-finite ICP result, the frame report) lives
//! in the named helpers below it.

use super::Odometry;
use crate::config::Config;
use crate::degeneracy::observability;
use crate::deskew::StampProblem;
use crate::downsample::{reference_order, Dedup, Downsampled};
use crate::error::FrameError;
use crate::lie::renormalize;
use crate::local_map::{MapMut, PointCodec, UpdateStats};
use crate::registration::{
    align_points_to_map, moved_points, Alignment, Executor, IcpParams, MotionPrior,
    PLANE_KERNEL_SCALE,
};
use crate::report::{Dropped, Flag, FrameReport, Status};
use crate::robust::{min_points, weakness, Degeneracy, Weakness};
use crate::scalar::Real;
use crate::storage::Storage;
use crate::{Point, Pose};

/// What receiving a scan produced (step 1 and the first pass of step 2, see `input`).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Received {
    /// The `alpha v` pass so far: points in the merge buffer, voxels dropped when it was full.
    pub(super) merged: Downsampled,
    /// Points kept by the crop (finite, within range).
    pub(super) kept: usize,
    /// Points offered, up to the scan capacity.
    pub(super) input: usize,
    /// Finite points outside the range shell.
    pub(super) out_of_range: u32,
    /// Input checks and capacity rules so far.
    pub(super) dropped: Dropped,
    /// Why the timestamps were not used, if they were given and unusable.
    pub(super) stamp_problem: Option<StampProblem>,
    /// Whether the scan is deskewed.
    pub(super) deskews: bool,
    /// The storage stopped holding the layout while the scan arrived.
    pub(super) storage_lost: bool,
}

/// Sizes of the two downsampled clouds.
#[derive(Clone, Copy, Debug)]
struct Clouds {
    merge: usize,
    source: usize,
}

impl<T: Real, P: PointCodec<T>, S: Storage> Odometry<T, P, S> {
    /// Steps 2-4 of Sec. III for a received scan, then the map update.
    pub(super) fn register<E: Executor>(
        &mut self,
        exec: &E,
        mut scan: Received,
    ) -> Result<FrameReport<T>, FrameError> {
        if scan.storage_lost {
            return Err(FrameError::Storage);
        }
        if scan.kept == 0 {
            return Err(FrameError::EmptyScan);
        }
        let cfg = self.config;
        let parts = self
            .layout
            .split::<T>(&self.caps, self.storage.as_mut())
            .map_err(|_| FrameError::Storage)?;
        let mut map = MapMut::<T, P>::of(&mut self.map, &self.layout.map, parts.map)
            .map_err(|_| FrameError::Storage)?;

        // Step 2 (Sec. III-B): P*_merge in the reference's order, then P^* from it.
        let clouds = downsample(&cfg, &mut scan, parts.merge, parts.source, parts.scratch);
        let (merge, source) = (&parts.merge[..clouds.merge], &parts.source[..clouds.source]);

        // Step 1's prediction, Eq. (1), and step 4's threshold, tau = 3 sigma_t (Eq. (7)).
        let prediction = self.last_pose * self.last_delta;
        let sigma = self.threshold.sigma();
        let max_distance = cfg.max_correspondence_factor * sigma;

        // Step 4 (Sec. III-E, Eq. (9)-(12)): robust ICP of P^* against the local map.
        let first_frame = map.view().is_empty();
        // Hold mode looks for weak directions once there is a prediction: the second frame's
        // is standing still, whatever the sensor does.
        let weak = match cfg.degeneracy {
            Degeneracy::Hold if !first_frame && self.frames >= 2 => weakness(
                &map.view(),
                source,
                &prediction,
                max_distance,
                min_points(cfg.alpha),
            ),
            _ => Weakness::NONE,
        };
        // Robust mode: the reference's registration, and where it leaves the pose degenerate,
        // a second one from the prediction with point-to-plane terms where the map is planar
        // (or only that one, when every frame passes the gate).
        let robust = cfg.degeneracy == Degeneracy::Robust;
        let always = robust && !first_frame && cfg.plane_gate >= T::one();
        // Its motion prior, once there is a velocity (as hold mode's); a term of weight 0 adds
        // nothing.
        let prior = (robust && self.frames >= 2).then(|| {
            let (hold, sideways) = (cfg.prediction_prior, cfg.lateral_prior);
            MotionPrior::new(&self.last_pose, &prediction, hold, sideways)
        });
        let mut register = |planes: bool| {
            let kernel = if planes {
                T::of(PLANE_KERNEL_SCALE)
            } else {
                cfg.kernel_scale
            };
            let icp = align_points_to_map(
                exec,
                source,
                &mut *parts.icp,
                &map.view(),
                &prediction,
                max_distance,
                kernel * sigma,
                &icp_params(&cfg, &prediction, &weak, planes, prior.filter(|_| planes)),
            );
            let (pose, finite) = finite_or(weak.apply(&prediction, icp.pose), prediction);
            let observability = if first_frame {
                None
            } else {
                let moved = moved_points::<T>(parts.icp, clouds.source, planes);
                let origin = Point::from(pose.translation.vector);
                observability(&map.view(), moved, clouds.source, &origin, max_distance)
            };
            Registered {
                icp,
                pose,
                finite,
                observability,
                planes,
            }
        };
        let mut reg = register(always);
        let degenerate = reg.observability.is_none_or(|o| o < cfg.plane_gate);
        if robust && !reg.planes && !first_frame && degenerate {
            reg = register(true);
        }
        let Registered {
            icp,
            pose,
            finite,
            observability,
            planes,
        } = reg;

        // Eq. (13): the model deviation is a sample of the adaptive threshold (Sec. III-D).
        let deviation = prediction.inverse() * pose;
        let model_error = self.threshold.model_error(&deviation);
        self.threshold.update(&deviation);

        // Sec. III-C: P*_merge joins the local map at T_t; voxels beyond r_max are pruned (a full
        // map gives up its farthest voxels first).
        let update = map.update(merge, &pose, parts.scratch);

        self.advance(pose);
        self.merge_len = clouds.merge;
        self.source_len = clouds.source;
        self.note_high_water(&clouds);
        let facts = Facts {
            sigma,
            icp,
            finite,
            first_frame,
            observability,
            weak,
            planes,
            model_error,
            update,
        };
        let report = self.report(&scan, &clouds, &facts);
        self.frames += 1;
        Ok(report)
    }

    /// The pose becomes `T_t`; the constant-velocity model `dT_t = T_{t-1}^-1 T_t` (Eq. (1))
    /// predicts the next scan and deskews it.
    fn advance(&mut self, pose: Pose<T>) {
        self.scan_motion = self.last_delta;
        self.last_delta = self.last_pose.inverse() * pose;
        self.last_pose = pose;
        renormalize(&mut self.last_pose);
    }

    fn note_high_water(&mut self, clouds: &Clouds) {
        let h = &mut self.high;
        h.merge_points = h.merge_points.max(clouds.merge);
        h.source_points = h.source_points.max(clouds.source);
        h.map_voxels = self.map.high_water_voxels();
        h.map_point_slots = self.map.high_water_point_slots();
    }

    /// The frame's report: the pose, what happened and what was dropped.
    fn report(&self, scan: &Received, clouds: &Clouds, f: &Facts<T>) -> FrameReport<T> {
        let mut dropped = scan.dropped;
        dropped.map_voxels_full = f.update.dropped_voxels as u32;
        dropped.map_points_full = f.update.dropped_points as u32;
        FrameReport {
            index: self.frames,
            pose: self.last_pose,
            status: status(&self.config, scan, &dropped, f),
            iterations: f.icp.iterations,
            work: f.icp.work,
            correspondences: f.icp.correspondences,
            sigma: f.sigma,
            rms: f.icp.rms,
            model_error: f.model_error,
            observability: f.observability,
            held: f.weak.held(),
            weak_ratios: f.weak.ratio,
            input_points: (scan.input + dropped.truncated as usize) as u32,
            out_of_range: scan.out_of_range,
            merge_points: clouds.merge as u32,
            source_points: clouds.source as u32,
            map_voxels: self.map.voxels() as u32,
            map_points: self.map.points() as u32,
            pruned_voxels: f.update.pruned_voxels as u32,
            map_radius: self.map.radius(),
            map_filled: f.update.filled,
            evicted_voxels: f.update.evicted_voxels as u32,
            dropped,
            deskewed: scan.deskews && scan.stamp_problem.is_none(),
            stamp_problem: scan.stamp_problem,
        }
    }
}

/// One registration of step 4 and what it left.
struct Registered<T: Real> {
    icp: Alignment<T>,
    pose: Pose<T>,
    finite: bool,
    observability: Option<T>,
    planes: bool,
}

/// What the steps found, for the report.
struct Facts<T: Real> {
    sigma: T,
    icp: Alignment<T>,
    finite: bool,
    first_frame: bool,
    observability: Option<T>,
    weak: Weakness<T>,
    /// Registered with robust mode's plane terms.
    planes: bool,
    model_error: T,
    update: UpdateStats,
}

/// Step 2 (Sec. III-B): the merge cloud, already filtered as it streamed in, is put in the
/// reference's order; the registration cloud is its `beta v` downsampling, in the same order.
fn downsample<T: Real>(
    cfg: &Config<T>,
    scan: &mut Received,
    merge: &mut [[T; 3]],
    source: &mut [[T; 3]],
    scratch: &mut [u64],
) -> Clouds {
    let alpha_v = cfg.voxel_size * cfg.alpha;
    let beta_v = cfg.voxel_size * cfg.beta;
    scan.dropped.merge_full = scan.merged.dropped as u32;
    let m = scan.merged.kept;
    reference_order(&mut merge[..m], alpha_v, scan.kept, scratch);
    let sourced = match Dedup::new(source, scratch, beta_v) {
        Some(mut dedup) => {
            for p in merge[..m].iter() {
                dedup.push(&Point::from(*p));
            }
            dedup.finish()
        }
        None => Downsampled::default(),
    };
    scan.dropped.source_full = sourced.dropped as u32;
    let s = sourced.kept;
    reference_order(&mut source[..s], beta_v, m, scratch);
    Clouds {
        merge: m,
        source: s,
    }
}

/// ICP's stopping rule: `gamma`, but never below what the scalar can resolve where the points
/// are. Map points sit up to `|t| + r_max` from the origin, and their rounding (8 ulp of that)
/// puts a floor under the correction ICP can reach. In f64 the floor is below 1e-10 m within
/// 10 km, far under gamma = 1e-4, so results are the reference's; in f32 it passes gamma once
/// `|t| + r_max` exceeds about 105 m, and without it ICP ran to the iteration cap on most frames
/// beyond 600 m from the start (tests/tests/long_run.rs).
fn icp_params<T: Real>(
    cfg: &Config<T>,
    prediction: &Pose<T>,
    weak: &Weakness<T>,
    planes: bool,
    prior: Option<MotionPrior<T>>,
) -> IcpParams<T> {
    let reach = prediction.translation.vector.norm() + cfg.max_range;
    IcpParams {
        convergence_criterion: cfg.convergence_criterion.max(T::of(8.0) * T::EPS * reach),
        max_iterations: cfg.max_iterations,
        budget: cfg.work_budget,
        hold: weak.hold,
        planes,
        prior,
    }
}

/// ICP's pose and `true`, or the prediction and `false` if ICP produced a non-finite pose
/// (the frame is then reported as singular).
fn finite_or<T: Real>(pose: Pose<T>, prediction: Pose<T>) -> (Pose<T>, bool) {
    let finite = pose.translation.vector.iter().all(|v| v.is_finite())
        && pose.rotation.coords.iter().all(|v| v.is_finite());
    if finite {
        (pose, true)
    } else {
        (prediction, false)
    }
}

/// The frame's status flags.
fn status<T: Real>(cfg: &Config<T>, scan: &Received, dropped: &Dropped, f: &Facts<T>) -> Status {
    let mut status = Status::OK;
    status.set(Flag::TimestampsIgnored, scan.stamp_problem.is_some());
    status.set(
        Flag::IterationCap,
        !f.icp.converged && !f.icp.singular && !f.icp.budget_spent,
    );
    status.set(Flag::Budget, f.icp.budget_spent);
    status.set(
        Flag::NoCorrespondences,
        !f.first_frame && f.icp.correspondences == 0,
    );
    status.set(
        Flag::Singular,
        !f.first_frame && (f.icp.singular || !f.finite),
    );
    // No structured voxel near any sample (a map of one huge voxel, say) measures nothing:
    // that is no evidence of a constrained pose either.
    status.set(
        Flag::Degenerate,
        !f.first_frame && f.observability.is_none_or(|o| o < cfg.degeneracy_ratio),
    );
    status.set(Flag::Held, f.weak.held().directions() > 0);
    status.set(Flag::Planes, f.planes);
    status.set(Flag::InvalidPoints, dropped.non_finite > 0);
    status.set(Flag::ScanTruncated, dropped.truncated > 0);
    status.set(Flag::Capacity, dropped.capacity());
    status.set(Flag::Evicted, f.update.evicted);
    status
}
