//! A scan arriving: step 1 (deskew and crop, Sec. III-A) and the first pass of step 2 (the
//! `alpha v` downsampling, Sec. III-B) run point by point as the scan streams in, so a sweep
//! never needs a buffer of its own. [`FrameInput::finish`] hands the result to the rest of the
//! frame (`steps`).

use super::steps::Received;
use super::Odometry;
use crate::deskew::{StampProblem, TimeSpan};
use crate::downsample::Dedup;
use crate::error::FrameError;
use crate::geometry::Pose;
use crate::local_map::PointCodec;
use crate::preprocess::{Drop, Preprocessor};
use crate::registration::{Executor, Sequential};
use crate::report::FrameReport;
use crate::scalar::Real;
use crate::storage::Storage;

/// A scan being received: see [`Odometry::begin_frame`].
pub struct FrameInput<'o, T: Real, P: PointCodec<T>, S: Storage> {
    odom: &'o mut Odometry<T, P, S>,
    pre: Preprocessor<T>,
    scan: Received,
}

impl<T: Real, P: PointCodec<T>, S: Storage> Odometry<T, P, S> {
    /// Step 1 (Sec. III-A, Eq. (2)-(4)) for a whole scan with optional per-point `stamps`,
    /// deskewed with `motion` (the sweep's, end to end), and the first pass of step 2 as its
    /// points arrive.
    pub(super) fn deskew(
        &mut self,
        points: &[[T; 3]],
        stamps: Option<&[f64]>,
        motion: Pose<T>,
    ) -> Received {
        let span = Preprocessor::<T>::span(self.config.deskew, stamps, points.len());
        let mut frame = self.begin(span, motion);
        frame.push(points, stamps.filter(|s| s.len() == points.len()));
        frame.scan
    }

    /// A scan arriving in pieces, whose capture times span `span`.
    pub(super) fn begin_span(&mut self, span: Option<(f64, f64)>) -> FrameInput<'_, T, P, S> {
        let span = span
            .filter(|_| self.config.deskew)
            .map(|(min, max)| TimeSpan::new(min, max));
        self.begin(span, self.motion.delta)
    }

    fn begin(
        &mut self,
        span: Option<Result<TimeSpan, StampProblem>>,
        motion: Pose<T>,
    ) -> FrameInput<'_, T, P, S> {
        self.sweep.motion = motion;
        let cfg = &self.config;
        let (lo, hi) = (cfg.min_range, cfg.max_range);
        let pre = Preprocessor::with_span(lo, hi, span, &motion, self.sweep.rotation);
        let mut scan = Received {
            stamp_problem: pre.stamp_problem(),
            deskews: pre.deskews(),
            ..Received::default()
        };
        // Clears the first pass's grid (scratch only: the last merge cloud stays readable until
        // a point of this scan replaces it).
        let b = &mut self.buffers;
        match b.layout.split::<T>(&b.caps, b.storage.as_mut()) {
            Ok(parts) => {
                let alpha_v = cfg.voxel_size * cfg.alpha;
                scan.merged = Dedup::new(parts.merge, parts.scratch, alpha_v)
                    .map(Dedup::finish)
                    .unwrap_or_default();
            }
            Err(_) => scan.storage_lost = true,
        }
        FrameInput {
            odom: self,
            pre,
            scan,
        }
    }
}

impl<T: Real, P: PointCodec<T>, S: Storage> FrameInput<'_, T, P, S> {
    /// Adds points of the scan (sensor frame) with their capture times, if any (one per
    /// point). Points past `Capacities::scan_points` are counted and ignored. Times of the
    /// wrong length, or single times that are not finite, leave those points undeskewed and
    /// the report says so.
    pub fn push(&mut self, points: &[[T; 3]], stamps: Option<&[f64]>) {
        let scan = &mut self.scan;
        let room = self
            .odom
            .buffers
            .caps
            .scan_points
            .saturating_sub(scan.input);
        let used = points.len().min(room);
        scan.dropped.truncated += (points.len() - used) as u32;
        scan.input += used;
        let deskews = self.pre.deskews();
        let stamps = match stamps {
            Some(s) if s.len() == points.len() => Some(s),
            Some(_) if deskews => {
                scan.stamp_problem.get_or_insert(StampProblem::Length);
                None
            }
            _ => None,
        };
        let odom = &mut *self.odom;
        let b = &mut odom.buffers;
        let Ok(parts) = b.layout.split::<T>(&b.caps, b.storage.as_mut()) else {
            scan.storage_lost = true;
            return;
        };
        let alpha_v = odom.config.voxel_size * odom.config.alpha;
        let Some(mut dedup) = Dedup::resume(parts.merge, parts.scratch, alpha_v, scan.merged)
        else {
            return;
        };
        for (i, raw) in points[..used].iter().enumerate() {
            let t = stamps.map(|s| s[i]);
            if deskews && t.is_some_and(|t| !t.is_finite()) {
                scan.stamp_problem.get_or_insert(StampProblem::NonFinite);
            }
            match self.pre.point(raw, t) {
                Ok(p) => {
                    scan.kept += 1;
                    dedup.push(&p);
                }
                Err(Drop::NonFinite) => scan.dropped.non_finite += 1,
                Err(Drop::OutOfRange) => scan.out_of_range += 1,
            }
        }
        scan.merged = dedup.finish();
        if scan.kept > 0 {
            // The merge buffer now holds this scan's points, not the last scan's cloud.
            b.merge_len = 0;
        }
    }

    /// Registers the scan on the calling thread.
    pub fn finish(self) -> Result<FrameReport<T>, FrameError> {
        self.finish_with(&Sequential)
    }

    /// Registers the scan, running the correspondence search on `exec`. Returns
    /// [`FrameError::EmptyScan`], with the odometry untouched, when no point was usable.
    pub fn finish_with<E: Executor>(self, exec: &E) -> Result<FrameReport<T>, FrameError> {
        let r = self.odom.register(exec, self.scan, None)?;
        self.odom.update(r)
    }
}
