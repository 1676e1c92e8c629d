//! SO(3) and SE(3) exponential and logarithm maps.
//!
//! The paper's deskewing (Eq. (4)) and every ICP update (Eq. (11)) go through `Exp`/`Log`. The
//! reference uses Sophus, whose SE(3) exponential maps the twist `[upsilon; omega]` to a
//! rotation `Exp(omega)` and a translation `V(omega) * upsilon` (`V` the left Jacobian of
//! SO(3)). nalgebra's `Isometry3::new` uses `upsilon` itself as the translation, which is a
//! different map, so the two maps are written out here with Sophus's formulas and its
//! small-angle branches. The types stay nalgebra's (`UnitQuaternion`, `Isometry3`).

use crate::geometry::Pose;
use crate::scalar::Real;
use nalgebra::{Matrix3, Quaternion, Translation3, UnitQuaternion, Vector3, Vector6};

/// Skew-symmetric matrix `[v]x` with `[v]x w = v x w`.
#[inline]
pub fn hat<T: Real>(v: &Vector3<T>) -> Matrix3<T> {
    let z = T::zero();
    Matrix3::new(z, -v.z, v.y, v.z, z, -v.x, -v.y, v.x, z)
}

/// `Exp: R^3 -> SO(3)` as a unit quaternion, with `theta = |omega|`.
pub fn so3_exp<T: Real>(omega: &Vector3<T>) -> (UnitQuaternion<T>, T) {
    let theta_sq = omega.norm_squared();
    let (theta, imag, real);
    if theta_sq < T::EPS * T::EPS {
        let theta_po4 = theta_sq * theta_sq;
        theta = T::zero();
        imag = T::of(0.5) - T::of(1.0 / 48.0) * theta_sq + T::of(1.0 / 3840.0) * theta_po4;
        real = T::one() - T::of(1.0 / 8.0) * theta_sq + T::of(1.0 / 384.0) * theta_po4;
    } else {
        theta = theta_sq.sqrt_l();
        let half = T::of(0.5) * theta;
        imag = half.sin_l() / theta;
        real = half.cos_l();
    }
    let q = Quaternion::new(real, imag * omega.x, imag * omega.y, imag * omega.z);
    (UnitQuaternion::new_unchecked(q), theta)
}

/// `Log: SO(3) -> R^3` (atan-based, wrapping the angle into `[-pi, pi]`), with the angle.
pub fn so3_log<T: Real>(q: &UnitQuaternion<T>) -> (Vector3<T>, T) {
    let v = q.as_ref().imag();
    let w = q.as_ref().scalar();
    let squared_n = v.norm_squared();
    let two = T::of(2.0);
    let (factor, theta);
    if squared_n < T::EPS * T::EPS {
        let squared_w = w * w;
        factor = two / w - T::of(2.0 / 3.0) * squared_n / (w * squared_w);
        theta = two * squared_n / w;
    } else {
        let n = squared_n.sqrt_l();
        let atan_nbyw = if w < T::zero() {
            (-n).atan2_l(-w)
        } else {
            n.atan2_l(w)
        };
        factor = two * atan_nbyw / n;
        theta = factor * n;
    }
    (v * factor, theta)
}

/// Left Jacobian `V(omega)` of SO(3).
pub fn left_jacobian<T: Real>(omega: &Vector3<T>, theta: T) -> Matrix3<T> {
    let theta_sq = theta * theta;
    let big_omega = hat(omega);
    if theta_sq < T::EPS * T::EPS {
        Matrix3::identity() + big_omega * T::of(0.5)
    } else {
        let omega_sq = big_omega * big_omega;
        Matrix3::identity()
            + big_omega * ((T::one() - theta.cos_l()) / theta_sq)
            + omega_sq * ((theta - theta.sin_l()) / (theta_sq * theta))
    }
}

/// Inverse of the left Jacobian of SO(3).
pub fn left_jacobian_inverse<T: Real>(omega: &Vector3<T>, theta: T) -> Matrix3<T> {
    let theta_sq = theta * theta;
    let big_omega = hat(omega);
    let omega_sq = big_omega * big_omega;
    let half = T::of(0.5);
    if theta_sq < T::EPS * T::EPS {
        Matrix3::identity() - big_omega * half + omega_sq * T::of(1.0 / 12.0)
    } else {
        let half_theta = half * theta;
        let c = (T::one() - half * theta * half_theta.cos_l() / half_theta.sin_l()) / theta_sq;
        Matrix3::identity() - big_omega * half + omega_sq * c
    }
}

/// `Exp: R^6 -> SE(3)` of the twist `[upsilon; omega]` (translation first, as in Sophus).
pub fn se3_exp<T: Real>(xi: &Vector6<T>) -> Pose<T> {
    let omega = Vector3::new(xi[3], xi[4], xi[5]);
    let upsilon = Vector3::new(xi[0], xi[1], xi[2]);
    let (q, theta) = so3_exp(&omega);
    let v = left_jacobian(&omega, theta);
    Pose::from_parts(Translation3::from(v * upsilon), q)
}

/// `Log: SE(3) -> R^6`, the inverse of [`se3_exp`].
pub fn se3_log<T: Real>(pose: &Pose<T>) -> Vector6<T> {
    let (omega, theta) = so3_log(&pose.rotation);
    let upsilon = left_jacobian_inverse(&omega, theta) * pose.translation.vector;
    Vector6::new(upsilon.x, upsilon.y, upsilon.z, omega.x, omega.y, omega.z)
}

/// Rotation angle in `[0, pi]`, computed as Eigen's `AngleAxis` does:
/// `2 atan2(|v|, |w|)` of the quaternion.
pub fn rotation_angle<T: Real>(q: &UnitQuaternion<T>) -> T {
    let n = q.as_ref().imag().norm();
    let w = q.as_ref().scalar().abs();
    if n == T::zero() {
        T::zero()
    } else {
        T::of(2.0) * n.atan2_l(w)
    }
}

/// Renormalises the rotation of a pose. Applied once per frame to the running pose so that
/// quaternion drift from repeated composition stays at rounding level over hours of driving.
pub fn renormalize<T: Real>(pose: &mut Pose<T>) {
    let q = pose.rotation.into_inner();
    pose.rotation = UnitQuaternion::new_normalize(q);
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    fn max_abs6(a: &Vector6<f64>, b: &Vector6<f64>) -> f64 {
        (a - b).amax()
    }

    #[test]
    fn exp_then_log_is_identity_on_twists_large_and_tiny() {
        let twists = [
            Vector6::new(0.3, -1.2, 2.0, 0.1, -0.4, 0.25),
            Vector6::new(1e-3, 2e-3, -5e-4, 1e-9, -2e-9, 3e-9),
            Vector6::new(5.0, 0.0, 0.0, 0.0, 0.0, 3.0),
            Vector6::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        ];
        for xi in &twists {
            let back = se3_log(&se3_exp(xi));
            // Sophus (and so the reference) loses V's Omega/2 term when 1 - cos(theta) rounds
            // to 0 (theta around 1e-8 rad): the round trip is then off by about |Omega u| / 2.
            assert!(max_abs6(xi, &back) < 1e-11, "{xi:?} -> {back:?}");
        }
    }

    #[test]
    fn exp_matches_closed_form_for_a_screw_about_z() {
        // A screw motion about z: rotate by phi while translating along the arc. For
        // upsilon = (r*phi, 0, 0) and omega = (0, 0, phi) the exact SE(3) exponential moves the
        // origin to (r sin(phi), r (1 - cos(phi)), 0): the chord of a circle of radius r.
        let (r, phi) = (2.0f64, 0.7f64);
        let pose = se3_exp(&Vector6::new(r * phi, 0.0, 0.0, 0.0, 0.0, phi));
        let p = pose * Point3::origin();
        assert!((p.x - r * phi.sin()).abs() < 1e-14);
        assert!((p.y - r * (1.0 - phi.cos())).abs() < 1e-14);
        assert!(p.z.abs() < 1e-15);
        assert!((rotation_angle(&pose.rotation) - phi).abs() < 1e-14);
    }

    #[test]
    fn exp_of_zero_is_bitwise_identity() {
        let pose = se3_exp(&Vector6::<f64>::zeros());
        let p = Point3::new(12.345678901234567, -0.1, 3.0);
        assert_eq!(pose * p, p);
    }

    #[test]
    fn log_wraps_angles_beyond_pi() {
        // A quaternion with negative w represents the same rotation; log must return the short
        // way round (angle <= pi).
        let (q, _) = so3_exp(&Vector3::new(0.0, 0.0, 3.0f64));
        let neg = UnitQuaternion::new_unchecked(-q.into_inner());
        let (w, theta) = so3_log(&neg);
        // Sophus reports a negative theta on this branch; only its magnitude is an angle.
        assert!((theta.abs() - 3.0).abs() < 1e-12 && (w.z - 3.0).abs() < 1e-12);
    }
}
