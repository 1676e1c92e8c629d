//! Analytic solids the scene is built from: infinite planes, boxes (turned about the vertical,
//! and tilted about their own long axis for slopes and ramps), vertical capped cylinders and
//! spheres, each with a ray intersection and a distance to its surface.
//!
//! Rays are unit-direction half-lines cast from outside every solid (the route keeps clear of
//! them); a ray starting inside returns its exit point rather than nothing.

use nalgebra::{Point3, Vector3};

/// Hits closer than this along a ray are ignored (m), so a surface never hits itself.
const T_EPS: f64 = 1e-9;

/// An infinite plane `n . x = d` with unit normal `n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// Unit normal.
    pub normal: Vector3<f64>,
    /// Offset along the normal (m).
    pub offset: f64,
}

/// A solid of the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A box rotated about the vertical through its centre, then tilted about its own x axis
    /// (build with [`Shape::yawed_box`] or [`Shape::tilted_box`]).
    Box {
        /// Centre (m).
        centre: Point3<f64>,
        /// Half extents along its own x, y, z (m).
        half: Vector3<f64>,
        /// `(cos yaw, sin yaw)` of its rotation about z.
        rot: [f64; 2],
        /// `(cos, sin)` of its tilt about its own x axis: `(1, 0)` stands it level.
        tilt: [f64; 2],
    },
    /// A vertical cylinder with flat caps from `z0` to `z1`.
    Cylinder {
        /// Axis position in the xy plane (m).
        centre: [f64; 2],
        /// Radius (m).
        radius: f64,
        /// Bottom and top heights (m).
        z: [f64; 2],
    },
    /// A sphere.
    Sphere {
        /// Centre (m).
        centre: Point3<f64>,
        /// Radius (m).
        radius: f64,
    },
    /// Foliage filling an upright ellipsoid, seen as a turbid medium (Beer-Lambert): a ray
    /// entering it stops after a distance drawn from an exponential law of mean `free_path`,
    /// or passes through. The draw is a pure function of the ray, so a scene stays
    /// deterministic; returns lie throughout the crown, as leaves give them.
    Foliage {
        /// Centre (m).
        centre: Point3<f64>,
        /// Semi-axes along x, y, z (m).
        axes: Vector3<f64>,
        /// Mean free path of a ray inside (m).
        free_path: f64,
    },
}

/// Where a ray met a surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// Distance along the unit ray (m).
    pub t: f64,
    /// Unit surface normal there (either orientation).
    pub normal: Vector3<f64>,
}

impl Plane {
    /// A plane through `point` with unit normal `normal`.
    pub fn new(normal: Vector3<f64>, point: Point3<f64>) -> Self {
        let normal = normal.normalize();
        Self {
            normal,
            offset: normal.dot(&point.coords),
        }
    }

    /// First intersection of the ray `o + t d` with `t` in `(0, t_max)`.
    pub fn hit(&self, o: &Point3<f64>, d: &Vector3<f64>, t_max: f64) -> Option<RayHit> {
        let den = self.normal.dot(d);
        if den == 0.0 {
            return None;
        }
        let t = (self.offset - self.normal.dot(&o.coords)) / den;
        (t > T_EPS && t < t_max).then_some(RayHit {
            t,
            normal: self.normal,
        })
    }

    /// Unsigned distance from `p` to the plane.
    pub fn distance(&self, p: &Point3<f64>) -> f64 {
        (self.normal.dot(&p.coords) - self.offset).abs()
    }
}

/// The uniform draw in `(0, 1]` of a ray `o + t d` through foliage centred at `c`.
fn foliage_draw(o: &Point3<f64>, d: &Vector3<f64>, c: &Point3<f64>) -> f64 {
    let bits = [o.x, o.y, o.z, d.x, d.y, d.z, c.x, c.y, c.z].map(f64::to_bits);
    let h = crate::rng::key(&bits);
    ((h >> 11) + 1) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A box's half extents seen from above, along its own x axis and across it: a tilt of
/// `(cos, sin)` about x widens it by its thickness.
pub fn plan_half(half: &Vector3<f64>, [ct, st]: [f64; 2]) -> [f64; 2] {
    [half.x, (ct * half.y).abs() + (st * half.z).abs()]
}

/// World to box frame: rotates `v` by `-yaw` about z, given `rot = (cos yaw, sin yaw)`, then by
/// minus the tilt about x (a level box skips the tilt, so its arithmetic is the yaw's alone).
#[inline]
fn unrotate(v: &Vector3<f64>, [c, s]: [f64; 2], [ct, st]: [f64; 2]) -> Vector3<f64> {
    let u = Vector3::new(c * v.x + s * v.y, -s * v.x + c * v.y, v.z);
    if st == 0.0 {
        return u;
    }
    Vector3::new(u.x, ct * u.y + st * u.z, -st * u.y + ct * u.z)
}

/// Box frame to world: the inverse of [`unrotate`].
#[inline]
fn rotate(v: &Vector3<f64>, [c, s]: [f64; 2], [ct, st]: [f64; 2]) -> Vector3<f64> {
    let u = if st == 0.0 {
        *v
    } else {
        Vector3::new(v.x, ct * v.y - st * v.z, st * v.y + ct * v.z)
    };
    Vector3::new(c * u.x - s * u.y, s * u.x + c * u.y, u.z)
}

/// Signed distance of a point to an axis-aligned box, from `|q| - half`.
#[inline]
fn box_sdf(q: &Vector3<f64>, half: &Vector3<f64>) -> f64 {
    let e = q.abs() - half;
    let outside = e.map(|x| x.max(0.0)).norm();
    outside + e.max().min(0.0)
}

impl Shape {
    /// A box with centre, half extents and rotation `yaw` (rad) about z.
    pub fn yawed_box(centre: Point3<f64>, half: Vector3<f64>, yaw: f64) -> Self {
        Self::tilted_box(centre, half, yaw, 0.0)
    }

    /// A box with centre, half extents, rotation `yaw` (rad) about z and then `tilt` (rad) about
    /// its own x axis: a positive tilt raises its `+y` side, so its top face is a slope.
    pub fn tilted_box(centre: Point3<f64>, half: Vector3<f64>, yaw: f64, tilt: f64) -> Self {
        Shape::Box {
            centre,
            half,
            rot: [libm::cos(yaw), libm::sin(yaw)],
            tilt: [libm::cos(tilt), libm::sin(tilt)],
        }
    }

    /// The lowest and highest heights of the solid (m).
    pub fn heights(&self) -> [f64; 2] {
        match *self {
            Shape::Box {
                centre, half, tilt, ..
            } => {
                let e = (tilt[1] * half.y).abs() + (tilt[0] * half.z).abs();
                [centre.z - e, centre.z + e]
            }
            Shape::Cylinder { z, .. } => z,
            Shape::Sphere { centre, radius } => [centre.z - radius, centre.z + radius],
            Shape::Foliage { centre, axes, .. } => [centre.z - axes.z, centre.z + axes.z],
        }
    }

    /// The xy bounding rectangle `[xmin, ymin, xmax, ymax]`.
    pub fn footprint(&self) -> [f64; 4] {
        match *self {
            Shape::Box {
                centre,
                half,
                rot,
                tilt,
            } => {
                let [c, s] = rot;
                let [hx, hy] = plan_half(&half, tilt);
                let ex = (c * hx).abs() + (s * hy).abs();
                let ey = (s * hx).abs() + (c * hy).abs();
                [centre.x - ex, centre.y - ey, centre.x + ex, centre.y + ey]
            }
            Shape::Cylinder { centre, radius, .. } => [
                centre[0] - radius,
                centre[1] - radius,
                centre[0] + radius,
                centre[1] + radius,
            ],
            Shape::Sphere { centre, radius } => [
                centre.x - radius,
                centre.y - radius,
                centre.x + radius,
                centre.y + radius,
            ],
            Shape::Foliage { centre, axes, .. } => [
                centre.x - axes.x,
                centre.y - axes.y,
                centre.x + axes.x,
                centre.y + axes.y,
            ],
        }
    }

    /// First intersection of the ray `o + t d` (unit `d`) with `t` in `(0, t_max)`.
    pub fn hit(&self, o: &Point3<f64>, d: &Vector3<f64>, t_max: f64) -> Option<RayHit> {
        match *self {
            Shape::Box {
                centre,
                half,
                rot,
                tilt,
            } => {
                let lo = unrotate(&(o - centre), rot, tilt);
                let ld = unrotate(d, rot, tilt);
                let (mut near, mut far) = (f64::NEG_INFINITY, f64::INFINITY);
                let (mut near_axis, mut far_axis) = (0, 0);
                for i in 0..3 {
                    if ld[i] == 0.0 {
                        if lo[i].abs() > half[i] {
                            return None;
                        }
                        continue;
                    }
                    let inv = 1.0 / ld[i];
                    let (mut t0, mut t1) = ((-half[i] - lo[i]) * inv, (half[i] - lo[i]) * inv);
                    if t0 > t1 {
                        core::mem::swap(&mut t0, &mut t1);
                    }
                    if t0 > near {
                        near = t0;
                        near_axis = i;
                    }
                    if t1 < far {
                        far = t1;
                        far_axis = i;
                    }
                }
                if near > far {
                    return None;
                }
                let (t, axis) = if near > T_EPS {
                    (near, near_axis)
                } else {
                    (far, far_axis)
                };
                if !(t > T_EPS && t < t_max) {
                    return None;
                }
                let mut n = Vector3::zeros();
                n[axis] = 1.0;
                Some(RayHit {
                    t,
                    normal: rotate(&n, rot, tilt),
                })
            }
            Shape::Cylinder { centre, radius, z } => {
                let mut best: Option<RayHit> = None;
                let (fx, fy) = (o.x - centre[0], o.y - centre[1]);
                let a = d.x * d.x + d.y * d.y;
                if a > 0.0 {
                    let b = fx * d.x + fy * d.y;
                    let c = fx * fx + fy * fy - radius * radius;
                    let disc = b * b - a * c;
                    if disc >= 0.0 {
                        let root = disc.sqrt();
                        for t in [(-b - root) / a, (-b + root) / a] {
                            let zt = o.z + t * d.z;
                            if t > T_EPS && t < t_max && zt >= z[0] && zt <= z[1] {
                                let n = Vector3::new(fx + t * d.x, fy + t * d.y, 0.0) / radius;
                                best = Some(RayHit { t, normal: n });
                                break;
                            }
                        }
                    }
                }
                if d.z != 0.0 {
                    for zc in z {
                        let t = (zc - o.z) / d.z;
                        let limit = best.map_or(t_max, |h| h.t);
                        if t > T_EPS && t < limit {
                            let (x, y) = (fx + t * d.x, fy + t * d.y);
                            if x * x + y * y <= radius * radius {
                                best = Some(RayHit {
                                    t,
                                    normal: Vector3::z(),
                                });
                            }
                        }
                    }
                }
                best
            }
            Shape::Sphere { centre, radius } => {
                let f = o - centre;
                let b = f.dot(d);
                let c = f.norm_squared() - radius * radius;
                let disc = b * b - c;
                if disc < 0.0 {
                    return None;
                }
                let root = disc.sqrt();
                let t = if -b - root > T_EPS {
                    -b - root
                } else {
                    -b + root
                };
                (t > T_EPS && t < t_max).then(|| RayHit {
                    t,
                    normal: (f + t * d) / radius,
                })
            }
            Shape::Foliage {
                centre,
                axes,
                free_path,
            } => {
                // The unit sphere in coordinates scaled by the semi-axes.
                let q = (o - centre).component_div(&axes);
                let v = d.component_div(&axes);
                let (a, b, c) = (v.norm_squared(), q.dot(&v), q.norm_squared() - 1.0);
                let disc = b * b - a * c;
                if disc < 0.0 {
                    return None;
                }
                let root = disc.sqrt();
                let (enter, exit) = (((-b - root) / a).max(T_EPS), (-b + root) / a);
                let t = enter - free_path * libm::log(foliage_draw(o, d, &centre));
                (t < exit && t < t_max).then_some(RayHit { t, normal: -d })
            }
        }
    }

    /// Unsigned distance from `p` to the solid's surface (m).
    pub fn distance(&self, p: &Point3<f64>) -> f64 {
        match *self {
            Shape::Box {
                centre,
                half,
                rot,
                tilt,
            } => box_sdf(&unrotate(&(p - centre), rot, tilt), &half).abs(),
            Shape::Cylinder { centre, radius, z } => {
                // The 2D box distance in (radial, height).
                let e = [
                    (p.x - centre[0]).hypot(p.y - centre[1]) - radius,
                    (p.z - 0.5 * (z[0] + z[1])).abs() - 0.5 * (z[1] - z[0]),
                ];
                let outside = e[0].max(0.0).hypot(e[1].max(0.0));
                (outside + e[0].max(e[1]).min(0.0)).abs()
            }
            Shape::Sphere { centre, radius } => ((p - centre).norm() - radius).abs(),
            // Distance to the volume (0 inside it), in the ellipsoid's scaled metric: an upper
            // bound outside, exact on the axes.
            Shape::Foliage { centre, axes, .. } => {
                let q = (p - centre).component_div(&axes);
                let n = q.norm();
                if n <= 1.0 {
                    0.0
                } else {
                    ((p - centre) * (1.0 - 1.0 / n)).norm()
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64, z: f64) -> Point3<f64> {
        Point3::new(x, y, z)
    }

    #[test]
    fn rotated_box_is_hit_on_its_near_face() {
        // A 2 x 2 x 2 box at x = 10 turned 45 degrees: its corner points at the ray.
        let b = Shape::yawed_box(
            p(10.0, 0.0, 1.0),
            Vector3::new(1.0, 1.0, 1.0),
            core::f64::consts::FRAC_PI_4,
        );
        let h = b.hit(&p(0.0, 0.0, 1.0), &Vector3::x(), 100.0).unwrap();
        assert!((h.t - (10.0 - 2f64.sqrt())).abs() < 1e-12, "{}", h.t);
        let aligned = Shape::yawed_box(p(10.0, 0.0, 1.0), Vector3::new(1.0, 1.0, 1.0), 0.0);
        let h = aligned
            .hit(&p(0.0, 0.0, 1.5), &Vector3::x(), 100.0)
            .unwrap();
        assert!((h.t - 9.0).abs() < 1e-12 && (h.normal.x.abs() - 1.0).abs() < 1e-12);
        assert!(aligned
            .hit(&p(0.0, 0.0, 2.5), &Vector3::x(), 100.0)
            .is_none());
        assert!(aligned.hit(&p(0.0, 0.0, 1.0), &Vector3::x(), 8.5).is_none());
        assert!(aligned
            .hit(&p(0.0, 0.0, 1.0), &-Vector3::x(), 100.0)
            .is_none());
    }

    #[test]
    fn a_tilted_box_is_a_slope_rising_on_its_plus_y_side() {
        // A slab 20 m wide across, 1 m thick, tilted 20 degrees and turned 90 degrees: its own
        // +y is world -x, so its top face climbs towards -x at tan(20 deg).
        let (tilt, yaw) = (20f64.to_radians(), core::f64::consts::FRAC_PI_2);
        let slab = Shape::tilted_box(p(0.0, 0.0, 0.0), Vector3::new(30.0, 10.0, 0.5), yaw, tilt);
        let top = |x: f64| {
            let h = slab.hit(&p(x, 3.0, 50.0), &-Vector3::z(), 100.0).unwrap();
            (50.0 - h.t, h.normal)
        };
        let (z0, n) = top(0.0);
        let (z1, _) = top(-4.0);
        let expected = 0.5 / tilt.cos();
        assert!((z0 - expected).abs() < 1e-12, "{z0} {expected}");
        assert!((z1 - z0 - 4.0 * tilt.tan()).abs() < 1e-12, "{z1} {z0}");
        assert!((n.z.abs() - tilt.cos()).abs() < 1e-12 && n.y.abs() < 1e-12);
        assert_eq!(slab.heights()[1], 10.0 * tilt.sin() + 0.5 * tilt.cos());
        let f = slab.footprint();
        let across = 10.0 * tilt.cos() + 0.5 * tilt.sin();
        assert!(
            (f[2] - across).abs() < 1e-12 && (f[3] - 30.0).abs() < 1e-12,
            "{f:?}"
        );
    }

    #[test]
    fn foliage_stops_rays_at_exponential_depths_inside_it() {
        // A crown 4 m across and deep with a 2 m free path: rays along its axis stop inside at a
        // mean depth of 2 m (truncated by its 8 m chord), and the share through is e^-4.
        let crown = Shape::Foliage {
            centre: p(20.0, 0.0, 5.0),
            axes: Vector3::new(4.0, 4.0, 3.0),
            free_path: 2.0,
        };
        let (mut inside, mut through, mut depth) = (0, 0, 0.0);
        for i in 0..20_000 {
            let o = p(0.0, 1e-6 * i as f64, 5.0);
            match crown.hit(&o, &Vector3::x(), 100.0) {
                Some(h) => {
                    assert!(
                        h.t > 16.0
                            && h.t < 24.0
                            && crown.distance(&(o + h.t * Vector3::x())) == 0.0
                    );
                    assert_eq!(
                        crown.hit(&o, &Vector3::x(), 100.0),
                        Some(h),
                        "deterministic"
                    );
                    inside += 1;
                    depth += h.t - 16.0;
                }
                None => through += 1,
            }
        }
        let mean = depth / inside as f64;
        // A mean of 2 m truncated at 8 m: 2 - 8 e^-4 / (1 - e^-4).
        let expected = 2.0 - 8.0 * (-4f64).exp() / (1.0 - (-4f64).exp());
        let share = through as f64 / 20_000.0;
        println!(
            "mean depth {mean:.3} m (expected {expected:.3}), through {share:.4} ({:.4})",
            (-4f64).exp()
        );
        assert!((mean - expected).abs() < 0.05 && (share - (-4f64).exp()).abs() < 0.005);
        assert!(crown.hit(&p(0.0, 5.0, 5.0), &Vector3::x(), 100.0).is_none());
        assert!(crown.hit(&p(0.0, 0.0, 5.0), &Vector3::x(), 16.0).is_none());
        assert_eq!(crown.heights(), [2.0, 8.0]);
        assert_eq!(crown.distance(&p(20.0, 0.0, 10.0)), 2.0);
    }

    #[test]
    fn cylinder_is_hit_on_its_side_and_its_top() {
        let c = Shape::Cylinder {
            centre: [5.0, 0.0],
            radius: 0.5,
            z: [0.0, 3.0],
        };
        let h = c.hit(&p(0.0, 0.0, 1.0), &Vector3::x(), 100.0).unwrap();
        assert!((h.t - 4.5).abs() < 1e-12);
        // Over the top: misses the side, and a ray from above lands on the cap.
        assert!(c.hit(&p(0.0, 0.0, 4.0), &Vector3::x(), 100.0).is_none());
        let down = c.hit(&p(5.1, 0.0, 10.0), &-Vector3::z(), 100.0).unwrap();
        assert!((down.t - 7.0).abs() < 1e-12);
    }

    #[test]
    fn sphere_and_plane_hits_are_where_geometry_says() {
        let s = Shape::Sphere {
            centre: p(0.0, 10.0, 0.0),
            radius: 2.0,
        };
        let h = s.hit(&p(0.0, 0.0, 0.0), &Vector3::y(), 100.0).unwrap();
        assert!((h.t - 8.0).abs() < 1e-12);
        let ground = Plane::new(Vector3::z(), Point3::origin());
        let d = Vector3::new(1.0, 0.0, -1.0).normalize();
        let h = ground.hit(&p(0.0, 0.0, 2.0), &d, 100.0).unwrap();
        assert!((h.t - 2.0 * 2f64.sqrt()).abs() < 1e-12);
        assert!(ground
            .hit(&p(0.0, 0.0, 2.0), &Vector3::x(), 100.0)
            .is_none());
    }

    #[test]
    fn every_hit_lies_on_the_surface_by_the_distance_function() {
        let shapes = [
            Shape::yawed_box(p(3.0, -2.0, 1.5), Vector3::new(2.0, 1.0, 1.5), 0.7),
            Shape::tilted_box(p(-3.0, -5.0, 1.0), Vector3::new(3.0, 4.0, 0.5), -0.4, 0.35),
            Shape::Cylinder {
                centre: [-4.0, 1.0],
                radius: 0.3,
                z: [0.0, 6.0],
            },
            Shape::Sphere {
                centre: p(0.0, 5.0, 4.0),
                radius: 2.5,
            },
        ];
        let mut rng = crate::rng::Stream::from_key(11);
        let (mut hits, mut worst) = (0, 0.0f64);
        for _ in 0..20_000 {
            let o = p(
                rng.range(-12.0, 12.0),
                rng.range(-12.0, 12.0),
                rng.range(0.0, 8.0),
            );
            let d = Vector3::new(rng.normal(), rng.normal(), rng.normal()).normalize();
            for s in &shapes {
                if s.distance(&o) < 1e-3 {
                    continue;
                }
                if let Some(h) = s.hit(&o, &d, 100.0) {
                    hits += 1;
                    worst = worst.max(s.distance(&(o + h.t * d)));
                }
            }
        }
        println!("{hits} hits, worst distance to surface {worst:.2e} m (tol 1e-9)");
        assert!(hits > 1000 && worst < 1e-9);
    }
}
