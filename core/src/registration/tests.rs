use super::*;
use crate::local_map::{Exact, LocalMap};
use crate::testutil::yard;
use nalgebra::{Translation3, UnitQuaternion};

const VOXELS: usize = 3000;
const POINTS: usize = 8192;
const MAP_WORDS: usize = LocalMap::<f64, Exact, &mut [u64]>::words(VOXELS, POINTS);
const N: usize = 6000;
const WORK_WORDS: usize = work_words::<f64>(N);

struct Fixture {
    map: [u64; MAP_WORDS],
    work: [u64; WORK_WORDS],
    scene: [[f64; 3]; N],
    n: usize,
}

impl Fixture {
    /// A map over the fixture's words holding the scene.
    fn map(&mut self) -> LocalMap<f64, Exact, &mut [u64]> {
        let mut map = LocalMap::new(1.0, 100.0, 20, VOXELS, POINTS, &mut self.map[..]).unwrap();
        let st = map.update(&self.scene[..self.n], &Pose::identity());
        assert_eq!(st.added, self.n, "every scene point must be in the map");
        map
    }
}

fn fixture() -> Fixture {
    let mut f = Fixture {
        map: [0; MAP_WORDS],
        work: [0; WORK_WORDS],
        scene: [[0.0; 3]; N],
        n: 0,
    };
    f.n = yard(&mut f.scene);
    assert!(f.n > 3000 && f.n < N);
    f
}

fn params() -> IcpParams<f64> {
    IcpParams {
        convergence_criterion: 1e-4,
        max_iterations: 500,
    }
}

/// Builds a map of the scene, moves a copy of the scene by `truth^-1` and registers it back.
fn register(
    f: &mut Fixture,
    truth: &Pose<f64>,
    guess: &Pose<f64>,
    exec: &impl Executor,
) -> Alignment<f64> {
    let scene = f.scene;
    let n = f.n;
    let mut source = [[0.0; 3]; N];
    let inv = truth.inverse();
    for (s, p) in source.iter_mut().zip(scene[..n].iter()) {
        let q = inv * Point::from(*p);
        *s = [q.x, q.y, q.z];
    }
    let mut work = f.work;
    let map = f.map();
    align_points_to_map(
        exec,
        &source[..n],
        &mut work,
        &map.view(),
        guess,
        6.0,
        2.0,
        &params(),
    )
}

fn errors(a: &Pose<f64>, b: &Pose<f64>) -> (f64, f64) {
    let d = a.inverse() * b;
    (d.translation.vector.norm(), d.rotation.angle())
}

#[test]
#[cfg_attr(miri, ignore = "minutes per ICP run under Miri")]
fn a_rigid_transform_of_a_structured_scene_is_recovered_to_a_micrometre() {
    let mut f = fixture();
    let truth = Pose::from_parts(
        Translation3::new(0.35, -0.2, 0.05),
        UnitQuaternion::from_euler_angles(0.01, -0.015, 0.04),
    );
    let a = register(&mut f, &truth, &Pose::identity(), &Sequential);
    let (et, er) = errors(&a.pose, &truth);
    assert!(a.converged && !a.singular);
    assert!(
        et < 1e-6 && er < 1e-6,
        "translation {et:e} m, rotation {er:e} rad"
    );
}

#[test]
#[cfg_attr(miri, ignore = "minutes per ICP run under Miri")]
fn the_iteration_cap_stops_icp_and_is_reported() {
    let mut f = fixture();
    let truth = Pose::translation(0.4, 0.1, 0.0);
    let scene = f.scene;
    let n = f.n;
    let mut source = [[0.0; 3]; N];
    for (s, p) in source.iter_mut().zip(scene[..n].iter()) {
        *s = [p[0] - 0.4, p[1] - 0.1, p[2]];
    }
    let mut work = f.work;
    let map = f.map();
    let capped = IcpParams {
        convergence_criterion: 1e-4,
        max_iterations: 2,
    };
    let a = align_points_to_map(
        &Sequential,
        &source[..n],
        &mut work,
        &map.view(),
        &Pose::identity(),
        6.0,
        2.0,
        &capped,
    );
    assert_eq!((a.iterations, a.converged), (2, false));
    let (et, _) = errors(&a.pose, &truth);
    assert!(
        et > 1e-4,
        "two iterations should not finish the job ({et:e})"
    );
}

#[test]
#[cfg_attr(miri, ignore = "minutes per ICP run under Miri")]
fn zero_correspondences_leave_the_initial_guess_and_flag_singular() {
    let mut f = fixture();
    // Far beyond the 27-voxel search: nothing associates.
    let truth = Pose::translation(50.0, 0.0, 0.0);
    let guess = Pose::translation(0.0, 0.0, 0.0);
    let a = register(&mut f, &truth, &guess, &Sequential);
    assert_eq!(a.correspondences, 0);
    assert!(a.singular);
    assert_eq!(a.pose, guess);
}

/// Runs chunks in reverse order: a stand-in for a thread pool finishing in any order.
struct Reversed;
impl Executor for Reversed {
    fn for_each<C: Send>(&self, chunks: &mut [C], work: &(dyn Fn(&mut C) + Sync)) {
        for c in chunks.iter_mut().rev() {
            work(c);
        }
    }
}

#[test]
#[cfg_attr(miri, ignore = "minutes per ICP run under Miri")]
fn the_result_does_not_depend_on_the_order_chunks_run_in() {
    let truth = Pose::from_parts(
        Translation3::new(0.2, 0.3, -0.02),
        UnitQuaternion::from_euler_angles(0.0, 0.01, -0.03),
    );
    let a = register(&mut fixture(), &truth, &Pose::identity(), &Sequential);
    let b = register(&mut fixture(), &truth, &Pose::identity(), &Reversed);
    assert_eq!(a.pose, b.pose);
    assert_eq!(a.iterations, b.iterations);
}
