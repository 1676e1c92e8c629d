//! The world the sensor sees: infinite planes plus solids indexed by a uniform 2D grid.
//!
//! A ray first meets the planes (ground, corridor walls) in closed form, which bounds how far it
//! can travel; it then walks the grid cells its xy projection crosses (a 2D DDA) and tests only
//! the solids registered in them, stopping once the nearest hit lies before the cell's exit. Cost
//! per ray is therefore bounded by the cells within range, not by the length of the route.

use crate::shapes::{Plane, Shape};
use nalgebra::{Point3, Vector3};

/// Which surface a ray hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Surface {
    /// The plane of that index.
    Plane(u32),
    /// The solid of that index.
    Solid(u32),
}

/// A ray's nearest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Range along the unit ray (m).
    pub t: f64,
    /// Unit normal at the hit (either orientation).
    pub normal: Vector3<f64>,
    /// What was hit.
    pub surface: Surface,
    /// The surface's diffuse reflectivity in `[0, 1]`.
    pub reflectivity: f32,
}

/// A solid and how bright it looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solid {
    /// Geometry.
    pub shape: Shape,
    /// Diffuse reflectivity in `[0, 1]`.
    pub reflectivity: f32,
}

/// Grid cell edge (m): a few solids per cell, a few dozen cells per long ray.
const CELL: f64 = 8.0;
/// Cap on grid cells (memory): past it the cells grow instead.
const MAX_CELLS: f64 = 4.0e6;

/// Solids binned by the xy cells their footprints overlap (compressed rows).
#[derive(Clone, Debug, Default)]
struct Grid {
    origin: [f64; 2],
    cell: f64,
    nx: usize,
    ny: usize,
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Grid {
    fn build(solids: &[Solid]) -> Self {
        if solids.is_empty() {
            return Self::default();
        }
        let mut b = [f64::MAX, f64::MAX, f64::MIN, f64::MIN];
        for s in solids {
            let f = s.shape.footprint();
            b = [
                b[0].min(f[0]),
                b[1].min(f[1]),
                b[2].max(f[2]),
                b[3].max(f[3]),
            ];
        }
        let (w, h) = ((b[2] - b[0]).max(1.0), (b[3] - b[1]).max(1.0));
        let cell = CELL.max((w * h / MAX_CELLS).sqrt());
        let nx = (w / cell).floor() as usize + 1;
        let ny = (h / cell).floor() as usize + 1;
        let mut g = Self {
            origin: [b[0], b[1]],
            cell,
            nx,
            ny,
            start: vec![0; nx * ny + 1],
            items: Vec::new(),
        };
        // Two passes (count, then fill) keep insertion order: deterministic and cache-friendly.
        let mut counts = vec![0u32; nx * ny];
        for s in solids {
            g.for_cells(&s.shape.footprint(), |c| counts[c] += 1);
        }
        let mut acc = 0u32;
        for (c, n) in counts.iter().enumerate() {
            g.start[c] = acc;
            acc += n;
        }
        g.start[nx * ny] = acc;
        let mut items = vec![0; acc as usize];
        let mut fill: Vec<u32> = g.start[..nx * ny].to_vec();
        for (i, s) in solids.iter().enumerate() {
            g.for_cells(&s.shape.footprint(), |c| {
                items[fill[c] as usize] = i as u32;
                fill[c] += 1;
            });
        }
        g.items = items;
        g
    }

    fn index(&self, x: f64, axis: usize) -> usize {
        let n = if axis == 0 { self.nx } else { self.ny };
        let i = ((x - self.origin[axis]) / self.cell).floor();
        (i.max(0.0) as usize).min(n - 1)
    }

    fn for_cells(&self, f: &[f64; 4], mut visit: impl FnMut(usize)) {
        let (x0, x1) = (self.index(f[0], 0), self.index(f[2], 0));
        let (y0, y1) = (self.index(f[1], 1), self.index(f[3], 1));
        for iy in y0..=y1 {
            for ix in x0..=x1 {
                visit(iy * self.nx + ix);
            }
        }
    }

    fn cell_items(&self, ix: usize, iy: usize) -> &[u32] {
        let c = iy * self.nx + ix;
        &self.items[self.start[c] as usize..self.start[c + 1] as usize]
    }
}

/// Planes and indexed solids.
#[derive(Clone, Debug)]
pub struct Scene {
    planes: Vec<(Plane, f32)>,
    solids: Vec<Solid>,
    grid: Grid,
}

impl Scene {
    /// A scene of `planes` (with reflectivities) and `solids`.
    pub fn new(planes: Vec<(Plane, f32)>, solids: Vec<Solid>) -> Self {
        let grid = Grid::build(&solids);
        Self {
            planes,
            solids,
            grid,
        }
    }

    /// The solids.
    pub fn solids(&self) -> &[Solid] {
        &self.solids
    }

    /// The planes.
    pub fn planes(&self) -> impl Iterator<Item = &Plane> {
        self.planes.iter().map(|(p, _)| p)
    }

    /// Nearest hit of the ray `o + t d` (unit `d`) with `t < t_max`.
    pub fn cast(&self, o: &Point3<f64>, d: &Vector3<f64>, t_max: f64) -> Option<Hit> {
        let mut best = self.cast_planes(o, d, t_max);
        let limit = best.as_ref().map_or(t_max, |h| h.t);
        self.cast_solids(o, d, limit, &mut best);
        best
    }

    /// Nearest hit of the ray with a plane, `t < t_max` (closed form, no grid).
    fn cast_planes(&self, o: &Point3<f64>, d: &Vector3<f64>, t_max: f64) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut limit = t_max;
        for (i, (plane, refl)) in self.planes.iter().enumerate() {
            if let Some(h) = plane.hit(o, d, limit) {
                limit = h.t;
                best = Some(Hit {
                    t: h.t,
                    normal: h.normal,
                    surface: Surface::Plane(i as u32),
                    reflectivity: *refl,
                });
            }
        }
        best
    }

    /// Walks the grid along the ray's xy projection up to `limit`, improving `best`.
    fn cast_solids(
        &self,
        o: &Point3<f64>,
        d: &Vector3<f64>,
        mut limit: f64,
        best: &mut Option<Hit>,
    ) {
        let g = &self.grid;
        if g.nx == 0 {
            return;
        }
        // Clip [0, limit] to the grid rectangle.
        let (mut t0, mut t1) = (0.0f64, limit);
        let lo = g.origin;
        let hi = [lo[0] + g.nx as f64 * g.cell, lo[1] + g.ny as f64 * g.cell];
        for a in 0..2 {
            if d[a] == 0.0 {
                if o[a] < lo[a] || o[a] > hi[a] {
                    return;
                }
            } else {
                let (ta, tb) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
            }
        }
        if t0 > t1 {
            return;
        }
        let mut cell = [0usize; 2];
        let mut next = [f64::INFINITY; 2];
        let mut delta = [f64::INFINITY; 2];
        let mut step = [0isize; 2];
        for a in 0..2 {
            cell[a] = g.index(o[a] + t0 * d[a], a);
            if d[a] > 0.0 {
                step[a] = 1;
                next[a] = (lo[a] + (cell[a] + 1) as f64 * g.cell - o[a]) / d[a];
                delta[a] = g.cell / d[a];
            } else if d[a] < 0.0 {
                step[a] = -1;
                next[a] = (lo[a] + cell[a] as f64 * g.cell - o[a]) / d[a];
                delta[a] = -g.cell / d[a];
            }
        }
        loop {
            for &i in g.cell_items(cell[0], cell[1]) {
                let solid = &self.solids[i as usize];
                if let Some(h) = solid.shape.hit(o, d, limit) {
                    limit = h.t;
                    *best = Some(Hit {
                        t: h.t,
                        normal: h.normal,
                        surface: Surface::Solid(i),
                        reflectivity: solid.reflectivity,
                    });
                }
            }
            let a = if next[0] < next[1] { 0 } else { 1 };
            let exit = next[a];
            // Nothing in a later cell can be nearer than this cell's exit.
            if limit <= exit || exit >= t1 || step[a] == 0 {
                return;
            }
            let n = if a == 0 { g.nx } else { g.ny };
            match cell[a].checked_add_signed(step[a]) {
                Some(c) if c < n => cell[a] = c,
                _ => return,
            }
            next[a] += delta[a];
        }
    }

    /// Unsigned distance from `p` to one surface (m).
    pub fn distance_to(&self, surface: Surface, p: &Point3<f64>) -> Option<f64> {
        match surface {
            Surface::Plane(i) => self.planes.get(i as usize).map(|(pl, _)| pl.distance(p)),
            Surface::Solid(i) => self.solids.get(i as usize).map(|s| s.shape.distance(p)),
        }
    }

    /// Brute-force nearest hit over every surface, for checking [`Self::cast`].
    pub fn cast_brute_force(&self, o: &Point3<f64>, d: &Vector3<f64>, t_max: f64) -> Option<Hit> {
        let mut best = self.cast_planes(o, d, t_max);
        let mut limit = best.as_ref().map_or(t_max, |h| h.t);
        for (i, s) in self.solids.iter().enumerate() {
            if let Some(h) = s.shape.hit(o, d, limit) {
                limit = h.t;
                best = Some(Hit {
                    t: h.t,
                    normal: h.normal,
                    surface: Surface::Solid(i as u32),
                    reflectivity: s.reflectivity,
                });
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::city;
    use crate::profile::Profile;
    use crate::rng::Stream;
    use crate::trajectory::Trajectory;

    #[test]
    fn grid_walk_finds_the_same_hit_as_brute_force() {
        // The DDA must never skip a solid: compare with testing every surface, on rays from
        // the route in every direction, some starting outside the grid.
        let tr = Trajectory::generate(Profile::Urban, 2, 60.0);
        let scene = city::build(Profile::Urban, 2, tr.route());
        let mut rng = Stream::from_key(5);
        let (mut solids, mut total) = (0, 0);
        for i in 0..5_000 {
            let s = rng.range(-150.0, 600.0);
            let [x, y] = tr.route().position(s);
            let far = if i % 10 == 0 { 300.0 } else { 0.0 };
            let o = Point3::new(
                x + rng.range(-far, far),
                y + rng.range(-far, far),
                rng.range(0.5, 3.0),
            );
            let d = Vector3::new(rng.normal(), rng.normal(), 0.3 * rng.normal()).normalize();
            let fast = scene.cast(&o, &d, 100.0);
            let slow = scene.cast_brute_force(&o, &d, 100.0);
            assert_eq!(
                fast.map(|h| h.t.to_bits()),
                slow.map(|h| h.t.to_bits()),
                "ray {i}"
            );
            total += fast.is_some() as u32;
            solids += matches!(fast.map(|h| h.surface), Some(Surface::Solid(_))) as u32;
        }
        println!("{total} hits of 5000 rays, {solids} on solids; grid == brute force on all");
        assert!(solids > 1200);
    }
}
