//! One scan through the pipeline: points stream in (steps 1-2, first pass), then `finish`
//! runs the rest (second downsampling pass, registration, map update).

use super::Odometry;
use crate::degeneracy::observability;
use crate::deskew::{StampProblem, TimeSpan};
use crate::downsample::{reference_order, Dedup, Downsampled};
use crate::error::FrameError;
use crate::lie::renormalize;
use crate::local_map::PointCodec;
use crate::preprocess::{Drop, Preprocessor};
use crate::registration::{align_points_to_map, Executor, IcpParams, Sequential};
use crate::report::{Dropped, FrameReport, Status};
use crate::scalar::Real;
use crate::Point;

/// A scan being received: see [`Odometry::begin_frame`].
pub struct FrameInput<'o, 'a, T: Real, P: PointCodec<T>> {
    odom: &'o mut Odometry<'a, T, P>,
    pre: Preprocessor<T>,
    merged: Downsampled,
    kept: usize,
    input: usize,
    out_of_range: u32,
    dropped: Dropped,
    stamp_problem: Option<StampProblem>,
}

impl<'a, T: Real, P: PointCodec<T>> Odometry<'a, T, P> {
    pub(super) fn begin(
        &mut self,
        span: Option<Result<TimeSpan, StampProblem>>,
    ) -> FrameInput<'_, 'a, T, P> {
        let cfg = &self.config;
        let pre = Preprocessor::with_span(cfg.min_range, cfg.max_range, span, &self.last_delta);
        // Clears the first pass's grid; the layout sized scratch for the merge capacity.
        let merged = Dedup::new(self.merge, self.scratch, cfg.voxel_size * cfg.alpha)
            .map(Dedup::finish)
            .unwrap_or_default();
        FrameInput {
            stamp_problem: pre.stamp_problem(),
            odom: self,
            pre,
            merged,
            kept: 0,
            input: 0,
            out_of_range: 0,
            dropped: Dropped::default(),
        }
    }
}

impl<T: Real, P: PointCodec<T>> FrameInput<'_, '_, T, P> {
    /// Adds points of the scan (sensor frame) with their capture times, if any (one per
    /// point). Points past `Capacities::scan_points` are counted and ignored. Times of the
    /// wrong length, or single times that are not finite, leave those points undeskewed and
    /// the report says so.
    pub fn push(&mut self, points: &[[T; 3]], stamps: Option<&[f64]>) {
        let room = self.odom.caps.scan_points.saturating_sub(self.input);
        let used = points.len().min(room);
        self.dropped.truncated += (points.len() - used) as u32;
        self.input += used;
        let deskews = self.pre.deskews();
        let stamps = match stamps {
            Some(s) if s.len() == points.len() => Some(s),
            Some(_) if deskews => {
                self.stamp_problem.get_or_insert(StampProblem::Length);
                None
            }
            _ => None,
        };
        let odom = &mut *self.odom;
        let alpha_v = odom.config.voxel_size * odom.config.alpha;
        let Some(mut dedup) = Dedup::resume(odom.merge, odom.scratch, alpha_v, self.merged) else {
            return;
        };
        for (i, raw) in points[..used].iter().enumerate() {
            let t = stamps.map(|s| s[i]);
            if deskews && t.is_some_and(|t| !t.is_finite()) {
                self.stamp_problem.get_or_insert(StampProblem::NonFinite);
            }
            match self.pre.point(raw, t) {
                Ok(p) => {
                    self.kept += 1;
                    dedup.push(&p);
                }
                Err(Drop::NonFinite) => self.dropped.non_finite += 1,
                Err(Drop::OutOfRange) => self.out_of_range += 1,
            }
        }
        self.merged = dedup.finish();
    }

    /// Registers the scan on the calling thread.
    pub fn finish(self) -> Result<FrameReport<T>, FrameError> {
        self.finish_with(&Sequential)
    }

    /// Registers the scan, running the correspondence search on `exec`. Returns
    /// [`FrameError::EmptyScan`], with the odometry untouched, when no point was usable.
    pub fn finish_with<E: Executor>(self, exec: &E) -> Result<FrameReport<T>, FrameError> {
        let Self {
            odom,
            pre,
            merged,
            kept,
            input,
            out_of_range,
            mut dropped,
            stamp_problem,
        } = self;
        let cfg = odom.config;
        if kept == 0 {
            odom.merge_len = 0;
            return Err(FrameError::EmptyScan);
        }
        // Step 2: both passes in the reference's order (see `downsample`).
        let alpha_v = cfg.voxel_size * cfg.alpha;
        let beta_v = cfg.voxel_size * cfg.beta;
        dropped.merge_full = merged.dropped as u32;
        let m = merged.kept;
        reference_order(&mut odom.merge[..m], alpha_v, kept, odom.scratch);
        let sourced = match Dedup::new(odom.source, odom.scratch, beta_v) {
            Some(mut dedup) => {
                for p in odom.merge[..m].iter() {
                    dedup.push(&Point::from(*p));
                }
                dedup.finish()
            }
            None => Downsampled::default(),
        };
        dropped.source_full = sourced.dropped as u32;
        let s = sourced.kept;
        reference_order(&mut odom.source[..s], beta_v, m, odom.scratch);
        odom.merge_len = m;

        // Steps 3 and 4: register against the map with the adaptive threshold.
        let sigma = odom.threshold.sigma();
        let max_distance = cfg.max_correspondence_factor * sigma;
        let initial_guess = odom.last_pose * odom.last_delta;
        // gamma, but never below what the scalar can resolve where the points are: map points
        // sit up to |t| + r_max from the origin, and their rounding (8 ulp of that) puts a floor
        // under the correction ICP can reach. In f64 the floor is below 1e-10 m within 10 km,
        // far under gamma = 1e-4, so results are the reference's; in f32 it passes gamma once
        // |t| + r_max exceeds about 105 m, and without it ICP ran to the iteration cap on most
        // frames beyond 600 m from the start (tests/tests/long_run.rs).
        let reach = initial_guess.translation.vector.norm() + cfg.max_range;
        let params = IcpParams {
            convergence_criterion: cfg.convergence_criterion.max(T::of(8.0) * T::EPS * reach),
            max_iterations: cfg.max_iterations,
        };
        let first_frame = odom.map.is_empty();
        let al = align_points_to_map(
            exec,
            &mut odom.source[..s],
            odom.systems,
            &odom.map,
            &initial_guess,
            max_distance,
            cfg.kernel_scale * sigma,
            &params,
        );
        let finite = al.pose.translation.vector.iter().all(|v| v.is_finite())
            && al.pose.rotation.coords.iter().all(|v| v.is_finite());
        let new_pose = if finite { al.pose } else { initial_guess };
        let observability = if first_frame {
            None
        } else {
            observability(
                &odom.map,
                &odom.source[..s],
                &Point::from(new_pose.translation.vector),
                max_distance,
            )
        };

        // Update: threshold, map, velocity and pose.
        let deviation = initial_guess.inverse() * new_pose;
        let model_error = odom.threshold.model_error(&deviation);
        odom.threshold.update(&deviation);
        let st = odom.map.update(&odom.merge[..m], &new_pose);
        dropped.map_voxels_full = st.dropped_voxels as u32;
        dropped.map_points_full = st.dropped_points as u32;
        odom.last_delta = odom.last_pose.inverse() * new_pose;
        odom.last_pose = new_pose;
        renormalize(&mut odom.last_pose);

        odom.high.merge_points = odom.high.merge_points.max(m);
        odom.high.source_points = odom.high.source_points.max(s);
        odom.high.map_voxels = odom.map.high_water_voxels();
        odom.high.map_point_slots = odom.map.high_water_point_slots();

        let mut status = Status::default();
        status.set(Status::TIMESTAMPS_IGNORED, stamp_problem.is_some());
        status.set(Status::ITERATION_CAP, !al.converged && !al.singular);
        status.set(
            Status::NO_CORRESPONDENCES,
            !first_frame && al.correspondences == 0,
        );
        status.set(Status::SINGULAR, !first_frame && (al.singular || !finite));
        status.set(
            Status::DEGENERATE,
            observability.is_some_and(|o| o < cfg.degeneracy_ratio),
        );
        status.set(Status::INVALID_POINTS, dropped.non_finite > 0);
        status.set(Status::SCAN_TRUNCATED, dropped.truncated > 0);
        status.set(Status::CAPACITY, dropped.capacity());

        let report = FrameReport {
            index: odom.frames,
            pose: odom.last_pose,
            status,
            iterations: al.iterations,
            correspondences: al.correspondences,
            sigma,
            rms: al.rms,
            model_error,
            observability,
            input_points: (input + dropped.truncated as usize) as u32,
            out_of_range,
            merge_points: m as u32,
            source_points: s as u32,
            map_voxels: odom.map.voxels() as u32,
            map_points: odom.map.points() as u32,
            pruned_voxels: st.pruned_voxels as u32,
            dropped,
            deskewed: pre.deskews() && stamp_problem.is_none(),
            stamp_problem,
        };
        odom.frames += 1;
        Ok(report)
    }
}
