//! The scenes of each profile. `urban` and `fast` are procedurally generated along the route:
//! street fronts of buildings with gaps (and a sparser second row behind), parked cars, lamp
//! posts and trees on both sides, every object kept clear of the whole route so that the path
//! never runs into one (even where the route crosses itself). `corridor` is an infinite tunnel
//! along the x axis (floor, walls, ceiling: nothing varies along the axis) and `plane` a lone
//! ground plane; both are degenerate on purpose. `tunnel` and `field` add sparse structure to
//! them (see `sparse`): weakly observable, as real tunnels and fields are. `suburban` lines long
//! streets with rows of houses, yards and trees out to 100 m (see `suburb`), `forest` a road
//! through woods, hillsides and overpasses (see `forest`), `warehouse` aisles between rows of
//! racks under a ceiling (see `warehouse`). Objects are kept as [`Group`]s, which
//! a revisit moves, turns or removes ([`changes`]).

use crate::profile::Profile;
use crate::scene::Scene;
use crate::scene::Solid;
use crate::shapes::Plane;
use crate::trajectory::Route;
use nalgebra::{Point3, Vector3};
use sparse::{CORRIDOR_HALF_WIDTH, CORRIDOR_HEIGHT};
use streets::{City, GROUND};
pub use streets::{Group, GroupKind};

pub mod changes;
mod forest;
mod sparse;
mod streets;
mod suburb;
mod warehouse;

/// A scene before it is indexed: its planes, its solids and the objects they make.
#[derive(Clone, Debug)]
pub struct Layout {
    /// Infinite planes and their reflectivity.
    pub planes: Vec<(Plane, f32)>,
    /// The solids.
    pub solids: Vec<Solid>,
    /// The objects (consecutive solids) a revisit may change; solids in none stay as they are.
    pub groups: Vec<Group>,
}

impl Layout {
    /// The indexed scene.
    pub fn scene(self) -> Scene {
        Scene::new(self.planes, self.solids)
    }
}

/// Builds the scene of `profile` around `route`.
pub fn build(profile: Profile, seed: u64, route: &Route) -> Scene {
    layout(profile, seed, route).scene()
}

/// The planes, solids and objects of `profile`'s scene around `route`.
pub fn layout(profile: Profile, seed: u64, route: &Route) -> Layout {
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
    let ceiling = (
        Plane::new(Vector3::z(), Point3::new(0.0, 0.0, warehouse::CEILING)),
        0.35,
    );
    let city = City::new(route, seed);
    let (planes, (solids, groups)) = match profile {
        Profile::Plane => (vec![ground], (Vec::new(), Vec::new())),
        Profile::Field => (vec![ground], city.field()),
        Profile::Corridor => (corridor, (Vec::new(), Vec::new())),
        Profile::Tunnel => (corridor, city.tunnel()),
        Profile::Urban | Profile::Fast | Profile::Handheld | Profile::Drone => {
            (vec![ground], city.generate())
        }
        Profile::Suburban => (vec![ground], city.suburb()),
        Profile::Forest => (vec![ground], city.forest()),
        Profile::Warehouse => (vec![ground, ceiling], city.warehouse()),
    };
    Layout {
        planes,
        solids,
        groups,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
                if solid.shape.heights()[0] > 4.0 {
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
