//! The warehouse scene: a flat floor under a ceiling, and long rows of pallet racks lining
//! aisles 3-4 m wide along the route, back to back with the racks of the next aisle, out to
//! about 15 m on both sides. Cross aisles every 20-40 m cut every row at once, so the sensor
//! sees down them; racks are runs of 6-20 m, 3-6 m tall, with small gaps between runs. Every
//! rack keeps clear of the whole route (which turns at right angles and may cross itself).

use super::streets::{City, Group, GroupKind};
use crate::scene::Solid;

/// Ceiling height (m).
pub(super) const CEILING: f64 = 8.0;
/// Rack depth (m).
const RACK_DEPTH: f64 = 1.2;
/// Clearance of a rack from the route (m): the narrowest aisle's half width, less a margin.
pub(super) const RACK_CLEARANCE: f64 = 1.4;
/// Rack rows on each side: the aisle's own and two more aisles beyond.
const ROWS: usize = 3;

impl City<'_> {
    /// Rows of racks along the whole route, both sides.
    pub(super) fn warehouse(mut self) -> (Vec<Solid>, Vec<Group>) {
        let (s0, s1) = self.route.knot_span();
        let half_aisle = 0.5 * self.rng.range(3.0, 4.0);
        // Cross aisles cut every row, on both sides, at the same places.
        let mut crosses = Vec::new();
        let mut s = s0 + self.rng.range(10.0, 40.0);
        while s < s1 {
            let width = self.rng.range(3.0, 4.0);
            crosses.push((s, s + width));
            s += width + self.rng.range(20.0, 40.0);
        }
        for side in [1.0, -1.0] {
            let mut face = half_aisle;
            for _ in 0..ROWS {
                // A back-to-back pair of racks, then the next aisle.
                for lateral in [face, face + RACK_DEPTH] {
                    self.rack_row(s0, s1, side * (lateral + 0.5 * RACK_DEPTH), &crosses);
                }
                face += 2.0 * RACK_DEPTH + 2.0 * half_aisle;
            }
        }
        self.finish()
    }

    /// One row of racks whose centre line runs `lateral` from the route (positive left).
    fn rack_row(&mut self, s0: f64, s1: f64, lateral: f64, crosses: &[(f64, f64)]) {
        let mut s = s0;
        let mut next = 0;
        while s < s1 {
            let (cross_start, cross_end) = crosses.get(next).copied().unwrap_or((s1, s1));
            if s >= cross_start {
                s = s.max(cross_end);
                next += 1;
                continue;
            }
            let run = self.rng.range(6.0, 20.0).min(cross_start - s);
            let height = self.rng.range(3.0, 6.0);
            let refl = self.rng.range(0.3, 0.6);
            let gap = self.rng.range(0.2, 1.0);
            if run > 1.5 {
                let (c, yaw) = self.offset(s + 0.5 * run, lateral);
                let half = [0.5 * run, 0.5 * RACK_DEPTH, 0.5 * height];
                let start = self.solids.len();
                self.add_box(c, yaw, half, 0.0, refl, Some(RACK_CLEARANCE));
                self.group(GroupKind::Structure, start);
            }
            s += run + gap;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::build;
    use super::super::streets::{Footprint, RouteIndex};
    use super::*;
    use crate::profile::Profile;
    use crate::shapes::Shape;
    use crate::trajectory::Trajectory;

    #[test]
    fn warehouse_aisles_are_lined_with_racks_clear_of_the_route_under_a_ceiling() {
        for seed in 0..3 {
            let tr = Trajectory::generate(Profile::Warehouse, seed, 120.0);
            let scene = build(Profile::Warehouse, seed, tr.route());
            assert_eq!(scene.planes().count(), 2);
            let index = RouteIndex::new(tr.route());
            let (s0, s1) = tr.route().knot_span();
            let mut near = 0;
            for solid in scene.solids() {
                let Shape::Box { centre, half, .. } = solid.shape else {
                    panic!("racks are boxes: {solid:?}");
                };
                assert!((0.6..=0.6 + 1e-12).contains(&half.y));
                assert!(2.0 * half.z >= 3.0 && 2.0 * half.z <= 6.0 && centre.z == half.z);
                let fp = Footprint::of(&solid.shape);
                assert!(
                    index.clear(&fp, RACK_CLEARANCE),
                    "{solid:?} is on the route"
                );
                near += usize::from(!index.clear(&fp, 2.1));
            }
            // Racks line both sides of the aisle: about 2 x 0.85 m of rack per route metre.
            let per_m = near as f64 / (s1 - s0);
            println!(
                "seed {seed}: {} racks, {near} lining the aisle ({per_m:.3}/m)",
                scene.solids().len()
            );
            assert!(per_m > 0.1, "{per_m}");
        }
    }
}
