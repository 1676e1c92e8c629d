//! Pose helpers every reader, metric and comparison shares: a rotation matrix or a 4x4 rigid
//! matrix as a pose, and how far apart two poses are. Each exists once, here; the rotation
//! angle itself is the core's ([`kiss_odom_core::stages::rotation_angle`]).

use kiss_odom_core::stages::rotation_angle;
use nalgebra::{Isometry3, Matrix3, Matrix4, Rotation3, Translation3, UnitQuaternion};

/// A rotation matrix as a quaternion, without re-projection (as Sophus does when the
/// reference receives a matrix). Input that may not be a rotation must be checked first
/// (`io::poses::isometry_from_matrix` projects and checks).
pub fn quaternion_of(r: &Matrix3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*r))
}

/// A 4x4 rigid matrix as a pose, the rotation block through [`quaternion_of`].
pub fn pose_of(m: &Matrix4<f64>) -> Isometry3<f64> {
    let r: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    Isometry3::from_parts(
        Translation3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]),
        quaternion_of(&r),
    )
}

/// [`pose_of`] of 16 row-major numbers; `None` for any other count.
pub fn pose_of_row_major(values: &[f64]) -> Option<Isometry3<f64>> {
    (values.len() == 16).then(|| pose_of(&Matrix4::from_row_slice(values)))
}

/// (distance between the positions in m, angle of `a^-1 b`'s rotation in rad, accurate for
/// tiny angles).
pub fn pose_difference(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    let dt = (a.translation.vector - b.translation.vector).norm();
    (dt, rotation_angle(&(a.rotation.inverse() * b.rotation)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn pose_difference_measures_distance_and_angle() {
        let a = Isometry3::new(Vector3::new(1.0, 2.0, 3.0), Vector3::new(0.0, 0.0, 0.3));
        let b = Isometry3::new(
            Vector3::new(1.0, 2.0, 3.5),
            Vector3::new(0.0, 0.0, 0.3 + 1e-9),
        );
        let (t, r) = pose_difference(&a, &b);
        assert!((t - 0.5).abs() < 1e-15);
        assert!((r - 1e-9).abs() < 1e-15, "{r}");
        assert_eq!(pose_difference(&a, &a), (0.0, 0.0));
    }

    #[test]
    fn a_matrix_becomes_the_pose_it_holds() {
        let p = Isometry3::new(Vector3::new(0.5, -2.0, 7.0), Vector3::new(0.1, -0.2, 0.3));
        let m = p.to_homogeneous();
        let back = pose_of(&m);
        let (t, r) = pose_difference(&p, &back);
        assert!(t < 1e-15 && r < 1e-15, "{t:e} {r:e}");
        let rows: Vec<f64> = (0..16).map(|i| m[(i / 4, i % 4)]).collect();
        assert_eq!(pose_of_row_major(&rows), Some(back));
        assert_eq!(pose_of_row_major(&rows[..12]), None);
    }
}
