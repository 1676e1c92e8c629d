//! The forest scene: a road through dense woodland out past 100 m on both sides, the ground
//! rising beside it in hillsides up to plateaus, and overpasses crossing it on piers, their
//! ramps sloping down to the ground. Crowns and shrubs are foliage volumes ([`Shape::Foliage`])
//! that a ray stops in at a random depth or passes through, so a sensor fills voxels in depth
//! throughout its `r_max` ball: far more of them than streets or suburbs give, as real drives
//! through woods, cuttings and interchanges do.

use super::streets::{
    City, Footprint, Group, BUILDING_CLEARANCE, CANOPY_CLEARANCE, POLE_CLEARANCE,
};
use crate::scene::Solid;
use crate::shapes::Shape;
use core::f64::consts::FRAC_PI_2;
use nalgebra::{Point3, Vector3};

/// Trees stand from [`WOOD_EDGE`] to [`WOOD_DEPTH`] metres either side of the route.
const WOOD_EDGE: f64 = 5.0;
const WOOD_DEPTH: f64 = 115.0;
/// Length (m) of one slab of a hillside: a curving route is followed in straight pieces.
const SLAB: f64 = 20.0;
/// Thickness (m) of slopes and decks.
const THICK: f64 = 1.2;
/// Headroom (m) under an overpass's deck: above anything a car carries.
const HEADROOM: [f64; 2] = [5.5, 7.5];

/// A stretch of rising ground on one side of the route: from arc length `s[0]` to `s[1]`, its
/// foot `foot` metres out, climbing at `grade` (rise over run) for `run` metres to a plateau.
#[derive(Clone, Copy, Debug)]
struct Hillside {
    s: [f64; 2],
    foot: f64,
    run: f64,
    grade: f64,
}

impl Hillside {
    /// Ground height `lateral` metres out (on the hillside's side) at arc length `s`, if the
    /// hillside covers it.
    fn height(&self, s: f64, lateral: f64) -> Option<f64> {
        if s < self.s[0] || s > self.s[1] || lateral < self.foot {
            return None;
        }
        Some(self.grade * (lateral - self.foot).min(self.run))
    }
}

impl City<'_> {
    /// Woods, hillsides and overpasses along the whole route.
    pub(super) fn forest(mut self) -> (Vec<Solid>, Vec<Group>) {
        let (s0, s1) = self.route.knot_span();
        let bridges = self.overpasses(s0, s1);
        for side in [1.0, -1.0] {
            let hills = self.hillsides(s0, s1, side);
            self.woods(s0, s1, side, &hills, &bridges);
        }
        self.finish()
    }

    /// Overpasses every 300-900 m: a deck 60-100 m long across the route, its piers and a ramp
    /// at each end. Returns the footprints trees keep out of.
    fn overpasses(&mut self, s0: f64, s1: f64) -> Vec<Footprint> {
        let mut keep_out = Vec::new();
        let mut s = s0 + self.rng.range(150.0, 400.0);
        while s < s1 {
            let (c, psi) = self.offset(s, 0.0);
            let (half_len, half_w) = (self.rng.range(30.0, 50.0), self.rng.range(4.0, 6.0));
            let under = self.rng.range(HEADROOM[0], HEADROOM[1]);
            let top = under + THICK;
            let ramp = self.rng.range(35.0, 60.0);
            s += self.rng.range(300.0, 900.0);
            let across = psi + FRAC_PI_2;
            let (ux, uy) = (libm::cos(across), libm::sin(across));
            self.add_box(
                c,
                across,
                [half_len, half_w, 0.5 * THICK],
                under,
                0.25,
                None,
            );
            // Piers in pairs under the deck, beside the road and every 12 m out from it.
            let mut out = 7.0;
            while out < half_len - 2.0 {
                for sign in [1.0, -1.0] {
                    let at = [c[0] + sign * out * ux, c[1] + sign * out * uy];
                    let half = [0.5, half_w - 0.8, 0.5 * under];
                    self.add_box(at, across, half, 0.0, 0.35, Some(POLE_CLEARANCE));
                }
                out += 12.0;
            }
            for sign in [1.0, -1.0] {
                let end = [c[0] + sign * half_len * ux, c[1] + sign * half_len * uy];
                let foot = [end[0] + sign * ramp * ux, end[1] + sign * ramp * uy];
                let rises = if sign > 0.0 {
                    across + core::f64::consts::PI
                } else {
                    across
                };
                self.add_slope(foot, rises, ramp, top, half_w, 0.25);
            }
            let reach = half_len + ramp;
            keep_out.push(Footprint::Rect(c, [reach, half_w + 1.0], [ux, uy]));
        }
        keep_out
    }

    /// Hillsides along most of the route on `side` (a valley): their foot 8-16 m out, climbing
    /// at 10-28 degrees for 20-100 m, to a plateau where they stop short of the woods' depth.
    /// The trees on them stand in tiers, each seen above the ones in front of it.
    fn hillsides(&mut self, s0: f64, s1: f64, side: f64) -> Vec<Hillside> {
        let mut hills = Vec::new();
        let mut s = s0 + self.rng.range(0.0, 100.0);
        while s < s1 {
            let length = self.rng.range(200.0, 600.0);
            let hill = Hillside {
                s: [s, s + length],
                foot: self.rng.range(8.0, 16.0),
                run: self.rng.range(20.0, 100.0),
                grade: libm::tan(self.rng.range(10f64, 28.0).to_radians()),
            };
            s += length + self.rng.range(30.0, 150.0);
            let rise = hill.grade * hill.run;
            // One metre longer than the step, so a bend leaves no gap between slabs.
            let half = 0.5 * SLAB + 1.0;
            let plateau = 0.5 * (WOOD_DEPTH + 5.0 - hill.foot - hill.run);
            let mut a = hill.s[0];
            let mut placed = false;
            while a < hill.s[1] {
                let mid = a + 0.5 * SLAB;
                let (foot, psi) = self.offset(mid, side * hill.foot);
                let rises = psi + side * FRAC_PI_2;
                placed |= self.add_slope(foot, rises, hill.run, rise, half, 0.3);
                if plateau > 0.0 {
                    let (c, _) = self.offset(mid, side * (hill.foot + hill.run + plateau));
                    let top = [half, plateau, 0.5 * rise];
                    placed |= self.add_box(c, psi, top, 0.0, 0.3, Some(BUILDING_CLEARANCE));
                }
                a += SLAB;
            }
            if placed {
                hills.push(hill);
            }
        }
        hills
    }

    /// Adds a slope rising from `foot` towards the horizontal direction `rises` (rad) by `rise`
    /// over `run` metres, `half_width` either side, if it keeps clear of the route.
    fn add_slope(
        &mut self,
        foot: [f64; 2],
        rises: f64,
        run: f64,
        rise: f64,
        half_width: f64,
        reflectivity: f32,
    ) -> bool {
        let tilt = libm::atan2(rise, run);
        let (st, ct) = (libm::sin(tilt), libm::cos(tilt));
        let half = Vector3::new(half_width, 0.5 * run / ct, 0.5 * THICK);
        // The top face's centre, then back along its normal by half the thickness.
        let along = 0.5 * run + half.z * st;
        let (dx, dy) = (libm::cos(rises), libm::sin(rises));
        let centre = Point3::new(
            foot[0] + along * dx,
            foot[1] + along * dy,
            0.5 * rise - half.z * ct,
        );
        let shape = Shape::tilted_box(centre, half, rises - FRAC_PI_2, tilt);
        if !self.index.clear(&Footprint::of(&shape), BUILDING_CLEARANCE) {
            return false;
        }
        self.solids.push(Solid {
            shape,
            reflectivity,
        });
        true
    }

    /// Trees from [`WOOD_EDGE`] to [`WOOD_DEPTH`] metres out on `side`, about one per 20 m^2
    /// (three in five of them tall) with shrubs under them, standing on the hillsides where
    /// there are some and out of the overpasses. Crowns and shrubs are foliage volumes.
    fn woods(&mut self, s0: f64, s1: f64, side: f64, hills: &[Hillside], bridges: &[Footprint]) {
        let mut s = s0;
        while s < s1 {
            s += self.rng.range(0.03, 0.2);
            let lateral = self.rng.range(WOOD_EDGE, WOOD_DEPTH);
            let (shrub, tall) = (self.rng.chance(0.3), self.rng.chance(0.6));
            // Tall trees hold the canopy up at 5-25 m; young ones and shrubs fill below it.
            let (trunk_r, trunk_h, crown) = if shrub {
                (
                    0.0,
                    0.0,
                    [self.rng.range(0.6, 1.8), self.rng.range(0.4, 1.0)],
                )
            } else if tall {
                let r = self.rng.range(3.0, 5.5);
                let t = self.rng.range(3.0, 8.0);
                (
                    self.rng.range(0.15, 0.45),
                    t,
                    [r, r * self.rng.range(1.5, 2.8)],
                )
            } else {
                let r = self.rng.range(0.8, 2.0);
                (
                    self.rng.range(0.05, 0.15),
                    self.rng.range(0.3, 2.0),
                    [r, r * 1.2],
                )
            };
            let free_path = self.rng.range(6.0, 20.0);
            let (c, _) = self.offset(s, side * lateral);
            let reach = crown[0];
            let clear = bridges.iter().all(|b| b.distance(c) > reach + 1.0)
                && self
                    .index
                    .clear(&Footprint::Disc(c, reach), CANOPY_CLEARANCE);
            if !clear {
                continue;
            }
            let base = hills
                .iter()
                .find_map(|h| h.height(s, lateral))
                .unwrap_or(0.0);
            if trunk_h > 0.0 {
                self.solids.push(Solid {
                    shape: Shape::Cylinder {
                        centre: c,
                        radius: trunk_r,
                        z: [base, base + trunk_h + crown[1]],
                    },
                    reflectivity: 0.15,
                });
            }
            self.solids.push(Solid {
                shape: Shape::Foliage {
                    centre: Point3::new(c[0], c[1], base + trunk_h + crown[1]),
                    axes: Vector3::new(crown[0], crown[0], crown[1]),
                    free_path,
                },
                reflectivity: 0.3,
            });
        }
    }
}
#[cfg(test)]
mod tests {
    use super::super::build;
    use super::super::streets::{Footprint, RouteIndex};
    use crate::profile::Profile;
    use crate::shapes::Shape;
    use crate::trajectory::Trajectory;

    #[test]
    fn a_forest_has_woods_slopes_and_overpasses_and_keeps_the_road_clear() {
        for seed in 0..2 {
            let tr = Trajectory::generate(Profile::Forest, seed, 90.0);
            let scene = build(Profile::Forest, seed, tr.route());
            let index = RouteIndex::new(tr.route());
            let (mut slopes, mut decks, mut crowns) = (0, 0, 0);
            for solid in scene.solids() {
                let [bottom, _] = solid.shape.heights();
                match solid.shape {
                    Shape::Box { tilt, .. } if tilt[1] != 0.0 => slopes += 1,
                    Shape::Box { .. } if bottom > 4.0 => decks += 1,
                    Shape::Foliage { .. } => crowns += 1,
                    _ => {}
                }
                // Only a deck spans the road, with a lorry's headroom under it; everything
                // else (trunks, crowns, piers, ramps, hillsides) keeps clear of it.
                let deck = matches!(solid.shape, Shape::Box { tilt, .. } if tilt[1] == 0.0)
                    && bottom > 4.0
                    && bottom < 10.0;
                if deck {
                    assert!(bottom >= super::HEADROOM[0], "{solid:?}");
                } else {
                    let fp = Footprint::of(&solid.shape);
                    assert!(index.clear(&fp, 2.9), "{solid:?} is on the route");
                }
            }
            println!(
                "seed {seed}: {} solids, {slopes} slopes, {decks} decks, {crowns} crowns",
                scene.solids().len()
            );
            assert!(
                slopes > 20 && decks >= 1 && crowns > 10_000,
                "{slopes} {decks} {crowns}"
            );
        }
    }
}
