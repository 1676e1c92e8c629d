//! Step 4 (Sec. III-E, Eq. (9)-(12)) in the mode the configuration names: robust ICP of the
//! registration cloud against the local map from the prediction.
//!
//! - Reference mode ([`Degeneracy::Reference`]): the reference's point-to-point ICP, bit for bit.
//! - Robust mode ([`Degeneracy::Robust`]): a registration cloud of one plane held to the
//!   prediction (it measures nothing along the plane); else the reference's registration;
//!   where its observability is below `plane_gate` (or always, with a gate of 1 or more) a
//!   registration from the prediction with point-to-plane terms where the map is planar, and
//!   the motion prior.
//!
//! What the paper leaves out lives here too: the convergence floor of a finite scalar and the
//! fallback for a non-finite ICP result.

use crate::config::{Config, Degeneracy};
use crate::geometry::{Point, Pose};
use crate::local_map::{MapView, PointCodec};
use crate::observability::observability;
use crate::one_plane::one_plane;
use crate::registration::{
    align_points_to_map, moved_points, Alignment, Executor, IcpParams, MotionPrior,
};
use crate::scalar::Real;

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
    /// Held to the prediction, unregistered: robust mode's registration cloud was one plane
    /// (see `one_plane`).
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
        let always = robust && !first_frame && cfg.robust.plane_gate >= T::one();
        let first = self.once(at, map, work, always);
        let degenerate = first
            .observability
            .is_none_or(|o| o < cfg.robust.plane_gate);
        if robust && !first.planes && !first_frame && degenerate {
            self.once(at, map, work, true)
        } else {
            first
        }
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
    ) -> Registered<T> {
        let cfg = self.cfg;
        let (kernel, prior) = if planes {
            let r = &cfg.robust;
            let prior = (at.frames >= 2).then(|| {
                MotionPrior::new(&at.last_pose, &at.pose, r.prediction_prior, r.lateral_prior)
            });
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
        held: true,
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
}
