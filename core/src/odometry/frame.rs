//! One scan through the paper's steps (Sec. III), once its points have arrived.
//!
//! [`Odometry::register`] reads like the paper, one call per step; step 4 in the configured
//! mode is `icp`, and what the paper leaves out (the frame report) lives in the helpers below.

use super::icp::{Predicted, Registered, Step};
use super::layout::{Layout, Parts};
use super::rehome::{nothing, shortfall};
use super::Odometry;
use crate::config::{Capacities, Config};
use crate::deskew::StampProblem;
use crate::downsample::{first_per_voxel, reference_order, Downsampled};
use crate::error::FrameError;
use crate::geometry::Pose;
use crate::lie::renormalize;
use crate::local_map::{MapMut, MapState, MapView, PointCodec, UpdateStats};
use crate::registration::Executor;
use crate::report::{Dropped, Flag, FrameReport, Status};
use crate::scalar::Real;
use crate::storage::Storage;

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

impl Received {
    /// Whether it was deskewed: asked to be, with usable timestamps.
    fn deskewed(&self) -> bool {
        self.deskews && self.stamp_problem.is_none()
    }

    /// The scan can be registered: its storage held and some point survived the crop.
    fn usable(&self) -> Result<(), FrameError> {
        if self.storage_lost {
            Err(FrameError::Storage)
        } else if self.kept == 0 {
            Err(FrameError::EmptyScan)
        } else {
            Ok(())
        }
    }
}

/// A scan registered, before anything of it is kept.
pub(super) struct Aligned<T: Real> {
    /// The configuration it was registered with.
    cfg: Config<T>,
    scan: Received,
    clouds: Clouds,
    reg: Registered<T>,
    /// The prediction the threshold measures the registration against.
    predicted: Pose<T>,
    /// Registered a second time, from a first registration of the same sweep.
    again: bool,
}

impl<T: Real> Aligned<T> {
    /// The pose the scan registered at.
    pub(super) fn pose(&self) -> Pose<T> {
        self.reg.pose
    }

    /// The model deviation, Eq. (13): the registered pose seen from the prediction.
    fn deviation(&self) -> Pose<T> {
        self.predicted.inverse() * self.reg.pose
    }
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
        scan: Received,
    ) -> Result<FrameReport<T>, FrameError> {
        let aligned = self.align(exec, scan, None)?;
        self.commit(aligned)
    }

    /// Steps 2 and 4: the pose a received scan registers at, from `start` if given (a first
    /// registration of the same sweep), else from the prediction. Nothing is kept yet (see
    /// [`Self::commit`]) but the clouds in their buffers.
    pub(super) fn align<E: Executor>(
        &mut self,
        exec: &E,
        mut scan: Received,
        start: Option<Pose<T>>,
    ) -> Result<Aligned<T>, FrameError> {
        scan.usable()?;
        // A host that grows its storage wants the whole scan kept (see `rehome`).
        self.room_for(Capacities {
            scan_points: scan.input + scan.dropped.truncated as usize,
            merge_points: if scan.merged.dropped > 0 {
                scan.kept
            } else {
                0
            },
            ..nothing()
        })?;
        // The map's shape from the first scan's density (`Config::sparse_scan_points`), taken
        // on by the map update (`commit`): until then the frame can still be refused.
        let cfg = if self.frames == 0 {
            self.first_scan_config(scan.kept)
        } else {
            self.config
        };
        // Step 1's prediction, Eq. (1) (the scan was deskewed with it as it arrived), and step
        // 4's threshold, tau = 3 sigma_t (Eq. (7)).
        let predicted = self.predict();
        let (mut parts, map) =
            open::<T, P>(&self.layout, &self.caps, &mut self.storage, &mut self.map)?;

        // Step 2 (Sec. III-B): P*_merge (in the reference's order, if configured), then P^*
        // from it.
        let m = order_merge(&cfg, &mut scan, parts.merge, parts.scratch);
        let from = Predicted {
            pose: start.unwrap_or(predicted.pose),
            ..predicted
        };
        // The first registration starts far from its answer, the prediction standing still.
        let coarse = if start.is_none() && predicted.frames == 1 {
            coarse_start(&cfg, exec, &mut parts, m, &map.view(), &from)
        } else {
            None
        };
        // Until a registration has measured every direction, every `beta v` voxel: a weakly
        // constrained scene's sparse structure is what measures its weak directions.
        let desired = if self.constrained {
            cfg.desired_source_points
        } else {
            0
        };
        let merge = &parts.merge[..m];
        let sourced = source_cloud(&cfg, desired, merge, parts.source, parts.scratch);
        scan.dropped.source_full = sourced.kept.dropped as u32;
        let need = Capacities {
            source_points: m,
            ..nothing()
        };
        if let Some(needed) = shortfall(&self.caps, self.when_full, &need) {
            if sourced.kept.dropped > 0 {
                self.needed = needed;
                return Err(FrameError::Full);
            }
        }
        let clouds = Clouds {
            merge: m,
            source: sourced.kept.kept,
        };
        let source = &parts.source[..clouds.source];

        // Step 4 (Sec. III-E, Eq. (9)-(12)): robust ICP of P^* against the local map.
        let from = Predicted {
            pose: coarse.as_ref().map_or(from.pose, |c| c.pose),
            ..from
        };
        let mut reg = Step::new(&cfg, exec, source).register(&from, &map.view(), parts.icp);
        if let Some(c) = coarse {
            reg.icp.iterations += c.icp.iterations;
            reg.icp.work += c.icp.work;
        }
        Ok(Aligned {
            cfg,
            scan,
            clouds,
            reg,
            predicted: predicted.pose,
            again: start.is_some(),
        })
    }

    /// The threshold's sample, the map update and the new pose, for a registered scan.
    pub(super) fn commit(&mut self, a: Aligned<T>) -> Result<FrameReport<T>, FrameError> {
        self.room_for(self.map_room(a.clouds.merge))?;
        self.use_config(a.cfg);
        // Eq. (13): the model deviation is a sample of the adaptive threshold (Sec. III-D).
        let deviation = a.deviation();
        let model_error = self.threshold.in_use().model_error(&deviation);
        self.threshold.update(&deviation);

        // Sec. III-C: P*_merge joins the local map at T_t; voxels beyond r_max are pruned (a full
        // map gives up its farthest voxels first).
        let (parts, mut map) =
            open::<T, P>(&self.layout, &self.caps, &mut self.storage, &mut self.map)?;
        let merge = &parts.merge[..a.clouds.merge];
        let update = map.update(merge, &a.reg.pose, parts.scratch);

        // T_t becomes the last pose; the frame's report.
        Ok(self.conclude(&a, model_error, &update))
    }

    /// Whether a registered whole scan is deskewed and registered again with the motion found
    /// ([`Config::redeskew`]). It was deskewed at a constant rate and registered against a
    /// map; the registration measured every direction (its observability is not below
    /// `degeneracy_ratio`: a degenerate one's motion along a weak direction is not measured,
    /// and deskewing with it bends the sweep); and its motion moves a point at `r_max` by more
    /// than `delta_min` at the sweep's start from where the prediction put it (below that the
    /// paper's threshold reads the deviation as no motion, Sec. III-D).
    pub(super) fn redeskews(&self, a: &Aligned<T>) -> bool {
        let cfg = &self.config;
        cfg.redeskew
            && a.scan.deskewed()
            && self.sweep_rotation.is_none()
            && a.reg.finite
            && measured_every_direction(cfg, &a.reg)
            && self.threshold.in_use().model_error(&a.deviation()) > cfg.min_motion_threshold
    }

    /// Eq. (1): the constant-velocity prediction `T_{t-1} dT_{t-1}`, with what step 4 needs to
    /// know of the past: the threshold's `sigma_t` and the frames so far.
    fn predict(&self) -> Predicted<T> {
        Predicted {
            pose: self.last_pose * self.last_delta,
            last_pose: self.last_pose,
            sigma: self.threshold.in_use().sigma(),
            frames: self.frames,
        }
    }

    /// The frame is done: `T_t` and the motion (see [`Self::advance`]), the buffers' sizes and
    /// high-water marks, and the report.
    fn conclude(&mut self, a: &Aligned<T>, model_error: T, update: &UpdateStats) -> FrameReport<T> {
        self.advance(a.reg.pose);
        self.constrained = measured_every_direction(&self.config, &a.reg);
        self.note(&a.clouds);
        let report = self.report(a, model_error, update);
        self.frames += 1;
        report
    }

    /// The pose becomes `T_t`; the constant-velocity model `dT_t = T_{t-1}^-1 T_t` (Eq. (1))
    /// predicts the next scan and deskews it.
    fn advance(&mut self, pose: Pose<T>) {
        self.scan_motion = self.deskew_motion;
        self.scan_rotation = self.sweep_rotation.take();
        self.last_delta = self.last_pose.inverse() * pose;
        self.last_pose = pose;
        renormalize(&mut self.last_pose);
    }

    /// The clouds' sizes and every buffer's high-water mark.
    fn note(&mut self, clouds: &Clouds) {
        self.merge_len = clouds.merge;
        self.source_len = clouds.source;
        let h = &mut self.high;
        h.merge_points = h.merge_points.max(clouds.merge);
        h.source_points = h.source_points.max(clouds.source);
        h.map_voxels = self.map.high_water_voxels();
        h.map_point_slots = self.map.high_water_point_slots();
    }

    /// The frame's report: the pose, what happened and what was dropped.
    fn report(&self, a: &Aligned<T>, model_error: T, update: &UpdateStats) -> FrameReport<T> {
        let (scan, clouds, f) = (&a.scan, &a.clouds, &a.reg);
        let mut dropped = scan.dropped;
        dropped.map_voxels_full = update.dropped_voxels as u32;
        dropped.map_points_full = update.dropped_points as u32;
        FrameReport {
            index: self.frames,
            pose: self.last_pose,
            status: status(&self.config, scan, &dropped, f, update),
            iterations: f.icp.iterations,
            work: f.icp.work,
            correspondences: f.icp.correspondences,
            plane_correspondences: f.icp.plane_correspondences,
            sigma: f.sigma,
            rms: f.icp.rms,
            model_error,
            observability: f.observability,
            held: f.weak.held(),
            weak_ratios: f.weak.ratio,
            input_points: (scan.input + dropped.truncated as usize) as u32,
            out_of_range: scan.out_of_range,
            merge_points: clouds.merge as u32,
            source_points: clouds.source as u32,
            map_voxels: self.map.voxels() as u32,
            map_points: self.map.points() as u32,
            pruned_voxels: update.pruned_voxels as u32,
            map_radius: self.map.radius(),
            map_filled: update.filled,
            evicted_voxels: update.evicted_voxels as u32,
            dropped,
            deskewed: scan.deskewed(),
            redeskewed: a.again,
            stamp_problem: scan.stamp_problem,
        }
    }
}

/// Step 2 (Sec. III-B): the merge cloud, already filtered as it streamed in, put in the
/// reference's order if [`Config::reference_order`]; its length.
fn order_merge<T: Real>(
    cfg: &Config<T>,
    scan: &mut Received,
    merge: &mut [[T; 3]],
    scratch: &mut [u64],
) -> usize {
    scan.dropped.merge_full = scan.merged.dropped as u32;
    let m = scan.merged.kept;
    if cfg.reference_order {
        reference_order(
            &mut merge[..m],
            cfg.voxel_size * cfg.alpha,
            scan.kept,
            scratch,
        );
    }
    m
}

/// Step 4's start for a scan's first registration against the map: the registration of the
/// thinned cloud (see [`Config::desired_source_points`]) from `from`, if the cloud was thinned
/// and that registration measured every direction; else `None` (start at `from`). Not with a
/// work budget, which bounds one registration.
fn coarse_start<T: Real, P: PointCodec<T>, E: Executor>(
    cfg: &Config<T>,
    exec: &E,
    parts: &mut Parts<'_, T>,
    merge: usize,
    map: &MapView<'_, T, P>,
    from: &Predicted<T>,
) -> Option<Registered<T>> {
    if cfg.work_budget.is_some() {
        return None;
    }
    let merge = &parts.merge[..merge];
    let thin = source_cloud(
        cfg,
        cfg.desired_source_points,
        merge,
        parts.source,
        parts.scratch,
    );
    if !thin.thinned {
        return None;
    }
    let step = Step::new(cfg, exec, &parts.source[..thin.kept.kept]);
    let reg = step.register(from, map, parts.icp);
    (reg.finite && measured_every_direction(cfg, &reg)).then_some(reg)
}

/// A registration cloud in the source buffer.
struct Sourced {
    kept: Downsampled,
    /// Made with voxels coarser than `beta v`.
    thinned: bool,
}

/// Step 2: the registration cloud, the `beta v` downsampling of `merge` in its order (then in
/// the reference's, if [`Config::reference_order`]), with coarser voxels if that keeps more
/// than `desired` points (0: never; see [`Config::desired_source_points`]).
fn source_cloud<T: Real>(
    cfg: &Config<T>,
    desired: usize,
    merge: &[[T; 3]],
    source: &mut [[T; 3]],
    scratch: &mut [u64],
) -> Sourced {
    let mut v = cfg.voxel_size * cfg.beta;
    let mut thin = |v| first_per_voxel(merge, v, source, scratch).unwrap_or_default();
    let mut kept = thin(v);
    let thinned = desired > 0 && kept.kept > desired;
    if thinned {
        v *= T::of(kept.kept as f64 / desired as f64);
        kept = thin(v);
    }
    if cfg.reference_order {
        reference_order(&mut source[..kept.kept], v, merge.len(), scratch);
    }
    Sourced { kept, thinned }
}

/// The parts of the storage a frame works in, and the map among them.
fn open<'w, T: Real, P: PointCodec<T>>(
    layout: &Layout,
    caps: &Capacities,
    storage: &'w mut impl Storage,
    map: &'w mut MapState<T>,
) -> Result<(Parts<'w, T>, MapMut<'w, T, P>), FrameError> {
    let parts = layout
        .split::<T>(caps, storage.as_mut())
        .map_err(|_| FrameError::Storage)?;
    let mut parts = parts;
    let words = core::mem::take(&mut parts.map);
    let map = MapMut::of(map, &layout.map, words).map_err(|_| FrameError::Storage)?;
    Ok((parts, map))
}

/// Whether a registration measured every direction: a frame registered against a map, with
/// an observability not below `degeneracy_ratio`.
fn measured_every_direction<T: Real>(cfg: &Config<T>, f: &Registered<T>) -> bool {
    !f.first_frame && f.observability.is_some_and(|o| o >= cfg.degeneracy_ratio)
}

/// Whether a registration left a direction unmeasured: no structured voxel near any sample (a
/// map of one huge voxel, say) measures nothing, which is no evidence of a constrained pose
/// either.
fn degenerate<T: Real>(cfg: &Config<T>, f: &Registered<T>) -> bool {
    !f.first_frame && f.observability.is_none_or(|o| o < cfg.degeneracy_ratio)
}

/// The frame's status flags.
fn status<T: Real>(
    cfg: &Config<T>,
    scan: &Received,
    dropped: &Dropped,
    f: &Registered<T>,
    update: &UpdateStats,
) -> Status {
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
    status.set(Flag::Degenerate, degenerate(cfg, f));
    status.set(Flag::Held, f.weak.held().directions() > 0);
    status.set(Flag::Planes, f.planes);
    status.set(Flag::InvalidPoints, dropped.non_finite > 0);
    status.set(Flag::ScanTruncated, dropped.truncated > 0);
    status.set(Flag::Capacity, dropped.capacity());
    status.set(Flag::Evicted, update.evicted);
    status
}
