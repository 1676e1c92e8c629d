use super::*;
use crate::local_map::{Exact, LocalMap};
use crate::testutil::yard;
use nalgebra::{Translation3, UnitQuaternion, Vector3};

/// Information of a corridor along the world x axis: walls and floor, nothing across x.
fn corridor_information<T: Real>() -> Information<T> {
    Information {
        t: Matrix3::from_diagonal(&Vector3::new(T::of(1e-4), T::one(), T::one())),
        r: Matrix3::from_diagonal(&Vector3::new(T::of(16.0), T::of(400.0), T::of(400.0))),
    }
}

fn prediction<T: Real>() -> Pose<T> {
    Pose::from_parts(
        Translation3::new(T::of(12.0), T::of(-3.0), T::of(0.5)),
        UnitQuaternion::from_euler_angles(T::of(0.02), T::of(-0.01), T::of(0.3)),
    )
}

#[test]
fn a_well_constrained_information_reads_its_eigenvalue_ratios() {
    let info = Information::<f64> {
        t: Matrix3::from_diagonal(&Vector3::new(0.3, 1.0, 0.8)),
        r: Matrix3::from_diagonal(&Vector3::new(50.0, 400.0, 300.0)),
    };
    let w = measure(&info, &prediction());
    let [t, r] = w.ratio.unwrap();
    assert!(
        (t - 0.3).abs() < 1e-12 && (r - 0.125).abs() < 1e-12,
        "{t} {r}"
    );
    assert!((w.middle.unwrap() - 0.8).abs() < 1e-12);
}

#[test]
fn a_lone_plane_leaves_two_translations_and_yaw_free() {
    // Ground z = 0 seen from 2 m up: information along z, roll and pitch only.
    let info = Information::<f64> {
        t: Matrix3::from_diagonal(&Vector3::new(0.0, 0.0, 1.0)),
        r: Matrix3::from_diagonal(&Vector3::new(100.0, 100.0, 0.0)),
    };
    let w = measure(&info, &Pose::identity());
    assert_eq!(w.ratio, Some([0.0, 0.0]), "a free translation and yaw");
    assert_eq!(w.middle, Some(0.0), "two free translations");
}

#[test]
fn a_corridor_leaves_one_translation_weak_and_the_middle_one_strong_whichever_way_it_faces() {
    // Walls 3 m apart seen less than the floor: the ratios are over the strongest, the floor.
    let info = Information::<f64> {
        t: Matrix3::from_diagonal(&Vector3::new(2e-4, 1.2, 2.0)),
        ..corridor_information()
    };
    for at in [Pose::identity(), prediction()] {
        let w = measure(&info, &at);
        let ([t, r], middle) = (w.ratio.unwrap(), w.middle.unwrap());
        assert!(
            (t - 1e-4).abs() < 1e-12 && (middle - 0.6).abs() < 1e-12,
            "{t} {middle}"
        );
        assert!((r - 0.04).abs() < 1e-12, "{r}");
    }
    let w = measure(&corridor_information::<f32>(), &prediction());
    let [t, _] = w.ratio.unwrap();
    assert!((t - 1e-4).abs() < 1e-6 && (w.middle.unwrap() - 1.0).abs() < 1e-5);
    assert_eq!(Weakness::<f64>::NONE.middle, None);
}

#[test]
fn an_information_without_a_positive_strongest_direction_reads_zero() {
    let info = Information::<f64> {
        t: Matrix3::zeros(),
        r: Matrix3::from_diagonal(&Vector3::new(f64::NAN, 1.0, 1.0)),
    };
    assert_eq!(measure(&info, &Pose::identity()).ratio, Some([0.0, 0.0]));
}

const VOXELS: usize = 3000;
const POINTS: usize = 8192;
const MAP_WORDS: usize = LocalMap::<f64, Exact, &mut [u64]>::words(VOXELS, POINTS);
const N: usize = 6000;

/// The weakest and middle translation ratios `weakness` measures for the points of the yard
/// that `keep` keeps, mapped at the origin and seen from a sensor at `truth` (the prediction).
fn measured_in_yard(keep: impl Fn(&[f64; 3]) -> bool) -> (f64, f64) {
    let mut all = [[0.0; 3]; N];
    let n = yard(&mut all);
    let mut scene = [[0.0; 3]; N];
    let mut m = 0;
    for p in all[..n].iter().filter(|p| keep(p)) {
        scene[m] = *p;
        m += 1;
    }
    let mut words = [0u64; MAP_WORDS];
    let mut map = LocalMap::<f64, Exact, _>::new(1.0, 100.0, 20, VOXELS, POINTS, &mut words[..]);
    let map = map.as_mut().unwrap();
    map.update(&scene[..m], &Pose::identity());
    let truth = Pose::from_parts(
        Translation3::new(0.3, -0.2, 0.02),
        UnitQuaternion::from_euler_angles(0.0, 0.0, 0.02),
    );
    let mut source = [[0.0; 3]; N];
    for (s, p) in source.iter_mut().zip(&scene[..m]) {
        let q = truth.inverse() * Point::from(*p);
        *s = [q.x, q.y, q.z];
    }
    let w = weakness(&map.view(), &source[..m], &truth, 6.0, 3);
    (w.ratio.unwrap()[0], w.middle.unwrap())
}

/// Measured from a map: the yard's floor alone leaves two translations free, the floor
/// between its two walls along x (a corridor) one, and the whole yard none (its other walls
/// and boxes constrain x, if weakly against its floor).
#[test]
#[cfg_attr(miri, ignore = "seconds of map search under Miri")]
fn a_map_s_plane_corridor_and_yard_leave_two_one_and_no_translation_free() {
    let floor = |p: &[f64; 3]| p[2] < 0.1;
    let corridor = |p: &[f64; 3]| floor(p) || (p[1].abs() - 12.3).abs() < 1e-9;
    let plane = measured_in_yard(floor);
    let lane = measured_in_yard(corridor);
    let whole = measured_in_yard(|_| true);
    std::println!(
        "weakest / middle translation over the strongest: plane {:.2e} / {:.2e}, corridor \
         {:.2e} / {:.2e}, yard {:.2e} / {:.2e}",
        plane.0,
        plane.1,
        lane.0,
        lane.1,
        whole.0,
        whole.1
    );
    assert!(plane.0 < 1e-6 && plane.1 < 1e-6, "plane {plane:?}");
    assert!(lane.0 < 1e-6 && lane.1 > 0.1, "corridor {lane:?}");
    assert!(whole.0 > 1e-2 && whole.1 > 0.1, "yard {whole:?}");
}

#[test]
fn min_points_needs_more_than_one_sweep() {
    assert_eq!(min_points(0.5f64), 5);
    assert_eq!(min_points(0.5f32), 5);
    assert_eq!(min_points(0.0f64), usize::MAX);
}

/// `n` points of a tilted plane (rough by 2 cm) out to 40 m, then `off` of them lifted 2 m off
/// it (a wall's worth of structure).
fn tilted_plane(n: usize, off: usize) -> std::vec::Vec<[f64; 3]> {
    let mut rng = crate::testutil::Rng(7);
    let normal = Vector3::new(0.1, -0.2, 1.0).normalize();
    let (u, w) = (normal.cross(&Vector3::x()).normalize(), normal);
    let v = w.cross(&u);
    (0..n)
        .map(|i| {
            let (a, b) = (80.0 * rng.next() - 40.0, 80.0 * rng.next() - 40.0);
            let lift = if i < off {
                2.0
            } else {
                0.04 * rng.next() - 0.02
            };
            let p = u * a + v * b + w * (lift - 1.7);
            [p.x, p.y, p.z]
        })
        .collect()
}

#[test]
#[cfg_attr(
    miri,
    ignore = "18,000 points of soft-float arithmetic: the Miri lane ran out of time on it; no unsafe on this path"
)]
fn a_cloud_is_one_plane_until_more_than_one_point_in_a_thousand_stands_off_it() {
    assert!(one_plane(&tilted_plane(3000, 0), 0.5));
    assert!(one_plane(&tilted_plane(3000, 3), 0.5), "0.1 % off");
    assert!(
        !one_plane(&tilted_plane(3000, 4), 0.5),
        "just over 0.1 % off"
    );
    // An open field's sparsest scans: about 1 % on poles and trees.
    assert!(!one_plane(&tilted_plane(3000, 27), 0.5));
    // The plane's roughness counts against a voxel finer than it.
    assert!(!one_plane(&tilted_plane(3000, 0), 0.01));
    // Too few points to say.
    assert!(!one_plane(&tilted_plane(2, 0), 0.5));
    let f32_plane: std::vec::Vec<[f32; 3]> = tilted_plane(3000, 0)
        .iter()
        .map(|p| p.map(|x| x as f32))
        .collect();
    assert!(one_plane(&f32_plane, 0.5f32));
}
