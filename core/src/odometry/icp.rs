//! Step 4 (Sec. III-E, Eq. (9)-(12)) in the mode the configuration names: robust ICP of the
//! registration cloud against the local map from the prediction.
//!
//! - Reference mode ([`Degeneracy::Reference`]): the reference's point-to-point ICP, bit for bit.
//! - Robust mode ([`Degeneracy::Robust`]): a registration cloud of one plane held to the
//!   prediction (it measures nothing along the plane); else the reference's registration;
//!   where its observability is below `plane_gate` (or always, with a gate of 1 or more) a
//!   registration from the prediction with point-to-plane terms where the map is planar, and
//!   the motion prior (with a `prior_gate` below 1, only where the scene's measurement at the
//!   prediction, `weakness`, finds a translation nearly free).
//!
//! What the paper leaves out lives here too: the convergence floor of a finite scalar and the
//! fallback for a non-finite ICP result.

use crate::config::{Config, Degeneracy, Robust};
use crate::geometry::{Point, Pose};
use crate::local_map::{MapView, PointCodec};
use crate::observability::observability;
use crate::registration::{
    align_points_to_map, moved_points, Alignment, Executor, IcpParams, MotionPrior,
};
use crate::scalar::Real;
use crate::weakness::{min_points, one_plane, weakness, Weakness};

/// What step 4 works with, besides the prediction, the map and ICP's work chunks.
pub(super) struct Step<'a, T: Real, E: Executor> {
    cfg: &'a Config<T>,
    exec: &'a E,
    /// `P^*`, the registration cloud (sensor frame).
    source: &'a [[T; 3]],
}

/// The prediction and what step 4 needs to know of the past.
pub(super) struct Predicted<T: Real> {
    /// The constant-velocity prediction, Eq. (1).
    pub(super) pose: Pose<T>,
    /// The last pose (the motion prior's reference).
    pub(super) last_pose: Pose<T>,
    /// `sigma_t`, Eq. (7).
    pub(super) sigma: T,
    /// Frames registered so far.
    pub(super) frames: u64,
}

/// One registration and what it left.
pub(super) struct Registered<T: Real> {
    /// `sigma_t` it was registered with.
    pub(super) sigma: T,
    /// Whether the map was empty (the first frame: the pose is the identity).
    pub(super) first_frame: bool,
    pub(super) icp: Alignment<T>,
    pub(super) pose: Pose<T>,
    /// Whether ICP's pose was finite (otherwise `pose` is the prediction).
    pub(super) finite: bool,
    /// The observability at the pose; `None` on the first frame or with nothing measured.
    pub(super) observability: Option<T>,
    /// Registered with robust mode's plane terms.
    pub(super) planes: bool,
    /// The scene's weakness at the prediction, where the motion prior's gate measured it.
    pub(super) weak: Weakness<T>,
    /// Held to the prediction, unregistered: robust mode's registration cloud was one plane
    /// (see `weakness::one_plane`).
    pub(super) held: bool,
}

impl<'a, T: Real, E: Executor> Step<'a, T, E> {
    /// Step 4 with `cfg`'s mode for `source`, run by `exec`.
    pub(super) fn new(cfg: &'a Config<T>, exec: &'a E, source: &'a [[T; 3]]) -> Self {
        Self { cfg, exec, source }
    }

    /// Step 4 in the configured mode from `at` against `map`, in the chunks `work`.
    pub(super) fn register<P: PointCodec<T>>(
        &self,
        at: &Predicted<T>,
        map: &MapView<'_, T, P>,
        work: &mut [u64],
    ) -> Registered<T> {
        let cfg = self.cfg;
        let first_frame = map.is_empty();
        let robust = cfg.degeneracy == Degeneracy::Robust;
        if robust && !first_frame && one_plane(self.source, cfg.voxel_size) {
            return held(at);
        }
        // Where robust mode's motion prior is gated on the scene, the scene is measured once
        // there is a prediction: the second frame's is standing still, whatever the sensor
        // does.
        let weak = if robust && !first_frame && at.frames >= 2 && gated(&cfg.robust) {
            self.weakness(at, map)
        } else {
            Weakness::NONE
        };
        let always = robust && !first_frame && cfg.robust.plane_gate >= T::one();
        let first = self.once(at, map, work, always, &weak);
        let degenerate = first
            .observability
            .is_none_or(|o| o < cfg.robust.plane_gate);
        if robust && !first.planes && !first_frame && degenerate {
            self.once(at, map, work, true, &weak)
        } else {
            first
        }
    }

    /// The scene's measurement at the prediction (see `weakness`).
    fn weakness<P: PointCodec<T>>(
        &self,
        at: &Predicted<T>,
        map: &MapView<'_, T, P>,
    ) -> Weakness<T> {
        let min = min_points(self.cfg.alpha);
        weakness(map, self.source, &at.pose, self.max_distance(at), min)
    }

    /// Correspondences farther than `max_correspondence_factor sigma` are rejected (Eq. (7)).
    fn max_distance(&self, at: &Predicted<T>) -> T {
        self.cfg.max_correspondence_factor * at.sigma
    }

    /// One registration from the prediction, with plane terms (and robust mode's motion prior,
    /// once there is a velocity) if `planes`.
    fn once<P: PointCodec<T>>(
        &self,
        at: &Predicted<T>,
        map: &MapView<'_, T, P>,
        work: &mut [u64],
        planes: bool,
        weak: &Weakness<T>,
    ) -> Registered<T> {
        let cfg = self.cfg;
        let (kernel, prior) = if planes {
            let weights = prior_weights(&cfg.robust, weak).filter(|_| at.frames >= 2);
            let prior = weights
                .map(|(hold, sideways)| MotionPrior::new(&at.last_pose, &at.pose, hold, sideways));
            (cfg.robust.kernel_scale, prior)
        } else {
            (cfg.kernel_scale, None)
        };
        let max_distance = self.max_distance(at);
        let icp = align_points_to_map(
            self.exec,
            self.source,
            &mut *work,
            map,
            &at.pose,
            max_distance,
            kernel * at.sigma,
            &icp_params(cfg, &at.pose, planes, prior),
        );
        let (pose, finite) = finite_or(icp.pose, at.pose);
        let first_frame = map.is_empty();
        let observability = if first_frame {
            None
        } else {
            let n = self.source.len();
            let moved = moved_points::<T>(work, n, planes);
            let origin = Point::from(pose.translation.vector);
            observability(map, moved, n, &origin, max_distance)
        };
        Registered {
            sigma: at.sigma,
            first_frame,
            icp,
            pose,
            finite,
            observability,
            planes,
            weak: *weak,
            held: false,
        }
    }
}

/// A frame held to its prediction: nothing registered, nothing measured.
fn held<T: Real>(at: &Predicted<T>) -> Registered<T> {
    Registered {
        sigma: at.sigma,
        first_frame: false,
        icp: Alignment::at(at.pose),
        pose: at.pose,
        finite: true,
        observability: None,
        planes: false,
        weak: Weakness::NONE,
        held: true,
    }
}

/// Whether robust mode's motion prior waits for a measurement of the scene: it has a term to
/// add, and a gate below 1.
fn gated<T: Real>(r: &Robust<T>) -> bool {
    let any = r.prediction_prior > T::zero() || r.lateral_prior > T::zero();
    any && r.prior_gate < T::one()
}

/// The motion prior's hold and lateral weights in a frame with `weak`'s measurement, `None`
/// where it does not act. With a gate of 1 or more, both, always. Else only where the weakest
/// translation was measured below the gate: the lateral prior there, and the hold prior only
/// where no other translation is below it (a corridor's axis). Along an open plane's two weak
/// translations, sparse structure still measures what a hold would overrule.
fn prior_weights<T: Real>(r: &Robust<T>, weak: &Weakness<T>) -> Option<(T, T)> {
    if r.prior_gate >= T::one() {
        return Some((r.prediction_prior, r.lateral_prior));
    }
    weak.ratio.filter(|[t, _]| *t < r.prior_gate)?;
    let corridor = weak.middle.is_some_and(|m| m >= r.prior_gate);
    let hold = if corridor {
        r.prediction_prior
    } else {
        T::zero()
    };
    Some((hold, r.lateral_prior))
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
    planes: bool,
    prior: Option<MotionPrior<T>>,
) -> IcpParams<T> {
    let reach = prediction.translation.vector.norm() + cfg.max_range;
    IcpParams {
        convergence_criterion: cfg.convergence_criterion.max(T::of(8.0) * T::EPS * reach),
        max_iterations: cfg.max_iterations,
        budget: cfg.work_budget,
        planes,
        prior,
        stop_on_cycle: planes && cfg.robust.cycle_stop,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_registration_with_plane_terms_under_cycle_stop_stops_on_a_loop() {
        let at = Pose::<f64>::identity();
        let stops = |cfg: &Config<f64>, planes| icp_params(cfg, &at, planes, None).stop_on_cycle;
        let (accurate, robust) = (Config::accurate(100.0), Config::robust(100.0));
        assert!(stops(&accurate, true));
        assert!(
            !stops(&accurate, false),
            "the preset's registrations without planes"
        );
        assert!(
            !stops(&robust, true),
            "robust mode keeps the reference's stopping rule"
        );
        assert!(!stops(&Config::new(100.0), false));
    }

    /// A measurement with the weakest and middle translation ratios `t` and `middle`.
    fn measured(t: f64, middle: f64) -> Weakness<f64> {
        Weakness {
            ratio: Some([t, 0.5]),
            middle: Some(middle),
        }
    }

    #[test]
    fn the_gated_prior_acts_where_a_translation_is_free_and_holds_a_corridors_lone_axis() {
        let preset = Config::<f64>::accurate(100.0).robust;
        let (hold, lateral) = (preset.prediction_prior, preset.lateral_prior);
        assert!(hold > 0.0 && lateral > 0.0 && gated(&preset));
        let weights = |w: &Weakness<f64>| prior_weights(&preset, w);
        assert_eq!(
            weights(&measured(0.01, 0.6)),
            Some((hold, lateral)),
            "a corridor"
        );
        assert_eq!(
            weights(&measured(0.01, 0.02)),
            Some((0.0, lateral)),
            "open ground"
        );
        assert_eq!(weights(&measured(0.3, 0.6)), None, "a street");
        assert_eq!(
            weights(&measured(preset.prior_gate, 0.6)),
            None,
            "the gate itself"
        );
        assert_eq!(weights(&Weakness::NONE), None, "nothing measured");
        // The tunnel setting's gate of 1 needs no measurement: both terms, always.
        let tunnel = Robust::<f64>::tunnel();
        assert!(!gated(&tunnel));
        let both = Some((tunnel.prediction_prior, tunnel.lateral_prior));
        assert_eq!(prior_weights(&tunnel, &Weakness::NONE), both);
        // Without a term to add there is nothing to gate.
        let none = Robust {
            prediction_prior: 0.0,
            lateral_prior: 0.0,
            ..preset
        };
        assert!(!gated(&none));
    }
}
