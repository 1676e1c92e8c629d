//! Step 1, continued: per-point preprocessing (finite check, deskew, range crop).
//!
//! As in the reference, points are deskewed first and cropped on their deskewed range
//! `min_range < |p| < max_range`. Non-finite points never reach the crop; they are counted.

use crate::deskew::{Deskewer, StampProblem, SweepRotation, TimeSpan};
use crate::geometry::{Point, Pose};
use crate::scalar::Real;

/// Counts from preprocessing one scan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Preprocessed {
    /// Points kept (finite and within range).
    pub kept: usize,
    /// Points with a NaN or infinite coordinate.
    pub non_finite: usize,
    /// Finite points outside `(min_range, max_range)`.
    pub out_of_range: usize,
    /// Whether the scan was deskewed.
    pub deskewed: bool,
    /// Why timestamps were given but not used.
    pub stamp_problem: Option<StampProblem>,
}

/// Deskews and crops the points of one scan, one at a time.
pub struct Preprocessor<T: Real> {
    min_range: T,
    max_range: T,
    deskewer: Option<Deskewer<T>>,
    stamp_problem: Option<StampProblem>,
}

impl<T: Real> Preprocessor<T> {
    /// Prepares a scan of `n_points` points with optional per-point `stamps`; deskews only if
    /// `deskew` is set and the stamps are usable.
    pub fn new(
        min_range: T,
        max_range: T,
        deskew: bool,
        stamps: Option<&[f64]>,
        n_points: usize,
        relative_motion: &Pose<T>,
    ) -> Self {
        let span = Self::span(deskew, stamps, n_points);
        Self::with_span(min_range, max_range, span, relative_motion, None)
    }

    /// The span a scan's `stamps` give when it is to be deskewed.
    pub fn span(
        deskew: bool,
        stamps: Option<&[f64]>,
        n_points: usize,
    ) -> Option<Result<TimeSpan, StampProblem>> {
        stamps.filter(|_| deskew).map(|s| TimeSpan::of(s, n_points))
    }

    /// Prepares a scan whose timestamps, if any, were checked to span `span`, with the
    /// sensor's rotation through the sweep when it was measured (see [`Deskewer::turning`]).
    pub fn with_span(
        min_range: T,
        max_range: T,
        span: Option<Result<TimeSpan, StampProblem>>,
        relative_motion: &Pose<T>,
        rotation: Option<SweepRotation<T>>,
    ) -> Self {
        let (deskewer, stamp_problem) = match span {
            Some(Ok(span)) => (
                Some(Deskewer::turning(relative_motion, rotation, span)),
                None,
            ),
            Some(Err(e)) => (None, Some(e)),
            None => (None, None),
        };
        Self {
            min_range,
            max_range,
            deskewer,
            stamp_problem,
        }
    }

    /// Whether points will be deskewed.
    pub fn deskews(&self) -> bool {
        self.deskewer.is_some()
    }

    /// Why stamps were given but ignored, if they were.
    pub fn stamp_problem(&self) -> Option<StampProblem> {
        self.stamp_problem
    }

    /// The preprocessed point, or why it was dropped. A point is deskewed when the scan is and
    /// it has a finite `stamp`.
    #[inline]
    pub fn point(&mut self, raw: &[T; 3], stamp: Option<f64>) -> Result<Point<T>, Drop> {
        let p = Point::from(*raw);
        if !(raw[0].is_finite() && raw[1].is_finite() && raw[2].is_finite()) {
            return Err(Drop::NonFinite);
        }
        let p = match (self.deskewer.as_mut(), stamp) {
            (Some(d), Some(t)) if t.is_finite() => d.apply(&p, t),
            _ => p,
        };
        let range = p.coords.norm();
        if range < self.max_range && range > self.min_range {
            Ok(p)
        } else {
            Err(Drop::OutOfRange)
        }
    }
}

/// Why a point was dropped during preprocessing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drop {
    /// A NaN or infinite coordinate.
    NonFinite,
    /// Outside `(min_range, max_range)` after deskewing.
    OutOfRange,
}

/// Stage API: deskews (when `stamps` are given and usable) and crops `points` into `out`,
/// keeping their order, as the reference's `Preprocess` does. Points past `out.len()` kept
/// points are not written (the count still includes them).
#[allow(clippy::too_many_arguments)]
pub fn preprocess<T: Real>(
    points: &[[T; 3]],
    stamps: Option<&[f64]>,
    relative_motion: &Pose<T>,
    min_range: T,
    max_range: T,
    deskew: bool,
    out: &mut [[T; 3]],
) -> Preprocessed {
    Preprocessor::new(
        min_range,
        max_range,
        deskew,
        stamps,
        points.len(),
        relative_motion,
    )
    .run(points, stamps, out)
}

impl<T: Real> Preprocessor<T> {
    /// Preprocesses a whole scan into `out`, as [`preprocess`] describes.
    pub fn run(
        mut self,
        points: &[[T; 3]],
        stamps: Option<&[f64]>,
        out: &mut [[T; 3]],
    ) -> Preprocessed {
        let mut res = Preprocessed {
            deskewed: self.deskews(),
            stamp_problem: self.stamp_problem(),
            ..Preprocessed::default()
        };
        for (i, raw) in points.iter().enumerate() {
            let t = stamps.and_then(|s| s.get(i).copied());
            match self.point(raw, t) {
                Ok(p) => {
                    if let Some(o) = out.get_mut(res.kept) {
                        *o = [p.x, p.y, p.z];
                    }
                    res.kept += 1;
                }
                Err(Drop::NonFinite) => res.non_finite += 1,
                Err(Drop::OutOfRange) => res.out_of_range += 1,
            }
        }
        res
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crop_keeps_points_strictly_inside_the_range_shell() {
        let pts = [
            [0.5, 0.0, 0.0],  // inside min range
            [1.0, 0.0, 0.0],  // exactly min range: dropped (strict)
            [3.0, 4.0, 0.0],  // range 5: kept
            [0.0, 0.0, 10.0], // exactly max range: dropped (strict)
            [f64::NAN, 0.0, 0.0],
            [f64::INFINITY, 0.0, 0.0],
        ];
        let mut out = [[0.0; 3]; 6];
        let r = preprocess(&pts, None, &Pose::identity(), 1.0, 10.0, true, &mut out);
        assert_eq!((r.kept, r.non_finite, r.out_of_range), (1, 2, 3));
        assert_eq!(out[0], [3.0, 4.0, 0.0]);
        assert!(!r.deskewed);
    }

    #[test]
    fn unusable_stamps_disable_deskewing_and_say_why() {
        let pts = [[1.0, 2.0, 3.0], [2.0, 3.0, 4.0]];
        let mut out = [[0.0; 3]; 2];
        let motion = Pose::translation(1.0, 0.0, 0.0);
        for (stamps, why) in [
            (&[0.0, 0.0][..], StampProblem::Constant),
            (&[0.0, f64::NAN][..], StampProblem::NonFinite),
            (&[0.0][..], StampProblem::Length),
        ] {
            let r = preprocess(&pts, Some(stamps), &motion, 0.0, 100.0, true, &mut out);
            assert_eq!((r.deskewed, r.stamp_problem), (false, Some(why)));
            assert_eq!(&out, &pts);
        }
    }
}
