//! The accurate preset's registration strategy: what it adds to the paper's steps, in one
//! place, so the frame itself reads as the paper.
//!
//! With the reference's configuration every rule here is off and a frame runs the paper's
//! steps alone. Each rule is a setting of [`Config`] that the preset turns on:
//! - the thinned registration cloud ([`Config::desired_source_points`]): `P^*` made with
//!   coarser voxels when it holds more points, once a registration has measured every
//!   direction; the first registration against the map starts from the thinned cloud's pose;
//! - the second deskew ([`Config::redeskew`]): a sweep deskewed again with the motion its first
//!   registration found, and registered again.
//!
//! Robust mode's plane terms, cycle stop and motion prior change step 4 itself (`icp`).

use super::icp::{Predicted, Registered, Step};
use super::layout::Parts;
use crate::config::Config;
use crate::downsample::{first_per_voxel, reference_order, Downsampled};
use crate::geometry::Pose;
use crate::local_map::{MapView, PointCodec};
use crate::registration::Executor;
use crate::scalar::Real;

/// What the strategy keeps from frame to frame.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Strategy {
    /// The last registration measured every direction (see [`measured_every_direction`]).
    pub(super) constrained: bool,
}

impl Strategy {
    /// Points the registration cloud is thinned to: until a registration has measured every
    /// direction, none (every `beta v` voxel: a weakly constrained scene's sparse structure is
    /// what measures its weak directions).
    pub(super) fn desired_points<T: Real>(&self, cfg: &Config<T>) -> usize {
        if self.constrained {
            cfg.desired_source_points
        } else {
            0
        }
    }

    /// Notes what a registration the frame kept measured.
    pub(super) fn registered<T: Real>(&mut self, cfg: &Config<T>, reg: &Registered<T>) {
        self.constrained = measured_every_direction(cfg, reg);
    }
}

/// Step 4's start for a scan's first registration against the map: the registration of the
/// thinned cloud (see [`Config::desired_source_points`]) from `from`, if the cloud was thinned
/// and that registration measured every direction; else `None` (start at `from`). Not with a
/// work budget, which bounds one registration.
pub(super) fn coarse_start<T: Real, P: PointCodec<T>, E: Executor>(
    cfg: &Config<T>,
    exec: &E,
    parts: &mut Parts<'_, T>,
    merge: usize,
    map: &MapView<'_, T, P>,
    from: &Predicted<T>,
) -> Option<Registered<T>> {
    if cfg.work_budget.is_some() || from.frames != 1 {
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
pub(super) struct Sourced {
    pub(super) kept: Downsampled,
    /// Made with voxels coarser than `beta v`.
    pub(super) thinned: bool,
}

/// Step 2: the registration cloud, the `beta v` downsampling of `merge` in its order (then in
/// the reference's, if [`Config::reference_order`]), with coarser voxels if that keeps more
/// than `desired` points (0: never; see [`Config::desired_source_points`]).
pub(super) fn source_cloud<T: Real>(
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

/// The motion to deskew a registered whole sweep with again ([`Config::redeskew`]): the one
/// its registration found, from `last_pose` to `pose`, if the sweep was deskewed at a constant
/// rate (`constant_rate`) and registered against a map; the registration measured every
/// direction (a degenerate one's motion along a weak direction is not measured, and deskewing
/// with it bends the sweep); and that motion moves a point at `r_max` by more than
/// `delta_min` from where the prediction put it (`model_error`; below that the paper's
/// threshold reads the deviation as no motion, Sec. III-D).
pub(super) fn deskew_again<T: Real>(
    cfg: &Config<T>,
    constant_rate: bool,
    reg: &Registered<T>,
    model_error: T,
    last_pose: &Pose<T>,
) -> Option<Pose<T>> {
    let again = cfg.redeskew
        && constant_rate
        && reg.finite
        && measured_every_direction(cfg, reg)
        && model_error > cfg.min_motion_threshold;
    again.then(|| last_pose.inverse() * reg.pose)
}

/// Whether a registration measured every direction: a frame registered against a map, with
/// an observability not below `degeneracy_ratio`.
pub(super) fn measured_every_direction<T: Real>(cfg: &Config<T>, f: &Registered<T>) -> bool {
    !f.first_frame && f.observability.is_some_and(|o| o >= cfg.degeneracy_ratio)
}
