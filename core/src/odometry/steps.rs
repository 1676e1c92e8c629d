//! The paper's steps for one scan (Sec. III), each a method [`Odometry::register_frame_with`]
//! calls in order: step 1 as the points arrive (`input`), then steps 2-4 ([`Odometry::register`])
//! and the map update with the threshold's sample ([`Odometry::update`]). Step 4 in the
//! configured mode is `icp`; what the accurate preset adds is `strategy`; what the paper leaves
//! out (the frame report, capacity checks) lives in the helpers below.

use super::icp::{Predicted, Registered, Step};
use super::layout::{Layout, Parts};
use super::rehome::{nothing, shortfall};
use super::strategy::{coarse_start, deskew_again, source_cloud};
use super::Odometry;
use crate::config::{Capacities, Config};
use crate::deskew::StampProblem;
use crate::downsample::{reference_order, Downsampled};
use crate::error::FrameError;
use crate::geometry::Pose;
use crate::local_map::{MapMut, MapState, PointCodec, UpdateStats};
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

/// A scan registered (steps 2-4), before anything of it is kept.
pub(super) struct Registration<T: Real> {
    scan: Received,
    clouds: Clouds,
    reg: Registered<T>,
    /// The prediction the threshold measures the registration against.
    predicted: Pose<T>,
    /// Registered a second time, from a first registration of the same sweep.
    again: bool,
}

impl<T: Real> Registration<T> {
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
    /// Steps 2-4 (Sec. III-B to III-E) for a received scan: `P*_merge` and `P^*`, then robust
    /// ICP against the local map gated by `tau_t = 3 sigma_t`, from `start` if given (a first
    /// registration of the same sweep), else from the prediction. Nothing is kept yet (see
    /// [`Self::update`]) but the clouds in their buffers.
    pub(super) fn register<E: Executor>(
        &mut self,
        exec: &E,
        mut scan: Received,
        start: Option<Pose<T>>,
    ) -> Result<Registration<T>, FrameError> {
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
        let cfg = self.config;
        // Step 1's prediction, Eq. (1) (the scan was deskewed with it as it arrived), and
        // step 4's `sigma_t` (Eq. (7)).
        let predicted = self.predict();
        let desired = self.strategy.desired_points(&cfg);
        let b = &mut self.buffers;
        let (mut parts, map) = open::<T, P>(&b.layout, &b.caps, &mut b.storage, &mut self.map)?;

        // Step 2 (Sec. III-B): P*_merge (in the reference's order, if configured), then P^*.
        let m = order_merge(&cfg, &mut scan, parts.merge, parts.scratch);
        let from = Predicted {
            pose: start.unwrap_or(predicted.pose),
            ..predicted
        };
        let coarse = match start {
            None => coarse_start(&cfg, exec, &mut parts, m, &map.view(), &from),
            Some(_) => None,
        };
        let merge = &parts.merge[..m];
        let sourced = source_cloud(&cfg, desired, merge, parts.source, parts.scratch);
        scan.dropped.source_full = sourced.kept.dropped as u32;
        if sourced.kept.dropped > 0 {
            let need = Capacities {
                source_points: m,
                ..nothing()
            };
            if let Some(needed) = shortfall(&b.caps, b.when_full, &need) {
                b.needed = needed;
                return Err(FrameError::Full);
            }
        }
        let clouds = Clouds {
            merge: m,
            source: sourced.kept.kept,
        };
        let source = &parts.source[..clouds.source];

        // Steps 3-4 (Sec. III-C to III-E, Eq. (9)-(12)): robust ICP of P^* against the map.
        let from = Predicted {
            pose: coarse.as_ref().map_or(from.pose, |c| c.pose),
            ..from
        };
        let mut reg = Step::new(&cfg, exec, source).register(&from, &map.view(), parts.icp);
        if let Some(c) = coarse {
            reg.icp.iterations += c.icp.iterations;
            reg.icp.work += c.icp.work;
        }
        Ok(Registration {
            scan,
            clouds,
            reg,
            predicted: predicted.pose,
            again: start.is_some(),
        })
    }

    /// The motion to deskew a registered sweep with again, if the preset's strategy asks for
    /// it (`strategy::deskew_again`).
    pub(super) fn deskew_again(&self, r: &Registration<T>) -> Option<Pose<T>> {
        let constant_rate = r.scan.deskewed() && self.sweep.rotation.is_none();
        let error = self.threshold.in_use().model_error(&r.deviation());
        deskew_again(
            &self.config,
            constant_rate,
            &r.reg,
            error,
            &self.motion.pose,
        )
    }

    /// Sec. III-C and III-D for a registered scan: its model deviation (Eq. (13)) joins the
    /// adaptive threshold, `P*_merge` joins the local map at `T_t` (voxels beyond `r_max` are
    /// pruned; a full map gives up its farthest voxels first), and `T_t` becomes the pose.
    pub(super) fn update(&mut self, r: Registration<T>) -> Result<FrameReport<T>, FrameError> {
        self.room_for(self.map_room(r.clouds.merge))?;
        let deviation = r.deviation();
        let model_error = self.threshold.in_use().model_error(&deviation);
        self.threshold.update(&deviation);

        let b = &mut self.buffers;
        let (parts, mut map) = open::<T, P>(&b.layout, &b.caps, &mut b.storage, &mut self.map)?;
        let merge = &parts.merge[..r.clouds.merge];
        let update = map.update(merge, &r.reg.pose, parts.scratch);

        self.sweep.registered();
        self.motion.advance_to(r.reg.pose);
        self.strategy.registered(&self.config, &r.reg);
        self.note(&r.clouds);
        let report = self.report(&r, model_error, &update);
        self.motion.frames += 1;
        Ok(report)
    }

    /// Eq. (1): the constant-velocity prediction `T_{t-1} dT_{t-1}`, with what step 4 needs to
    /// know of the past: the threshold's `sigma_t` and the frames so far.
    fn predict(&self) -> Predicted<T> {
        Predicted {
            pose: self.motion.prediction(),
            last_pose: self.motion.pose,
            sigma: self.threshold.in_use().sigma(),
            frames: self.motion.frames,
        }
    }

    /// The clouds' sizes and every buffer's high-water mark.
    fn note(&mut self, clouds: &Clouds) {
        let b = &mut self.buffers;
        b.merge_len = clouds.merge;
        b.source_len = clouds.source;
        let h = &mut b.high;
        h.merge_points = h.merge_points.max(clouds.merge);
        h.source_points = h.source_points.max(clouds.source);
        h.map_voxels = self.map.high_water_voxels();
        h.map_point_slots = self.map.high_water_point_slots();
    }

    /// The frame's report: the pose, what happened and what was dropped.
    fn report(&self, a: &Registration<T>, model_error: T, update: &UpdateStats) -> FrameReport<T> {
        let (scan, clouds, f) = (&a.scan, &a.clouds, &a.reg);
        let mut dropped = scan.dropped;
        dropped.map_voxels_full = update.dropped_voxels as u32;
        dropped.map_points_full = update.dropped_points as u32;
        FrameReport {
            index: self.motion.frames,
            pose: self.motion.pose,
            status: status(&self.config, scan, &dropped, f, update),
            iterations: f.icp.iterations,
            work: f.icp.work,
            correspondences: f.icp.correspondences,
            plane_correspondences: f.icp.plane_correspondences,
            sigma: f.sigma,
            rms: f.icp.rms,
            model_error,
            observability: f.observability,
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
        !f.first_frame && !f.held && f.icp.correspondences == 0,
    );
    status.set(
        Flag::Singular,
        !f.first_frame && (f.icp.singular || !f.finite),
    );
    status.set(Flag::Degenerate, degenerate(cfg, f));
    status.set(Flag::Planes, f.planes);
    status.set(Flag::OnePlane, f.held);
    status.set(Flag::InvalidPoints, dropped.non_finite > 0);
    status.set(Flag::ScanTruncated, dropped.truncated > 0);
    status.set(Flag::Capacity, dropped.capacity());
    status.set(Flag::Evicted, update.evicted);
    status
}
