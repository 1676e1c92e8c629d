//! The scenes of each profile. `urban` and `fast` are procedurally generated along the route:
//! street fronts of buildings with gaps (and a sparser second row behind), parked cars, lamp
//! posts and trees on both sides, every object kept clear of the whole route so that the path
//! never runs into one (even where the route crosses itself). `corridor` is an infinite tunnel
//! along the x axis (floor, walls, ceiling: nothing varies along the axis) and `plane` a lone
//! ground plane; both are degenerate on purpose. `tunnel` and `field` add sparse structure to
//! them (see `sparse`): weakly observable, as real tunnels and fields are. `suburban` lines long
//! streets with rows of houses, yards and trees out to 100 m (see `suburb`).

use crate::profile::Profile;
use crate::scene::Scene;
use crate::shapes::Plane;
use crate::trajectory::Route;
use nalgebra::{Point3, Vector3};
use sparse::{CORRIDOR_HALF_WIDTH, CORRIDOR_HEIGHT};
use streets::{City, GROUND};

mod sparse;
mod streets;
mod suburb;

/// Builds the scene of `profile` around `route`.
pub fn build(profile: Profile, seed: u64, route: &Route) -> Scene {
    let ground = (Plane::new(Vector3::z(), Point3::origin()), GROUND);
    let w = CORRIDOR_HALF_WIDTH;
    let corridor = vec![
        ground,
        (
            Plane::new(Vector3::z(), Point3::new(0.0, 0.0, CORRIDOR_HEIGHT)),
            0.35,
        ),
        (Plane::new(Vector3::y(), Point3::new(0.0, w, 0.0)), 0.45),
        (Plane::new(Vector3::y(), Point3::new(0.0, -w, 0.0)), 0.45),
    ];
    match profile {
        Profile::Plane => Scene::new(vec![ground], Vec::new()),
        Profile::Field => Scene::new(vec![ground], City::new(route, seed).field()),
        Profile::Corridor => Scene::new(corridor, Vec::new()),
        Profile::Tunnel => Scene::new(corridor, City::new(route, seed).tunnel()),
        Profile::Urban | Profile::Fast | Profile::Handheld | Profile::Drone => {
            Scene::new(vec![ground], City::new(route, seed).generate())
        }
        Profile::Suburban => Scene::new(vec![ground], City::new(route, seed).suburb()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::Shape;
    use crate::trajectory::Trajectory;
    use streets::{Footprint, RouteIndex};

    #[test]
    fn no_solid_stands_on_the_route() {
        // Every solid's footprint keeps clear of the driven path at sensor height, including
        // where the route crosses itself: a sensor riding it never starts inside an object.
        for seed in 0..3 {
            let tr = Trajectory::generate(Profile::Urban, seed, 300.0);
            let scene = build(Profile::Urban, seed, tr.route());
            let index = RouteIndex::new(tr.route());
            let mut low = 0;
            for solid in scene.solids() {
                // Objects entirely above 4 m (lamp arms, canopies) may overhang the road.
                let bottom = match solid.shape {
                    Shape::Box { centre, half, .. } => centre.z - half.z,
                    Shape::Cylinder { z, .. } => z[0],
                    Shape::Sphere { centre, radius } => centre.z - radius,
                };
                if bottom > 4.0 {
                    continue;
                }
                low += 1;
                let exact = Footprint::of(&solid.shape);
                assert!(index.clear(&exact, 2.9), "solid {solid:?} is on the route");
            }
            println!(
                "seed {seed}: {} solids, {low} near the ground, all clear",
                scene.solids().len()
            );
            assert!(low > 500, "a 3 km urban route should be lined with objects");
        }
    }

    #[test]
    fn corridor_has_only_axis_parallel_planes() {
        let tr = Trajectory::generate(Profile::Corridor, 0, 10.0);
        let scene = build(Profile::Corridor, 0, tr.route());
        assert!(scene.solids().is_empty());
        for p in scene.planes() {
            assert_eq!(p.normal.x, 0.0);
        }
    }
}
