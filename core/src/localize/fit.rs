//! Step 3 and 4 of a frame: `P^*` registered to the prior map from a start, and the fit
//! measured (the inlier share off level ground, the observability ratio).

use super::Localizer;
use crate::geometry::{Point, Pose};
use crate::local_map::Voxels;
use crate::observability::observability;
use crate::registration::{align_points_to_map, moved_points, Executor, IcpParams};
use crate::scalar::Real;
use crate::storage::Storage;

impl<T: Real, S: Storage> Localizer<'_, T, S> {
    /// Registers `source` to the prior map from `from` with gate `gate`: the pose, the
    /// inlier share there and the conditioning.
    pub(super) fn register<E: Executor>(
        &mut self,
        exec: &E,
        source: &[[T; 3]],
        from: &Pose<T>,
        gate: T,
    ) -> (Pose<T>, T, Option<T>) {
        let cfg = &self.config;
        let h = self.file.header();
        let view = self.held.voxels::<T>(h.voxel_size, h.voxels_per_tile());
        let Some(work) = self.storage.as_mut().get_mut(..Self::words(&self.caps)) else {
            return (*from, T::zero(), None);
        };
        let params = IcpParams {
            convergence_criterion: cfg.convergence_criterion,
            max_iterations: cfg.max_iterations,
            budget: cfg.work_budget,
            planes: false,
            prior: None,
            stop_on_cycle: false,
        };
        let kernel = cfg.kernel_scale * gate / T::of(3.0);
        let icp = align_points_to_map(exec, source, work, &view, from, gate, kernel, &params);
        let pose = icp.pose;
        let finite = pose.translation.vector.iter().all(|v| v.is_finite())
            && pose.rotation.coords.iter().all(|v| v.is_finite());
        if !finite || source.is_empty() {
            return (*from, T::zero(), None);
        }
        let n = source.len();
        let origin = Point::from(pose.translation.vector);
        let obs = observability(&view, moved_points::<T>(work, n, false), n, &origin, gate);
        let (level, structure) = inliers(&view, source, &pose, self.settings.inlier_distance);
        let off_level = n - level;
        let share = if off_level == 0 {
            T::zero()
        } else {
            T::of(structure as f64 / off_level as f64)
        };
        (pose, share, obs)
    }
}

/// Of `source` moved by `pose`, the points within `near` of a map point on level ground (a
/// voxel whose spread is less than 5 % vertical) and those within `near` of any other map
/// point. Level ground matches whatever the horizontal error, so only the others tell a right
/// pose from a wrong one.
fn inliers<T: Real, V: Voxels<T>>(
    view: &V,
    source: &[[T; 3]],
    pose: &Pose<T>,
    near: T,
) -> (usize, usize) {
    let (mut level, mut structure) = (0, 0);
    for p in source {
        let q = pose * Point::new(p[0], p[1], p[2]);
        let Some((m, _)) = view.closest_neighbor(&q, near) else {
            continue;
        };
        let flat = view
            .voxel_covariance(&m)
            .is_some_and(|(k, c)| k >= 3 && c[(2, 2)] < T::of(0.05) * c.trace());
        if flat {
            level += 1;
        } else {
            structure += 1;
        }
    }
    (level, structure)
}
