//! Street fronts generated along the route (the `urban` and `fast` scenes), and what every
//! generated scene shares: an object's [`Footprint`], the [`RouteIndex`] that keeps objects clear
//! of the driven path, and the [`City`] that places them (and groups them into the objects a
//! revisit may change).

use crate::rng::{Purpose, Stream};
use crate::scene::Solid;
use crate::shapes::{plan_half, Shape};
use crate::trajectory::Route;
use nalgebra::{Point3, Vector3};
use std::ops::Range;

/// What kind of object a [`Group`] of solids is, for a revisit's changes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GroupKind {
    /// A parked car (body and cabin): what changes first between visits.
    Car,
    /// A structure: a building with its facade, a wall, a rack, a pole, a tree, a boulder.
    Structure,
}

/// Consecutive solids that make one object (a car's body and cabin, a building and its
/// pilasters): a revisit moves, turns or removes them together.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Group {
    /// What the object is.
    pub kind: GroupKind,
    /// Its solids, the first one the object's body.
    pub solids: Range<usize>,
}

/// Reflectivity of asphalt, concrete walls and ceilings.
pub(super) const GROUND: f32 = 0.2;

/// A 2D region an object occupies, for clearance checks against the route.
#[derive(Clone, Copy, Debug)]
pub(super) enum Footprint {
    /// Centre, half extents, `(cos, sin)` of its yaw.
    Rect([f64; 2], [f64; 2], [f64; 2]),
    /// Centre, radius.
    Disc([f64; 2], f64),
}

impl Footprint {
    pub(super) fn centre_radius(&self) -> ([f64; 2], f64) {
        match *self {
            Footprint::Rect(c, h, _) => (c, h[0].hypot(h[1])),
            Footprint::Disc(c, r) => (c, r),
        }
    }

    /// The footprint of `shape` seen from above.
    pub(super) fn of(shape: &Shape) -> Self {
        match *shape {
            Shape::Box {
                centre,
                half,
                rot,
                tilt,
            } => Footprint::Rect([centre.x, centre.y], plan_half(&half, tilt), rot),
            Shape::Cylinder { centre, radius, .. } => Footprint::Disc(centre, radius),
            Shape::Sphere { centre, radius } => Footprint::Disc([centre.x, centre.y], radius),
            Shape::Foliage { centre, axes, .. } => {
                Footprint::Disc([centre.x, centre.y], axes.x.max(axes.y))
            }
        }
    }

    pub(super) fn distance(&self, q: [f64; 2]) -> f64 {
        match *self {
            Footprint::Rect(c, h, [cs, sn]) => {
                let (dx, dy) = (q[0] - c[0], q[1] - c[1]);
                let (lx, ly) = (cs * dx + sn * dy, -sn * dx + cs * dy);
                let (ex, ey) = ((lx.abs() - h[0]).max(0.0), (ly.abs() - h[1]).max(0.0));
                ex.hypot(ey)
            }
            Footprint::Disc(c, r) => ((q[0] - c[0]).hypot(q[1] - c[1]) - r).max(0.0),
        }
    }
}

/// Route samples every metre, binned by cell for "is anything of the route near here".
pub(super) struct RouteIndex {
    pub(super) cell: f64,
    /// `(cell key, sample)`, sorted by key.
    pub(super) samples: Vec<((i64, i64), [f64; 2])>,
}

impl RouteIndex {
    const CELL: f64 = 16.0;

    pub(super) fn new(route: &Route) -> Self {
        let (s0, s1) = route.knot_span();
        let n = (s1 - s0).max(0.0) as usize + 1;
        let mut samples: Vec<_> = (0..n)
            .map(|i| {
                let p = route.position(s0 + i as f64);
                (Self::key(p, Self::CELL), p)
            })
            .collect();
        samples.sort_by_key(|&(k, _)| k);
        Self {
            cell: Self::CELL,
            samples,
        }
    }

    pub(super) fn key(p: [f64; 2], cell: f64) -> (i64, i64) {
        ((p[0] / cell).floor() as i64, (p[1] / cell).floor() as i64)
    }

    /// Whether every route sample is at least `min` from `f`.
    pub(super) fn clear(&self, f: &Footprint, min: f64) -> bool {
        let (c, r) = f.centre_radius();
        let reach = r + min + 1.0;
        let lo = Self::key([c[0] - reach, c[1] - reach], self.cell);
        let hi = Self::key([c[0] + reach, c[1] + reach], self.cell);
        for ix in lo.0..=hi.0 {
            for iy in lo.1..=hi.1 {
                let start = self.samples.partition_point(|&(k, _)| k < (ix, iy));
                for &(k, q) in &self.samples[start..] {
                    if k != (ix, iy) {
                        break;
                    }
                    if f.distance(q) < min {
                        return false;
                    }
                }
            }
        }
        true
    }
}

/// Clearance from the route (the driven lane's centre) for each kind of object (m).
pub(super) const BUILDING_CLEARANCE: f64 = 7.0;
pub(super) const CAR_CLEARANCE: f64 = 3.0;
pub(super) const POLE_CLEARANCE: f64 = 4.0;
pub(super) const CANOPY_CLEARANCE: f64 = 3.0;

/// Generates street furniture along the route.
pub(super) struct City<'a> {
    pub(super) route: &'a Route,
    pub(super) index: RouteIndex,
    pub(super) rng: Stream,
    pub(super) solids: Vec<Solid>,
    /// The objects a revisit may change, in the order they were placed.
    pub(super) groups: Vec<Group>,
}

impl<'a> City<'a> {
    pub(super) fn new(route: &'a Route, seed: u64) -> Self {
        Self {
            route,
            index: RouteIndex::new(route),
            rng: Stream::new(seed, Purpose::Scene),
            solids: Vec::new(),
            groups: Vec::new(),
        }
    }

    /// Records the solids placed since `start` as one object of `kind` (none: no object).
    pub(super) fn group(&mut self, kind: GroupKind, start: usize) {
        if self.solids.len() > start {
            self.groups.push(Group {
                kind,
                solids: start..self.solids.len(),
            });
        }
    }

    /// The solids placed and their objects.
    pub(super) fn finish(self) -> (Vec<Solid>, Vec<Group>) {
        (self.solids, self.groups)
    }

    /// The point at arc length `s` moved `lateral` metres to the left, and the heading there.
    pub(super) fn offset(&self, s: f64, lateral: f64) -> ([f64; 2], f64) {
        let p = self.route.position(s);
        let psi = self.route.heading(s);
        let (sn, cs) = (libm::sin(psi), libm::cos(psi));
        ([p[0] - sn * lateral, p[1] + cs * lateral], psi)
    }

    /// Adds a box if its footprint keeps `clearance` from the route; returns whether it did.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn add_box(
        &mut self,
        c: [f64; 2],
        yaw: f64,
        half: [f64; 3],
        z0: f64,
        reflectivity: f64,
        clearance: Option<f64>,
    ) -> bool {
        let rot = [libm::cos(yaw), libm::sin(yaw)];
        let fp = Footprint::Rect(c, [half[0], half[1]], rot);
        if let Some(min) = clearance {
            if !self.index.clear(&fp, min) {
                return false;
            }
        }
        self.solids.push(Solid {
            shape: Shape::yawed_box(
                Point3::new(c[0], c[1], z0 + half[2]),
                Vector3::new(half[0], half[1], half[2]),
                yaw,
            ),
            reflectivity: reflectivity as f32,
        });
        true
    }

    pub(super) fn generate(mut self) -> (Vec<Solid>, Vec<Group>) {
        let (s0, s1) = self.route.knot_span();
        for side in [1.0, -1.0] {
            self.buildings(s0, s1, side);
            self.cars(s0, s1, side);
            self.poles(s0, s1, side);
            self.trees(s0, s1, side);
            self.clutter(s0, s1, side);
        }
        self.finish()
    }

    pub(super) fn buildings(&mut self, s0: f64, s1: f64, side: f64) {
        let mut s = s0;
        let mut next_cross = s0 + self.rng.range(20.0, 100.0);
        while s < s1 {
            if s >= next_cross {
                let width = self.rng.range(10.0, 18.0);
                self.cross_street(s + 0.5 * width, side, width);
                s += width;
                next_cross = s + self.rng.range(60.0, 150.0);
                continue;
            }
            let frontage = self.rng.range(8.0, 30.0);
            if self.rng.chance(0.2) {
                // An alley or an open lot, sometimes behind a low wall.
                let gap = self.rng.range(6.0, 25.0);
                let (wall, setback, height) = (
                    self.rng.chance(0.5),
                    self.rng.range(9.0, 13.0),
                    self.rng.range(1.0, 2.5),
                );
                if wall {
                    let (c, yaw) = self.offset(s + 0.5 * gap, side * (setback + 0.15));
                    let half = [0.5 * gap - 0.5, 0.15, 0.5 * height];
                    let start = self.solids.len();
                    self.add_box(c, yaw, half, 0.0, 0.35, Some(BUILDING_CLEARANCE));
                    self.group(GroupKind::Structure, start);
                }
                s += gap;
                continue;
            }
            let setback = self.rng.range(9.0, 15.0);
            let depth = self.rng.range(10.0, 30.0);
            let height = self.rng.range(5.0, 35.0);
            let refl = self.rng.range(0.25, 0.6);
            let mid = s + 0.5 * frontage;
            let (c, yaw) = self.offset(mid, side * (setback + 0.5 * depth));
            let half = [0.5 * frontage - 0.3, 0.5 * depth, 0.5 * height];
            let start = self.solids.len();
            if self.add_box(c, yaw, half, 0.0, refl, Some(BUILDING_CLEARANCE)) {
                self.facade(mid, side, setback, half[0], height, refl);
            }
            self.group(GroupKind::Structure, start);
            // A second row behind, seen through gaps and over low buildings.
            let back = self.rng.chance(0.5);
            let (gap, d2, h2) = (
                self.rng.range(8.0, 25.0),
                self.rng.range(10.0, 25.0),
                self.rng.range(8.0, 45.0),
            );
            let f2 = frontage * self.rng.range(0.6, 1.0);
            let refl2 = self.rng.range(0.25, 0.6);
            if back {
                let (c, yaw) = self.offset(mid, side * (setback + depth + gap + 0.5 * d2));
                let half = [0.5 * f2, 0.5 * d2, 0.5 * h2];
                let start = self.solids.len();
                self.add_box(c, yaw, half, 0.0, refl2, Some(BUILDING_CLEARANCE));
                self.group(GroupKind::Structure, start);
            }
            s += frontage;
        }
    }

    /// A side street leaving the route at arc length `s`: buildings line both of its sides,
    /// so their fronts face along the route (what keeps registration honest along the road).
    pub(super) fn cross_street(&mut self, s: f64, side: f64, width: f64) {
        let (p, psi) = self.offset(s, 0.0);
        let (cs, sn) = (libm::cos(psi), libm::sin(psi));
        // Away from the route along the side street, and along the route.
        let away = [-sn * side, cs * side];
        let along = [cs, sn];
        let yaw = psi + side * core::f64::consts::FRAC_PI_2;
        for sigma in [-1.0, 1.0] {
            let mut d = self.rng.range(9.0, 14.0);
            let reach = self.rng.range(40.0, 100.0);
            while d < reach {
                let frontage = self.rng.range(8.0, 30.0);
                let gap = self.rng.chance(0.2);
                let setback = self.rng.range(0.5 * width + 1.0, 0.5 * width + 4.0);
                let depth = self.rng.range(10.0, 25.0);
                let height = self.rng.range(5.0, 35.0);
                let refl = self.rng.range(0.25, 0.6);
                if !gap {
                    let u = d + 0.5 * frontage;
                    let v = sigma * (setback + 0.5 * depth);
                    let c = [
                        p[0] + away[0] * u + along[0] * v,
                        p[1] + away[1] * u + along[1] * v,
                    ];
                    let half = [0.5 * frontage - 0.3, 0.5 * depth, 0.5 * height];
                    let start = self.solids.len();
                    self.add_box(c, yaw, half, 0.0, refl, Some(BUILDING_CLEARANCE));
                    self.group(GroupKind::Structure, start);
                }
                d += frontage;
            }
        }
    }

    /// Pilasters or shop-front columns along a building's street face: relief along the
    /// street, which flat facades do not give.
    pub(super) fn facade(
        &mut self,
        mid: f64,
        side: f64,
        setback: f64,
        half_front: f64,
        height: f64,
        refl: f64,
    ) {
        let spacing = self.rng.range(3.0, 6.0);
        let (width, depth) = (self.rng.range(0.4, 0.8), self.rng.range(0.3, 0.6));
        let tall = if self.rng.chance(0.5) {
            height
        } else {
            height.min(self.rng.range(3.0, 4.5))
        };
        let n = ((2.0 * half_front) / spacing).floor() as i64;
        let (face, yaw) = self.offset(mid, side * (setback - 0.5 * depth));
        let (cs, sn) = (libm::cos(yaw), libm::sin(yaw));
        for i in 0..=n {
            let u = -0.5 * n as f64 * spacing + i as f64 * spacing;
            if u.abs() > half_front - 0.5 * width {
                continue;
            }
            let c = [face[0] + u * cs, face[1] + u * sn];
            let half = [0.5 * width, 0.5 * depth, 0.5 * tall];
            self.add_box(c, yaw, half, 0.0, refl, Some(BUILDING_CLEARANCE - 1.0));
        }
    }

    /// Bollards, sign posts, hydrants, bushes and bins along the kerb.
    pub(super) fn clutter(&mut self, s0: f64, s1: f64, side: f64) {
        let mut s = s0;
        while s < s1 {
            s += self.rng.range(5.0, 15.0);
            let kind = self.rng.next_u64() % 5;
            let lateral = side * self.rng.range(5.8, 7.5);
            let size = self.rng.range(0.0, 1.0);
            let (c, yaw) = self.offset(s, lateral);
            let disc = |r: f64| Footprint::Disc(c, r);
            let cyl = |r: f64, h: f64| Shape::Cylinder {
                centre: c,
                radius: r,
                z: [0.0, h],
            };
            let (shape, refl, fp) = match kind {
                0 => (cyl(0.1, 0.9 + 0.3 * size), 0.6, disc(0.1)),
                1 => (cyl(0.04, 2.2 + 0.6 * size), 0.5, disc(0.4)),
                2 => (cyl(0.15, 0.6 + 0.2 * size), 0.7, disc(0.15)),
                3 => {
                    let r = 0.5 + 0.7 * size;
                    let sphere = Shape::Sphere {
                        centre: Point3::new(c[0], c[1], 0.6 * r),
                        radius: r,
                    };
                    (sphere, 0.25, disc(r))
                }
                _ => {
                    let b = Shape::yawed_box(
                        Point3::new(c[0], c[1], 0.55),
                        Vector3::new(0.3, 0.3, 0.55),
                        yaw,
                    );
                    (b, 0.3, disc(0.45))
                }
            };
            if !self.index.clear(&fp, POLE_CLEARANCE) {
                continue;
            }
            self.solids.push(Solid {
                shape,
                reflectivity: refl as f32,
            });
            if kind == 1 {
                // The sign plate, facing the road.
                let top = 2.2 + 0.6 * size;
                self.add_box(c, yaw, [0.3, 0.03, 0.3], top, 0.9, None);
            }
        }
    }

    pub(super) fn cars(&mut self, s0: f64, s1: f64, side: f64) {
        let mut s = s0;
        while s < s1 {
            s += self.rng.range(5.5, 15.0);
            let parked = self.rng.chance(0.6);
            let (len, width) = (self.rng.range(4.0, 4.8), self.rng.range(1.7, 1.9));
            let skew = self.rng.range(-0.05, 0.05);
            let lateral = side * self.rng.range(4.4, 4.8);
            let paint = self.rng.range(0.05, 0.9);
            if !parked {
                continue;
            }
            let (c, psi) = self.offset(s, lateral);
            let yaw = psi + skew;
            let body = [0.5 * len, 0.5 * width, 0.375];
            let start = self.solids.len();
            if self.add_box(c, yaw, body, 0.25, paint, Some(CAR_CLEARANCE)) {
                // The cabin sits a little behind the middle; dark glass.
                let back = 0.1 * len;
                let cc = [c[0] - back * libm::cos(yaw), c[1] - back * libm::sin(yaw)];
                let cabin = [0.28 * len, 0.5 * width - 0.08, 0.23];
                self.add_box(cc, yaw, cabin, 1.0, 0.1, None);
                self.group(GroupKind::Car, start);
            }
        }
    }

    pub(super) fn poles(&mut self, s0: f64, s1: f64, side: f64) {
        let mut s = s0;
        while s < s1 {
            s += self.rng.range(15.0, 35.0);
            let lateral = side * self.rng.range(6.2, 6.8);
            let (radius, height) = (self.rng.range(0.1, 0.18), self.rng.range(5.0, 9.0));
            let (c, psi) = self.offset(s, lateral);
            if !self.pole(c, radius, height) {
                continue;
            }
            // A lamp arm reaching over the road, well above the sensor.
            let (ac, _) = self.offset(s, lateral - side * 0.9);
            self.add_box(ac, psi, [0.08, 0.9, 0.06], height - 0.3, 0.6, None);
        }
    }

    pub(super) fn trees(&mut self, s0: f64, s1: f64, side: f64) {
        let mut s = s0;
        while s < s1 {
            s += self.rng.range(8.0, 25.0);
            let planted = self.rng.chance(0.6);
            let lateral = side * self.rng.range(7.2, 8.8);
            let (trunk_r, trunk_h) = (self.rng.range(0.15, 0.3), self.rng.range(2.5, 4.0));
            let crown = self.rng.range(1.5, 3.0);
            if !planted {
                continue;
            }
            let (c, _) = self.offset(s, lateral);
            self.tree(c, [trunk_r, trunk_h], crown);
        }
    }

    /// Adds a pole at `c` if it keeps clear of the route; returns whether it did.
    pub(super) fn pole(&mut self, c: [f64; 2], radius: f64, height: f64) -> bool {
        if !self
            .index
            .clear(&Footprint::Disc(c, radius), POLE_CLEARANCE)
        {
            return false;
        }
        self.solids.push(Solid {
            shape: Shape::Cylinder {
                centre: c,
                radius,
                z: [0.0, height],
            },
            reflectivity: 0.5,
        });
        true
    }

    /// Adds a tree (trunk radius and height, crown radius) at `c` if its crown keeps clear of
    /// the route.
    pub(super) fn tree(&mut self, c: [f64; 2], [trunk_r, trunk_h]: [f64; 2], crown: f64) {
        if !self
            .index
            .clear(&Footprint::Disc(c, crown), CANOPY_CLEARANCE)
        {
            return;
        }
        self.solids.push(Solid {
            shape: Shape::Cylinder {
                centre: c,
                radius: trunk_r,
                z: [0.0, trunk_h],
            },
            reflectivity: 0.15,
        });
        self.solids.push(Solid {
            shape: Shape::Sphere {
                centre: Point3::new(c[0], c[1], trunk_h + 0.6 * crown),
                radius: crown,
            },
            reflectivity: 0.3,
        });
    }
}
