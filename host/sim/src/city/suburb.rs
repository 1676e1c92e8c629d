//! The suburban scene: long streets lined with detached houses in rows out to about 100 m on
//! both sides (front yards, hedges, garden and street trees, lamp posts), cut by side streets
//! that open long views. Crowns and hedges are clumps of foliage that rays pass between, so
//! vegetation fills voxels in depth, as real foliage does. A 16-beam sensor at road speed sees
//! its ground disc and this structure out to `r_max`: the scene a map sized from city streets
//! fills.

use super::streets::{City, Footprint, Group, GroupKind, BUILDING_CLEARANCE, CANOPY_CLEARANCE};
use crate::scene::Solid;
use crate::shapes::Shape;
use nalgebra::Point3;

/// Lateral distance (m) from the route of the first row of houses' street face, and the
/// spacing of the rows behind it; rows stop at [`LAST_ROW`].
const FIRST_ROW: f64 = 14.0;
const ROW_SPACING: f64 = 26.0;
const LAST_ROW: f64 = 100.0;
/// Largest radius of a clump of foliage (m).
const CLUMP_MAX: f64 = 0.5;

impl City<'_> {
    /// Houses, yards and trees along the whole route, both sides.
    pub(super) fn suburb(mut self) -> (Vec<Solid>, Vec<Group>) {
        let (s0, s1) = self.route.knot_span();
        for side in [1.0, -1.0] {
            let mut row = FIRST_ROW;
            while row < LAST_ROW {
                let offset = row + self.rng.range(-3.0, 3.0);
                self.house_row(s0, s1, side, offset, row == FIRST_ROW);
                row += ROW_SPACING;
            }
            self.poles(s0, s1, side);
            self.cars(s0, s1, side);
            self.clutter(s0, s1, side);
            self.gardens(s0, s1, side);
        }
        self.finish()
    }

    /// One row of houses whose street faces stand `setback` from the route, with gaps for side
    /// streets every 150-300 m; the first row gets hedges along the pavement.
    fn house_row(&mut self, s0: f64, s1: f64, side: f64, setback: f64, hedges: bool) {
        let mut s = s0 + self.rng.range(0.0, 20.0);
        let mut next_street = s + self.rng.range(60.0, 300.0);
        while s < s1 {
            if s >= next_street {
                s += self.rng.range(12.0, 18.0);
                next_street = s + self.rng.range(150.0, 300.0);
                continue;
            }
            let lot = self.rng.range(18.0, 35.0);
            if self.rng.chance(0.25) {
                s += lot; // an empty lot
                continue;
            }
            let frontage = (lot - self.rng.range(8.0, 16.0)).max(8.0);
            let (depth, height) = (self.rng.range(8.0, 14.0), self.rng.range(3.5, 7.5));
            let refl = self.rng.range(0.25, 0.6);
            let mid = s + 0.5 * lot;
            let (c, yaw) = self.offset(mid, side * (setback + 0.5 * depth));
            let half = [0.5 * frontage, 0.5 * depth, 0.5 * height];
            let start = self.solids.len();
            self.add_box(c, yaw, half, 0.0, refl, Some(BUILDING_CLEARANCE));
            self.group(GroupKind::Structure, start);
            // A garage or shed beside some houses.
            if self.rng.chance(0.4) {
                let along = 0.5 * frontage + self.rng.range(1.5, 3.0);
                let (gc, gyaw) = self.offset(mid + along, side * (setback + 3.0));
                let g = [1.5, 3.0, 0.5 * self.rng.range(2.4, 3.2)];
                let start = self.solids.len();
                self.add_box(gc, gyaw, g, 0.0, 0.4, Some(BUILDING_CLEARANCE));
                self.group(GroupKind::Structure, start);
            }
            // A fence or hedge along the lot line, back to the next row.
            if self.rng.chance(0.5) {
                let (fc, fyaw) = self.offset(s, side * (setback + 0.5 * ROW_SPACING));
                let f = [
                    0.05,
                    0.5 * ROW_SPACING - 2.0,
                    0.5 * self.rng.range(1.0, 2.0),
                ];
                self.add_box(fc, fyaw, f, 0.0, 0.3, Some(BUILDING_CLEARANCE));
            }
            if hedges && self.rng.chance(0.6) {
                let inset = self.rng.range(2.0, 4.0);
                self.hedge(mid, side * (setback - inset), lot - 3.0);
            }
            s += lot;
        }
    }

    /// Street trees along the pavement and trees in the yards and between the rows, out to
    /// 100 m.
    fn gardens(&mut self, s0: f64, s1: f64, side: f64) {
        let mut s = s0;
        while s < s1 {
            s += self.rng.range(1.5, 5.0);
            let lateral = if self.rng.chance(0.2) {
                self.rng.range(7.5, 9.5) // a street tree
            } else {
                self.rng.range(15.0, LAST_ROW)
            };
            let (trunk_r, trunk_h) = (self.rng.range(0.12, 0.35), self.rng.range(1.5, 4.5));
            let crown = self.rng.range(1.5, 5.0);
            let (c, _) = self.offset(s, side * lateral);
            self.porous_tree(c, [trunk_r, trunk_h], crown);
        }
    }

    /// A trunk and a crown of foliage clumps scattered through an ellipsoid of `crown` radius
    /// (0.8 of it high), if the crown keeps clear of the route.
    fn porous_tree(&mut self, c: [f64; 2], [trunk_r, trunk_h]: [f64; 2], crown: f64) {
        if !self
            .index
            .clear(&Footprint::Disc(c, crown + CLUMP_MAX), CANOPY_CLEARANCE)
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
        let centre = [c[0], c[1], trunk_h + 0.8 * crown];
        let clumps = (4.0 * crown * crown) as usize;
        self.foliage(centre, [crown, crown, 0.8 * crown], clumps);
    }

    /// A hedge `length` long at `lateral` from the route, centred on arc length `s`: clumps
    /// of foliage 0.8-1.8 m high.
    fn hedge(&mut self, s: f64, lateral: f64, length: f64) {
        let (c, yaw) = self.offset(s, lateral);
        let half = [0.5 * length + CLUMP_MAX, 0.6 + CLUMP_MAX];
        let fp = Footprint::Rect(c, half, [libm::cos(yaw), libm::sin(yaw)]);
        if length <= 1.0 || !self.index.clear(&fp, BUILDING_CLEARANCE - 1.0) {
            return;
        }
        let height = self.rng.range(0.8, 1.8);
        let (cs, sn) = (libm::cos(yaw), libm::sin(yaw));
        let mut u = -0.5 * length;
        while u < 0.5 * length {
            let at = [c[0] + u * cs, c[1] + u * sn, 0.5 * height];
            self.foliage(at, [0.6, 0.6, 0.5 * height], 3);
            u += 1.0;
        }
    }

    /// `n` clumps of leaves (spheres of 0.2 m to [`CLUMP_MAX`]) uniformly inside the ellipsoid of semi-axes
    /// `axes` around `centre`.
    fn foliage(&mut self, centre: [f64; 3], axes: [f64; 3], n: usize) {
        let mut placed = 0;
        while placed < n {
            let u = [
                self.rng.range(-1.0, 1.0),
                self.rng.range(-1.0, 1.0),
                self.rng.range(-1.0, 1.0),
            ];
            if u[0] * u[0] + u[1] * u[1] + u[2] * u[2] > 1.0 {
                continue;
            }
            let radius = self.rng.range(0.2, CLUMP_MAX);
            self.solids.push(Solid {
                shape: Shape::Sphere {
                    centre: Point3::new(
                        centre[0] + u[0] * axes[0],
                        centre[1] + u[1] * axes[1],
                        (centre[2] + u[2] * axes[2]).max(radius),
                    ),
                    radius,
                },
                reflectivity: 0.3,
            });
            placed += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::build;
    use super::super::streets::{Footprint, RouteIndex};
    use crate::profile::Profile;
    use crate::trajectory::Trajectory;

    #[test]
    fn suburbs_have_houses_out_to_a_hundred_metres_clear_of_the_route() {
        for seed in 0..2 {
            let tr = Trajectory::generate(Profile::Suburban, seed, 60.0);
            let scene = build(Profile::Suburban, seed, tr.route());
            let index = RouteIndex::new(tr.route());
            let (s0, s1) = tr.route().knot_span();
            let samples: Vec<[f64; 2]> = (0..((s1 - s0) / 2.0) as usize)
                .map(|i| tr.route().position(s0 + 2.0 * i as f64))
                .collect();
            let (mut near, mut far) = (0, 0);
            for solid in scene.solids() {
                let fp = Footprint::of(&solid.shape);
                assert!(index.clear(&fp, 2.9), "{solid:?} is on the route");
                let (c, _) = fp.centre_radius();
                // Lateral distance from the route: to the nearest route sample.
                let d = samples
                    .iter()
                    .map(|p| (p[0] - c[0]).hypot(p[1] - c[1]))
                    .fold(f64::MAX, f64::min);
                if d < 30.0 {
                    near += 1;
                } else if d > 70.0 {
                    far += 1;
                }
            }
            println!(
                "seed {seed}: {} solids, {near} within 30 m of the route, {far} beyond 70 m",
                scene.solids().len()
            );
            assert!(near > 200 && far > 100, "{near} near, {far} far");
        }
    }
}
