//! The two geometric types every stage shares.

/// Rigid transform used for every pose: a unit quaternion and a translation.
pub type Pose<T> = nalgebra::Isometry3<T>;
/// A 3D point.
pub type Point<T> = nalgebra::Point3<T>;

use crate::scalar::Real;

/// A pose in any scalar as `f64`: the translation widened, the quaternion widened and then
/// renormalised in `f64`, so that every output of an `f32` run (the host's pose files, a
/// receiver's pose datagrams) holds the same bits.
pub fn widen_pose<T: Real>(p: &Pose<T>) -> Pose<f64> {
    let q = p.rotation.coords;
    let t = p.translation.vector;
    Pose::from_parts(
        nalgebra::Translation3::new(t.x.wide(), t.y.wide(), t.z.wide()),
        nalgebra::UnitQuaternion::new_normalize(nalgebra::Quaternion::new(
            q.w.wide(),
            q.x.wide(),
            q.y.wide(),
            q.z.wide(),
        )),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widening_keeps_the_translation_and_renormalises_the_rotation() {
        let p = Pose::<f32>::new(
            nalgebra::Vector3::new(1.5, -2.25, 0.1),
            nalgebra::Vector3::new(0.3, -0.2, 1.1),
        );
        let w = widen_pose(&p);
        assert_eq!(w.translation.vector.x, 1.5);
        assert_eq!(w.translation.vector.z, f64::from(0.1f32));
        let norm = w.rotation.coords.norm();
        assert!(
            (norm - 1.0).abs() < 4.0 * f64::EPSILON,
            "|q| - 1 = {:e}",
            norm - 1.0
        );
        // Renormalised in f64, not just widened: the f32 quaternion's own norm is off by ~1e-8.
        let raw = p.rotation.coords.map(f64::from);
        assert!(
            (raw.norm() - 1.0).abs() > 1e-10,
            "the test needs an f32 norm off by more"
        );
        assert!((w.rotation.coords - raw / raw.norm()).norm() < 1e-15);
        let angle = (w.rotation.angle() - f64::from(p.rotation.angle())).abs();
        assert!(angle < 1e-6, "angle moved by {angle:e}");
    }
}
