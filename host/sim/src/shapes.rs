//! Analytic solids the scene is built from: infinite planes, yaw-rotated boxes, vertical capped
//! cylinders and spheres, each with a ray intersection and a distance to its surface.
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
    /// A box rotated about the vertical through its centre (build with [`Shape::yawed_box`]).
    Box {
        /// Centre (m).
        centre: Point3<f64>,
        /// Half extents along its own x, y, z (m).
        half: Vector3<f64>,
        /// `(cos yaw, sin yaw)` of its rotation about z.
        rot: [f64; 2],
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

/// Rotates `v` by `-yaw` about z (world to box frame), given `(cos yaw, sin yaw)`.
#[inline]
fn unrotate(v: &Vector3<f64>, c: f64, s: f64) -> Vector3<f64> {
    Vector3::new(c * v.x + s * v.y, -s * v.x + c * v.y, v.z)
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
        Shape::Box {
            centre,
            half,
            rot: [libm::cos(yaw), libm::sin(yaw)],
        }
    }

    /// The xy bounding rectangle `[xmin, ymin, xmax, ymax]`.
    pub fn footprint(&self) -> [f64; 4] {
        match *self {
            Shape::Box { centre, half, rot } => {
                let [c, s] = rot;
                let ex = (c * half.x).abs() + (s * half.y).abs();
                let ey = (s * half.x).abs() + (c * half.y).abs();
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
        }
    }

    /// First intersection of the ray `o + t d` (unit `d`) with `t` in `(0, t_max)`.
    pub fn hit(&self, o: &Point3<f64>, d: &Vector3<f64>, t_max: f64) -> Option<RayHit> {
        match *self {
            Shape::Box { centre, half, rot } => {
                let [c, s] = rot;
                let lo = unrotate(&(o - centre), c, s);
                let ld = unrotate(d, c, s);
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
                // Back to world: rotate by +yaw.
                let normal = Vector3::new(c * n.x - s * n.y, s * n.x + c * n.y, n.z);
                Some(RayHit { t, normal })
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
        }
    }

    /// Unsigned distance from `p` to the solid's surface (m).
    pub fn distance(&self, p: &Point3<f64>) -> f64 {
        match *self {
            Shape::Box { centre, half, rot } => {
                let [c, s] = rot;
                box_sdf(&unrotate(&(p - centre), c, s), &half).abs()
            }
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
