//! The core's poses and frame reports in any scalar as `f64`, the one scalar the host speaks.

use kiss_odom_core::{FrameReport, Real};
use nalgebra::Isometry3;

/// A pose in any scalar as `f64`. The quaternion is renormalised after widening, as every
/// pose file this tool ever wrote was (the baseline poses are byte-compared).
pub fn widen<T: Real>(p: &Isometry3<T>) -> Isometry3<f64> {
    kiss_odom_core::widen_pose(p)
}

/// A frame report in any scalar as `f64` (its pose by [`widen`]).
pub fn widen_report<T: Real>(r: &FrameReport<T>) -> FrameReport<f64> {
    FrameReport {
        index: r.index,
        pose: widen(&r.pose),
        status: r.status,
        iterations: r.iterations,
        work: r.work,
        correspondences: r.correspondences,
        plane_correspondences: r.plane_correspondences,
        sigma: r.sigma.wide(),
        rms: r.rms.wide(),
        model_error: r.model_error.wide(),
        observability: r.observability.map(Real::wide),
        input_points: r.input_points,
        out_of_range: r.out_of_range,
        merge_points: r.merge_points,
        source_points: r.source_points,
        map_voxels: r.map_voxels,
        map_points: r.map_points,
        pruned_voxels: r.pruned_voxels,
        map_radius: r.map_radius.wide(),
        map_filled: r.map_filled,
        evicted_voxels: r.evicted_voxels,
        dropped: r.dropped,
        deskewed: r.deskewed,
        redeskewed: r.redeskewed,
        stamp_problem: r.stamp_problem,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use kiss_odom_io::pose::pose_difference;
    use nalgebra::Vector3;

    #[test]
    fn widening_keeps_an_f64_pose_and_rounds_an_f32_one() {
        let p = Isometry3::new(Vector3::new(0.5, -2.0, 7.0), Vector3::new(0.1, -0.2, 0.3));
        let (t, r) = pose_difference(&widen(&p), &p);
        assert!(t == 0.0 && r < 1e-15, "{t:e} {r:e}");
        let p32: Isometry3<f32> = p.cast();
        let (t, r) = pose_difference(&widen(&p32), &p);
        assert!(t < 1e-6 && r < 1e-6, "{t:e} {r:e}");
    }
}
