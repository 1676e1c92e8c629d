//! The scalar type: one code path for `f32` and `f64`.
//!
//! Linear algebra comes from nalgebra's [`RealField`]; transcendental functions are called
//! explicitly through `libm` so that the same binary arithmetic runs on every target. A host
//! build that links `std` (which may switch nalgebra to the platform's libm) still gets the same
//! `sin`, `cos` and `atan2` as a bare-metal build, which keeps poses bit-identical across targets.

use nalgebra::RealField;

/// `floor(x) as i32` without a call to `floor` (baseline x86-64 and Cortex-M have no rounding
/// instruction): truncation toward zero, minus one for negative non-integers. Exact inside the
/// `i32` range; outside it the cast saturates exactly like `floor(x) as i32`, and NaN gives 0.
macro_rules! floor_to_i32 {
    ($x:expr, $t:ty) => {{
        let x: $t = $x;
        let i = x as i32;
        if (i as $t) > x {
            i.saturating_sub(1)
        } else {
            i
        }
    }};
}

/// A floating-point scalar the pipeline can run on: `f32` or `f64`.
pub trait Real:
    RealField + Copy + Default + bytemuck::Pod + core::fmt::Debug + Send + Sync + 'static
{
    /// Machine epsilon.
    const EPS: Self;
    /// Converts from `f64` (rounding for `f32`).
    fn of(x: f64) -> Self;
    /// Widens to `f64`.
    fn wide(self) -> f64;
    /// `sin` from libm.
    fn sin_l(self) -> Self;
    /// `cos` from libm.
    fn cos_l(self) -> Self;
    /// `atan2(self, x)` from libm.
    fn atan2_l(self, x: Self) -> Self;
    /// Correctly rounded square root.
    fn sqrt_l(self) -> Self;
    /// `floor(self)` converted to `i32`, saturating at the `i32` range (NaN gives 0).
    fn floor_i32(self) -> i32;
}

impl Real for f64 {
    const EPS: Self = f64::EPSILON;
    #[inline]
    fn of(x: f64) -> Self {
        x
    }
    #[inline]
    fn wide(self) -> f64 {
        self
    }
    #[inline]
    fn sin_l(self) -> Self {
        libm::sin(self)
    }
    #[inline]
    fn cos_l(self) -> Self {
        libm::cos(self)
    }
    #[inline]
    fn atan2_l(self, x: Self) -> Self {
        libm::atan2(self, x)
    }
    #[inline]
    fn sqrt_l(self) -> Self {
        libm::sqrt(self)
    }
    #[inline]
    fn floor_i32(self) -> i32 {
        floor_to_i32!(self, f64)
    }
}

impl Real for f32 {
    const EPS: Self = f32::EPSILON;
    #[inline]
    fn of(x: f64) -> Self {
        x as f32
    }
    #[inline]
    fn wide(self) -> f64 {
        self as f64
    }
    #[inline]
    fn sin_l(self) -> Self {
        libm::sinf(self)
    }
    #[inline]
    fn cos_l(self) -> Self {
        libm::cosf(self)
    }
    #[inline]
    fn atan2_l(self, x: Self) -> Self {
        libm::atan2f(self, x)
    }
    #[inline]
    fn sqrt_l(self) -> Self {
        libm::sqrtf(self)
    }
    #[inline]
    fn floor_i32(self) -> i32 {
        floor_to_i32!(self, f32)
    }
}

/// `sqrt(a) < sqrt(b)` for non-negative `a`, `b`, decided exactly as the reference decides it
/// (it compares Euclidean norms), but without a square root unless the two are within rounding
/// of each other. Used wherever the reference compares distances, so that ties and boundary
/// cases fall the same way.
#[inline]
pub fn norm_lt<T: Real>(a2: T, b2: T) -> bool {
    if a2 >= b2 {
        return false;
    }
    // a2 < b2: the square roots can only round to the same value when a2 and b2 are within a
    // few ulps; only then pay for them.
    let four = T::of(4.0);
    if a2 < b2 * (T::one() - four * T::EPS) {
        return true;
    }
    a2.sqrt_l() < b2.sqrt_l()
}

/// `sqrt(a2) < b` for non-negative `a2` and `b`, decided exactly (the reference compares a
/// norm with a distance), with a square root only near the boundary.
#[inline]
pub fn sqrt_lt<T: Real>(a2: T, b: T) -> bool {
    let b2 = b * b;
    let four = T::of(4.0);
    if a2 < b2 * (T::one() - four * T::EPS) {
        return true;
    }
    if a2 > b2 * (T::one() + four * T::EPS) {
        return false;
    }
    a2.sqrt_l() < b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn norm_lt_agrees_with_comparing_square_roots() {
        // Values spread over many magnitudes plus neighbours one ulp apart, where the fast path
        // must hand over to the exact comparison.
        let mut xs = [0.0f64; 64];
        let mut v = 1e-9;
        for (i, x) in xs.iter_mut().enumerate() {
            *x = if i % 2 == 0 {
                v
            } else {
                f64::from_bits(v.to_bits() + 1)
            };
            if i % 2 == 1 {
                v *= 3.7;
            }
        }
        for &a in &xs {
            for &b in &xs {
                assert_eq!(norm_lt(a, b), a.sqrt() < b.sqrt(), "a={a:e} b={b:e}");
            }
        }
    }

    #[test]
    fn sqrt_lt_agrees_with_the_square_root_comparison() {
        for i in 0..2000u64 {
            let b = 0.1 + i as f64 * 0.0137;
            let b2 = b * b;
            for a2 in [
                b2,
                f64::from_bits(b2.to_bits() - 1),
                f64::from_bits(b2.to_bits() + 1),
                b2 * 0.5,
                b2 * 2.0,
            ] {
                assert_eq!(sqrt_lt(a2, b), a2.sqrt() < b, "a2={a2:e} b={b:e}");
            }
        }
    }

    #[test]
    fn floor_i32_equals_libm_floor_then_cast() {
        // A log-spaced sweep over both signs from 1e-7 to 3e9 (past the i32 range), each value
        // with its neighbours: integers, halves and one ulp either side.
        let mut checked = 0;
        for e in -70..=95 {
            let m = 10f64.powf(e as f64 / 10.0);
            for base in [
                m,
                -m,
                m.round(),
                -m.round(),
                m.round() + 0.5,
                -m.round() - 0.5,
            ] {
                for x in [
                    base,
                    f64::from_bits(base.to_bits() + 1),
                    f64::from_bits(base.to_bits().saturating_sub(1)),
                ] {
                    assert_eq!(x.floor_i32(), libm::floor(x) as i32, "{x:e}");
                    let y = x as f32;
                    assert_eq!(y.floor_i32(), libm::floorf(y) as i32, "{y:e}");
                    checked += 1;
                }
            }
        }
        assert!(checked > 2900);
        for x in [
            -0.0,
            0.0,
            -1e-300,
            2147483647.5,
            -2147483648.5,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ] {
            assert_eq!(x.floor_i32(), libm::floor(x) as i32, "{x:e}");
        }
    }

    #[test]
    fn floor_i32_saturates_and_maps_nan_to_zero() {
        assert_eq!((-0.5f64).floor_i32(), -1);
        assert_eq!(1e300f64.floor_i32(), i32::MAX);
        assert_eq!(f64::NAN.floor_i32(), 0);
        assert_eq!((-2.0f32).floor_i32(), -2);
    }
}
