//! Sparse structure for the weakly observable profiles. `tunnel` puts pillars, door frames and
//! cabinets on the corridor's walls every 10-40 m; `field` puts poles, trees and boulders
//! 20-60 m apart along the route, 5-30 m to either side. Between them the scene is the
//! degenerate corridor or plane, so registration has a little information along the free
//! directions, not none: what robust mode is measured on.

use super::streets::{City, Footprint, Group, GroupKind};
use crate::scene::Solid;
use crate::shapes::Shape;

/// Corridor half width (m): walls at `y = +-CORRIDOR_HALF_WIDTH`.
pub(super) const CORRIDOR_HALF_WIDTH: f64 = 4.5;
/// Corridor ceiling height (m).
pub(super) const CORRIDOR_HEIGHT: f64 = 5.5;

use nalgebra::Point3;

/// Clearance of tunnel structure from the route (m); the walls are 4.5 m from the axis and
/// structure stands at most 0.8 m proud of them.
const TUNNEL_CLEARANCE: f64 = 2.5;
/// Clearance of a boulder from the route (m).
const BOULDER_CLEARANCE: f64 = 4.0;

impl City<'_> {
    /// Structure on the corridor's walls along the route (which follows the corridor's axis).
    pub(super) fn tunnel(mut self) -> (Vec<Solid>, Vec<Group>) {
        let (s0, s1) = self.route.knot_span();
        let (x0, x1) = (self.route.position(s0)[0], self.route.position(s1)[0]);
        let mut x = x0 + self.rng.range(10.0, 40.0);
        while x < x1 {
            let side = self.rng.sign();
            let kind = self.rng.next_u64() % 3;
            let depth = self.rng.range(0.3, 0.8);
            let (width, height) = (self.rng.range(0.4, 2.5), self.rng.range(1.0, 3.0));
            let refl = self.rng.range(0.3, 0.6);
            // From `depth` proud of the wall to 0.1 m into it, so no face lies in its plane.
            let y = side * (CORRIDOR_HALF_WIDTH + 0.05 - 0.5 * depth);
            let half_y = 0.5 * depth + 0.05;
            let clear = Some(TUNNEL_CLEARANCE);
            let start = self.solids.len();
            match kind {
                0 => {
                    // A pillar, floor to ceiling.
                    let half = [0.25 * width, half_y, 0.5 * CORRIDOR_HEIGHT];
                    self.add_box([x, y], 0.0, half, 0.0, refl, clear);
                }
                1 => {
                    // A door frame: two jambs and a lintel, 2-3 m high.
                    let h = 2.0 + 0.5 * height;
                    for u in [-0.5 * width, 0.5 * width] {
                        self.add_box([x + u, y], 0.0, [0.1, half_y, 0.5 * h], 0.0, refl, clear);
                    }
                    let lintel = [0.5 * width + 0.1, half_y, 0.15];
                    self.add_box([x, y], 0.0, lintel, h, refl, clear);
                }
                _ => {
                    // A cabinet or a niche's fill, 1-3 m high.
                    let half = [0.5 * width, half_y, 0.5 * height];
                    self.add_box([x, y], 0.0, half, 0.0, refl, clear);
                }
            }
            self.group(GroupKind::Structure, start);
            x += self.rng.range(10.0, 40.0);
        }
        self.finish()
    }

    /// Objects scattered along the route, clear of it everywhere (it may cross itself).
    pub(super) fn field(mut self) -> (Vec<Solid>, Vec<Group>) {
        let (s0, s1) = self.route.knot_span();
        let mut s = s0 + self.rng.range(20.0, 60.0);
        while s < s1 {
            let lateral = self.rng.sign() * self.rng.range(5.0, 30.0);
            let kind = self.rng.next_u64() % 3;
            let size = self.rng.range(0.0, 1.0);
            let (c, _) = self.offset(s, lateral);
            let start = self.solids.len();
            match kind {
                0 => {
                    self.pole(c, 0.1 + 0.1 * size, 4.0 + 4.0 * size);
                }
                1 => self.tree(c, [0.15 + 0.15 * size, 2.5 + 1.5 * size], 1.5 + 1.5 * size),
                _ => {
                    let r = 0.5 + size;
                    if self.index.clear(&Footprint::Disc(c, r), BOULDER_CLEARANCE) {
                        self.solids.push(Solid {
                            shape: Shape::Sphere {
                                centre: Point3::new(c[0], c[1], 0.6 * r),
                                radius: r,
                            },
                            reflectivity: 0.25,
                        });
                    }
                }
            }
            self.group(GroupKind::Structure, start);
            s += self.rng.range(20.0, 60.0);
        }
        self.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::super::build;
    use super::super::streets::RouteIndex;
    use super::*;
    use crate::profile::Profile;
    use crate::scene::Scene;
    use crate::trajectory::Trajectory;

    /// The centre of a solid's footprint.
    fn centre(solid: &Solid) -> [f64; 2] {
        match Footprint::of(&solid.shape) {
            Footprint::Rect(c, ..) | Footprint::Disc(c, _) => c,
        }
    }

    /// The scene of a minute of `profile` under `seed`, its planes counted and every solid
    /// checked `clearance` from the route; and the route's length.
    fn scene(profile: Profile, seed: u64, planes: usize, clearance: f64) -> (Scene, f64) {
        let tr = Trajectory::generate(profile, seed, 60.0);
        let (s0, s1) = tr.route().knot_span();
        let scene = build(profile, seed, tr.route());
        assert_eq!(scene.planes().count(), planes);
        let index = RouteIndex::new(tr.route());
        for solid in scene.solids() {
            let fp = Footprint::of(&solid.shape);
            assert!(index.clear(&fp, clearance), "{solid:?} is on the route");
        }
        (scene, s1 - s0)
    }

    #[test]
    fn tunnel_walls_carry_sparse_structure_clear_of_the_route() {
        for seed in 0..3 {
            let (scene, length) = scene(Profile::Tunnel, seed, 4, TUNNEL_CLEARANCE);
            for solid in scene.solids() {
                // Against a wall: its outer face is inside the wall, its inner one proud of it.
                let Shape::Box { centre, half, .. } = solid.shape else {
                    panic!("tunnel structure is boxes: {solid:?}");
                };
                let outer = centre.y.abs() + half.y;
                let inner = centre.y.abs() - half.y;
                assert!(outer > CORRIDOR_HALF_WIDTH && outer < CORRIDOR_HALF_WIDTH + 0.2);
                assert!(
                    inner > CORRIDOR_HALF_WIDTH - 0.85,
                    "{solid:?} stands too far out"
                );
            }
            // Groups (a door frame is three boxes) 10-40 m apart over the whole route.
            let mut x: Vec<f64> = scene.solids().iter().map(|s| centre(s)[0]).collect();
            x.sort_by(f64::total_cmp);
            let mut groups = vec![x[0]];
            for &xi in &x[1..] {
                if xi - groups.last().unwrap() > 3.0 {
                    groups.push(xi);
                }
            }
            let gaps: Vec<f64> = groups.windows(2).map(|w| w[1] - w[0]).collect();
            let (lo, hi) = gaps
                .iter()
                .fold((f64::MAX, 0.0f64), |(l, h), &g| (l.min(g), h.max(g)));
            println!(
                "seed {seed}: {} solids in {} groups, gaps {lo:.1}-{hi:.1} m",
                x.len(),
                groups.len()
            );
            assert!(
                groups.len() as f64 >= length / 41.0,
                "{} groups",
                groups.len()
            );
            assert!(lo > 7.0 && hi < 43.0, "gaps {lo:.1}-{hi:.1} m");
        }
    }

    #[test]
    fn field_objects_are_sparse_and_clear_of_the_route() {
        for seed in 0..3 {
            let (scene, length) = scene(Profile::Field, seed, 1, 2.9);
            // Trees are two solids (trunk and crown) on one footprint centre.
            let mut centres: Vec<[i64; 2]> = scene
                .solids()
                .iter()
                .map(|s| centre(s).map(|v| (v * 1e3) as i64))
                .collect();
            centres.sort_unstable();
            centres.dedup();
            let n = centres.len() as f64;
            println!("seed {seed}: {n} objects along {length:.0} m");
            // One per 20-60 m of route, less the few too close to where it turns back.
            assert!(n >= length / 80.0 && n <= length / 20.0 + 1.0);
        }
    }
}
