use super::*;
use crate::city::changes::Change;
use crate::scene::Surface;
use crate::sequence::{self, Format, Messages, Request};
use crate::shapes::Shape;
use crate::simulation::{SimParams, Simulation};
use crate::writer::INITIAL_POSE;
use crate::Layout;
use nalgebra::Point3;

/// A small noise-free sensor: the tests are about geometry.
fn params(profile: Profile, seed: u64, frames: u64) -> SimParams {
    let mut p = SimParams::new(profile, seed, frames);
    p.sensor.beams = 16;
    p.sensor.columns = 256;
    p.sensor.noise = 0.0;
    p.sensor.dropout = 0.0;
    p
}

fn revisit(mut p: SimParams, changes: f64) -> SimParams {
    p.revisit = Some(Revisit { changes });
    p
}

fn runs(profile: Profile, seed: u64, frames: u64, changes: f64) -> (Simulation, Simulation) {
    let first = params(profile, seed, frames);
    (
        Simulation::new(first).unwrap(),
        Simulation::new(revisit(first, changes)).unwrap(),
    )
}

#[test]
fn the_revisit_scene_is_the_first_runs_apart_from_the_changes_it_lists() {
    for (profile, seed) in [
        (Profile::Urban, 1),
        (Profile::Field, 2),
        (Profile::Warehouse, 3),
    ] {
        let (a, b) = runs(profile, seed, 200, 0.1);
        let changed = b.changed().unwrap();
        assert_eq!(a.scene().planes().count(), b.scene().planes().count());
        assert!(a
            .scene()
            .planes()
            .zip(b.scene().planes())
            .all(|(p, q)| p == q));
        assert_eq!(b.scene().solids(), &changed.solids[..]);
        // Which first-run solids the listed changes touch.
        let layout = crate::city::layout(profile, seed, a.trajectory().route());
        assert_eq!(layout.solids, a.scene().solids());
        let mut touched = vec![None; layout.solids.len()];
        for &(g, c) in &changed.changes {
            for i in layout.groups[g].solids.clone() {
                touched[i] = Some(c);
            }
        }
        // Every untouched solid is in the revisit's scene, bit for bit, once.
        let mut seen = vec![0; layout.solids.len()];
        for (j, o) in changed.origin.iter().enumerate() {
            if let Some(i) = *o {
                assert_eq!(b.scene().solids()[j], a.scene().solids()[i]);
                assert!(touched[i].is_none(), "solid {i} changed but kept");
                seen[i] += 1;
            }
        }
        let untouched = touched.iter().filter(|t| t.is_none()).count();
        assert!((0..seen.len()).all(|i| seen[i] == usize::from(touched[i].is_none())));
        // The moved and turned solids are elsewhere; the removed ones and only they are gone.
        let removed = touched
            .iter()
            .filter(|t| **t == Some(Change::Removed))
            .count();
        let kept_changed = touched.iter().filter(|t| t.is_some()).count() - removed;
        let new = usize::from(changed.wall);
        assert_eq!(b.scene().solids().len(), untouched + kept_changed + new);
        let moved: Vec<_> = (0..b.scene().solids().len())
            .filter(|&j| changed.origin[j].is_none())
            .collect();
        for &j in &moved[..moved.len() - new] {
            let s = &b.scene().solids()[j];
            assert!(!a.scene().solids().contains(s), "{j} {s:?} unchanged");
        }
        let cars = crate::city::changes::count(&layout.groups, crate::city::GroupKind::Car);
        let cars_changed = changed
            .changes
            .iter()
            .filter(|(g, _)| layout.groups[*g].kind == crate::city::GroupKind::Car)
            .count();
        println!(
            "{profile:?}: {} objects ({cars} cars), {} changed ({cars_changed} cars: {} moved, \
             {} turned, {} removed), {} of {} solids untouched, wall {}",
            changed.groups,
            changed.changes.len(),
            changed.count(|c| matches!(c, Change::Moved(_))),
            changed.count(|c| matches!(c, Change::Turned(_))),
            changed.count(|c| *c == Change::Removed),
            untouched,
            layout.solids.len(),
            changed.wall
        );
        assert!(changed.wall, "{profile:?}: the new wall found no place");
        assert!(cars_changed as f64 >= 0.1 * cars as f64);
        assert!(!changed.changes.is_empty());
    }
}

#[test]
fn with_no_changes_asked_a_tenth_of_the_parked_cars_still_change_and_a_wall_appears() {
    let (a, b) = runs(Profile::Urban, 4, 150, 0.0);
    let changed = b.changed().unwrap();
    let layout = crate::city::layout(Profile::Urban, 4, a.trajectory().route());
    let cars = crate::city::changes::count(&layout.groups, crate::city::GroupKind::Car);
    let all_cars = changed
        .changes
        .iter()
        .all(|(g, _)| layout.groups[*g].kind == crate::city::GroupKind::Car);
    println!("{} of {cars} cars changed", changed.changes.len());
    assert!(all_cars && cars > 20);
    assert_eq!(changed.changes.len(), (0.1 * cars as f64).ceil() as usize);
    assert!(changed.wall);
}

#[test]
fn changes_of_0_3_change_that_share_of_the_objects() {
    for (profile, seed) in [(Profile::Urban, 5), (Profile::Warehouse, 6)] {
        let (a, b) = runs(profile, seed, 150, 0.3);
        let changed = b.changed().unwrap();
        let share = changed.changes.len() as f64 / changed.groups as f64;
        let layout = crate::city::layout(profile, seed, a.trajectory().route());
        let grouped: usize = layout.groups.iter().map(|g| g.solids.len()).sum();
        let solids: usize = changed
            .changes
            .iter()
            .map(|(g, _)| layout.groups[*g].solids.len())
            .sum();
        let solid_share = solids as f64 / grouped as f64;
        println!(
            "{profile:?}: {} of {} objects changed ({share:.3}, tolerance 0.3 +- 0.01), their \
             solids {solids} of {grouped} ({solid_share:.3})",
            changed.changes.len(),
            changed.groups
        );
        assert!((share - 0.3).abs() <= 0.01);
        assert!((solid_share - 0.3).abs() < 0.1);
    }
}

/// Whether `p` is within `margin` of the inside of `shape`.
fn near_inside(shape: &Shape, p: &Point3<f64>, margin: f64) -> bool {
    match *shape {
        Shape::Box {
            centre,
            half,
            rot,
            tilt: [ct, st],
        } => {
            let d = p - centre;
            let (lx, ly) = (rot[0] * d.x + rot[1] * d.y, -rot[1] * d.x + rot[0] * d.y);
            let (ly, lz) = (ct * ly + st * d.z, -st * ly + ct * d.z);
            lx.abs() < half.x + margin && ly.abs() < half.y + margin && lz.abs() < half.z + margin
        }
        Shape::Cylinder { centre, radius, z } => {
            (p.x - centre[0]).hypot(p.y - centre[1]) < radius + margin
                && p.z > z[0] - margin
                && p.z < z[1] + margin
        }
        Shape::Sphere { centre, radius } => (p - centre).norm() < radius + margin,
        Shape::Foliage { .. } => shape.distance(p) < margin,
    }
}

#[test]
fn the_revisit_drives_the_other_way_beside_the_first_run_and_never_strays_from_it() {
    for (profile, seed, frames) in [
        (Profile::Urban, 1, 400),
        (Profile::Field, 2, 300),
        (Profile::Warehouse, 3, 400),
        (Profile::Handheld, 7, 200),
    ] {
        let (a, b) = runs(profile, seed, frames, 0.1);
        let first: Vec<_> = (0..frames)
            .map(|k| a.trajectory().pose(a.end_offset(k)))
            .collect();
        let lateral = lateral_offset(profile);
        let (mut worst, mut opposite, mut offset_err) = (0.0f64, 0, 0.0f64);
        for k in 0..frames {
            let t = b.end_offset(k);
            let pose = b.trajectory().pose(t);
            let p = pose.translation.vector;
            // Nearest first-run sweep end.
            let (near, d) = first
                .iter()
                .map(|q| (q, (q.translation.vector - p).xy().norm()))
                .min_by(|x, y| x.1.total_cmp(&y.1))
                .unwrap();
            worst = worst.max(d);
            let ax = pose.rotation.matrix().column(0).xy();
            let bx = near.rotation.matrix().column(0).xy();
            opposite += usize::from(ax.dot(&bx) < -0.5);
            // Beside the route, at the lane's offset.
            let s = b.trajectory().route_arc(t);
            let c = b.trajectory().route().position(s);
            offset_err = offset_err.max(((p.x - c[0]).hypot(p.y - c[1]) - lateral).abs());
            let eye = Point3::from(p);
            for solid in b.scene().solids() {
                assert!(
                    !near_inside(&solid.shape, &eye, 0.5),
                    "frame {k} in {solid:?}"
                );
            }
        }
        let (a0, a1) = (
            a.trajectory().route_arc(0.0),
            a.trajectory().route_arc(a.end_offset(frames - 1)),
        );
        let (b0, b1) = (
            b.trajectory().route_arc(0.0),
            b.trajectory().route_arc(b.end_offset(frames - 1)),
        );
        let covered = (b0 - b1) / (a1 - a0);
        println!(
            "{profile:?}: farthest revisit frame {worst:.2} m from the first run (tolerance 30), \
             {opposite}/{frames} frames facing the other way, lane offset error {offset_err:.2e} \
             m, covers {covered:.2} of the first run's stretch [{a0:.0}, {a1:.0}] m back from \
             {b0:.0} to {b1:.0}"
        );
        assert!(worst < 30.0);
        assert!(opposite as f64 > 0.9 * frames as f64);
        assert!(offset_err < 1e-6);
        assert_eq!(b0, a1);
        assert!(b1 >= a0 && covered > 0.55, "covers {covered}");
    }
}

#[test]
fn revisit_ground_truth_puts_static_points_where_the_first_run_sees_them() {
    let (a, b) = runs(Profile::Urban, 1, 300, 0.3);
    let origin = b.changed().unwrap().origin.clone();
    let g0 = b.ground_truth(0);
    println!("frame 0 ground truth: {:?}", g0.translation.vector);
    assert!(
        g0.translation.vector.norm() > 5.0,
        "frame 0 should not be the identity"
    );
    assert_eq!(a.ground_truth_origin(), b.ground_truth_origin());
    let (mut checked, mut worst) = (0, 0.0f64);
    for k in (0..300).step_by(30) {
        let frame = b.frame(k);
        let truth = b.ground_truth(k);
        for ((p, t), s) in frame.points.iter().zip(&frame.stamps).zip(&frame.surfaces) {
            // The last column is cast from the sweep's end, the pose ground truth gives.
            if *t != frame.end_time {
                continue;
            }
            let local = Point3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            let world = a.ground_truth_origin() * (truth * local);
            let surface = match *s {
                Surface::Plane(i) => Surface::Plane(i),
                Surface::Solid(j) => match origin[j as usize] {
                    Some(i) => Surface::Solid(i as u32),
                    None => continue, // moved or new since the first run
                },
            };
            let d = a.scene().distance_to(surface, &world).unwrap();
            worst = worst.max(d);
            checked += 1;
        }
    }
    println!("{checked} points of static surfaces, farthest {worst:.2e} m off (tolerance 1e-4)");
    assert!(checked > 100);
    assert!(worst < 1e-4);
}

#[test]
fn initial_pose_txt_round_trips_to_frame_zeros_pose() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("revisit");
    let request = Request {
        params: revisit(params(Profile::Urban, 8, 12), 0.2),
        sensor: None,
        format: Format::Generic,
        messages: Messages::Points,
        messages_per_frame: 1,
        imu: None,
        layout: Layout::Generic,
        overwrite: false,
    };
    sequence::write(&request, &dir, &|| false, &mut |_| {}).unwrap();
    let text = std::fs::read_to_string(dir.join(INITIAL_POSE)).unwrap();
    assert_eq!(text.lines().count(), 1);
    let pose = kiss_odom_io::poses::parse_xyz_rpy(&text).unwrap();
    let poses = std::fs::read_to_string(dir.join("poses.txt")).unwrap();
    let row: Vec<f64> = poses
        .lines()
        .next()
        .unwrap()
        .split(' ')
        .map(|v| v.parse().unwrap())
        .collect();
    let m = pose.to_homogeneous();
    let worst = (0..12)
        .map(|i| (m[(i / 4, i % 4)] - row[i]).abs())
        .fold(0.0, f64::max);
    println!(
        "{}: worst entry {worst:.1e} off poses.txt's first row (tolerance 1e-9)",
        text.trim()
    );
    assert!(worst < 1e-9);
    let sim = Simulation::new(request.params).unwrap();
    assert!((sim.ground_truth(0).to_homogeneous() - m).amax() < 1e-9);
    let toml = std::fs::read_to_string(dir.join("sim.toml")).unwrap();
    assert!(
        toml.contains("[revisit]") && toml.contains("initial_pose.txt"),
        "{toml}"
    );
}

#[test]
fn a_revisit_is_refused_with_a_dataset_layout_and_changes_outside_0_to_1() {
    for bad in [-0.1, 1.5, f64::NAN] {
        let e = revisit(params(Profile::Urban, 0, 2), bad)
            .validate()
            .unwrap_err();
        assert!(e.to_string().contains("changes"), "{e}");
    }
    let request = Request {
        params: revisit(params(Profile::Urban, 0, 2), 0.1),
        sensor: None,
        format: Format::Generic,
        messages: Messages::Points,
        messages_per_frame: 1,
        imu: None,
        layout: Layout::Mulran,
        overwrite: false,
    };
    let e = sequence::params_of(&request).unwrap_err().to_string();
    assert!(e.contains("--revisit"), "{e}");
}
