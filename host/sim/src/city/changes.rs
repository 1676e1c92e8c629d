//! What a revisit finds changed in a scene: a share of its objects ([`Group`]s, parked cars
//! first, then structures) moved 2-6 m along their own long axis (a round one in a random
//! direction), turned by 10-30 degrees about their body's centre, or removed, and a new wall
//! (10 m long, 3 m high) beside the stretch the revisit drives. Every draw comes from the
//! seed's [`Purpose::Changes`] stream, so a revisit's scene is a function of the seed and the
//! share only. A moved or turned object that would come within `lateral + 0.9` m of the route
//! (the revisit drives `lateral` from it) is moved without turning, else removed; so the
//! revisit's sensor never starts inside an object.

use super::streets::{Footprint, RouteIndex};
use super::{Group, GroupKind, Layout};
use crate::profile::Profile;
use crate::rng::{Purpose, Stream};
use crate::scene::Solid;
use crate::shapes::Shape;
use crate::trajectory::Route;
use nalgebra::{Point3, Vector3};

/// Share of the parked cars a revisit always finds moved or gone, whatever share is asked for.
pub const CAR_SHARE: f64 = 0.1;
/// The new wall: length, thickness and height (m).
const WALL: [f64; 3] = [10.0, 0.3, 3.0];
/// Objects whose bottom is above this (m) may overhang the route (lamp arms, crowns).
const OVERHEAD: f64 = 4.0;

/// What happened to an object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Change {
    /// Moved this far (m) along its long axis.
    Moved(f64),
    /// Turned by this angle (rad) about its body's centre.
    Turned(f64),
    /// Gone.
    Removed,
}

/// A revisit's scene: the first run's solids as changed, and the record of what changed.
#[derive(Clone, Debug)]
pub struct Changed {
    /// The solids of the revisit's scene: the unchanged ones in their first-run order, the
    /// moved and turned ones in their place, without the removed ones, the new wall last.
    pub solids: Vec<Solid>,
    /// For each solid of [`Self::solids`], the index of the first run's solid it is unchanged
    /// from (`None`: moved, turned or new).
    pub origin: Vec<Option<usize>>,
    /// For each changed object (an index into the first run's [`Layout::groups`]), its change.
    pub changes: Vec<(usize, Change)>,
    /// Objects in the first run's scene that a revisit may change.
    pub groups: usize,
    /// Whether the new wall found a place beside the revisit's stretch.
    pub wall: bool,
}

impl Changed {
    /// How many objects had `f` happen to them.
    pub fn count(&self, f: impl Fn(&Change) -> bool) -> usize {
        self.changes.iter().filter(|(_, c)| f(c)).count()
    }
}

/// Where the revisit drives: `lateral` (m) left of the route, over its arc lengths `span`.
#[derive(Clone, Copy, Debug)]
pub struct Lane {
    /// Offset from the route's centre line, positive left (m).
    pub lateral: f64,
    /// The route's arc lengths the revisit covers, lowest first (m).
    pub span: (f64, f64),
}

/// The revisit's scene: `share` (in `0..=1`) of `layout`'s objects changed, at least
/// [`CAR_SHARE`] of its parked cars, and the new wall on the far side of the route from `lane`.
pub fn apply(
    layout: &Layout,
    profile: Profile,
    route: &Route,
    seed: u64,
    share: f64,
    lane: Lane,
) -> Changed {
    let index = RouteIndex::new(route);
    let min = lane.lateral.abs() + 0.9;
    let mut rng = Stream::new(seed, Purpose::Changes);
    let of_kind = |kind| -> Vec<usize> {
        (0..layout.groups.len())
            .filter(|&g| layout.groups[g].kind == kind)
            .collect()
    };
    let (mut cars, mut structures) = (of_kind(GroupKind::Car), of_kind(GroupKind::Structure));
    shuffle(&mut cars, &mut rng);
    shuffle(&mut structures, &mut rng);
    let total = layout.groups.len();
    let floor = (CAR_SHARE * cars.len() as f64).ceil() as usize;
    let n = ((share * total as f64).round() as usize)
        .max(floor)
        .min(total);
    let mut placed: Vec<Option<Solid>> = layout.solids.iter().copied().map(Some).collect();
    let mut changed = vec![false; layout.solids.len()];
    let mut changes = Vec::with_capacity(n);
    for &g in cars.iter().chain(&structures).take(n) {
        // Every draw is made whatever is chosen, so one object's fate moves no other's.
        let pick = rng.uniform();
        let along = rng.range(2.0, 6.0) * rng.sign();
        let angle = rng.range(10.0, 30.0).to_radians() * rng.sign();
        let heading = rng.range(0.0, core::f64::consts::TAU);
        let group = &layout.groups[g];
        let solids = &layout.solids[group.solids.clone()];
        // A round object (a pole, a tree, a boulder) turned about its axis is unchanged.
        let round = !matches!(solids[0].shape, Shape::Box { .. });
        let wanted = if pick < 0.2 {
            Change::Removed
        } else if pick < 0.65 || round {
            Change::Moved(along)
        } else {
            Change::Turned(angle)
        };
        let fallback = [wanted, Change::Moved(along), Change::Removed];
        let (change, moved) = fallback
            .into_iter()
            .find_map(|c| {
                if c == Change::Removed {
                    return Some((c, Vec::new()));
                }
                let moved = transform(solids, c, heading)?;
                let clear = moved.iter().all(|s| !low(s) || index.clear(&fp(s), min));
                clear.then_some((c, moved))
            })
            .unwrap_or((Change::Removed, Vec::new()));
        debug_assert!(change == Change::Removed || moved.len() == solids.len());
        for (k, i) in group.solids.clone().enumerate() {
            placed[i] = moved.get(k).copied();
            changed[i] = true;
        }
        changes.push((g, change));
    }
    let mut solids = Vec::with_capacity(layout.solids.len() + 1);
    let mut origin = Vec::with_capacity(layout.solids.len() + 1);
    for (i, s) in placed.into_iter().enumerate() {
        if let Some(s) = s {
            solids.push(s);
            origin.push((!changed[i]).then_some(i));
        }
    }
    let wall = new_wall(profile, route, &index, lane);
    if let Some(w) = wall {
        solids.push(w);
        origin.push(None);
    }
    changes.sort_by_key(|&(g, _)| g);
    Changed {
        solids,
        origin,
        changes,
        groups: total,
        wall: wall.is_some(),
    }
}

/// Fisher-Yates with the stream's draws.
fn shuffle(v: &mut [usize], rng: &mut Stream) {
    for i in (1..v.len()).rev() {
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        v.swap(i, j);
    }
}

fn low(s: &Solid) -> bool {
    s.shape.heights()[0] < OVERHEAD
}

fn fp(s: &Solid) -> Footprint {
    Footprint::of(&s.shape)
}

/// `solids` (an object, its body first) after `change`; `None` if removed. An object without a
/// long axis (a pole, a tree) moves along `heading` (rad).
fn transform(solids: &[Solid], change: Change, heading: f64) -> Option<Vec<Solid>> {
    let (pivot, axis) = match solids.first()?.shape {
        Shape::Box { centre, rot, .. } => ([centre.x, centre.y], rot),
        Shape::Cylinder { centre, .. } => (centre, [libm::cos(heading), libm::sin(heading)]),
        Shape::Sphere { centre, .. } | Shape::Foliage { centre, .. } => (
            [centre.x, centre.y],
            [libm::cos(heading), libm::sin(heading)],
        ),
    };
    let (turn, shift) = match change {
        Change::Removed => return None,
        Change::Moved(d) => ([1.0, 0.0], [d * axis[0], d * axis[1]]),
        Change::Turned(a) => ([libm::cos(a), libm::sin(a)], [0.0, 0.0]),
    };
    let map = |p: [f64; 2]| {
        let (dx, dy) = (p[0] - pivot[0], p[1] - pivot[1]);
        [
            pivot[0] + turn[0] * dx - turn[1] * dy + shift[0],
            pivot[1] + turn[1] * dx + turn[0] * dy + shift[1],
        ]
    };
    let moved = solids
        .iter()
        .map(|s| {
            let shape = match s.shape {
                Shape::Box {
                    centre,
                    half,
                    rot,
                    tilt,
                } => {
                    let c = map([centre.x, centre.y]);
                    Shape::Box {
                        centre: Point3::new(c[0], c[1], centre.z),
                        half,
                        tilt,
                        rot: [
                            rot[0] * turn[0] - rot[1] * turn[1],
                            rot[1] * turn[0] + rot[0] * turn[1],
                        ],
                    }
                }
                Shape::Cylinder { centre, radius, z } => Shape::Cylinder {
                    centre: map(centre),
                    radius,
                    z,
                },
                Shape::Sphere { centre, radius } => {
                    let c = map([centre.x, centre.y]);
                    Shape::Sphere {
                        centre: Point3::new(c[0], c[1], centre.z),
                        radius,
                    }
                }
                Shape::Foliage {
                    centre,
                    axes,
                    free_path,
                } => {
                    let c = map([centre.x, centre.y]);
                    Shape::Foliage {
                        centre: Point3::new(c[0], c[1], centre.z),
                        axes,
                        free_path,
                    }
                }
            };
            Solid { shape, ..*s }
        })
        .collect();
    Some(moved)
}

/// A wall on the far side of the route from the revisit's lane, near the middle of its
/// stretch, at the first place (8 m steps either way) where it keeps clear of the route.
fn new_wall(profile: Profile, route: &Route, index: &RouteIndex, lane: Lane) -> Option<Solid> {
    // Centre line's distance from the route and the clearance its face keeps (m).
    let (off, clearance) = match profile {
        Profile::Warehouse => (1.15, 0.95),
        Profile::Corridor | Profile::Tunnel => (3.0, 2.5),
        _ => (5.5, 5.0),
    };
    let lateral = -lane.lateral.signum() * off;
    let mid = 0.5 * (lane.span.0 + lane.span.1);
    (0..21)
        .map(|j| mid + 8.0 * if j % 2 == 0 { j / 2 } else { -(j + 1) / 2 } as f64)
        .filter(|s| (lane.span.0..=lane.span.1).contains(s))
        .find_map(|s| {
            let p = route.position(s);
            let psi = route.heading(s);
            let (sn, cs) = (libm::sin(psi), libm::cos(psi));
            let c = [p[0] - sn * lateral, p[1] + cs * lateral];
            let half = Vector3::new(0.5 * WALL[0], 0.5 * WALL[1], 0.5 * WALL[2]);
            let wall = Solid {
                shape: Shape::yawed_box(Point3::new(c[0], c[1], half.z), half, psi),
                reflectivity: 0.5,
            };
            index.clear(&fp(&wall), clearance).then_some(wall)
        })
}

/// The objects of `groups` of `kind`.
pub fn count(groups: &[Group], kind: GroupKind) -> usize {
    groups.iter().filter(|g| g.kind == kind).count()
}
