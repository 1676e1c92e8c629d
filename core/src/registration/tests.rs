use super::*;
use crate::config::BLOCK;
use crate::local_map::{Exact, MapBuffers};
use crate::testutil::yard;
use crate::voxel::VoxelKey;
use nalgebra::{Translation3, UnitQuaternion};

const SLOTS: usize = 4096;
const BLOCKS: usize = 2048;
const N: usize = 6000;

struct Fixture {
    keys: [VoxelKey; SLOTS],
    heads: [u32; SLOTS],
    counts: [u8; SLOTS],
    points: [[f64; 3]; BLOCKS * BLOCK],
    links: [u32; BLOCKS],
    scene: [[f64; 3]; N],
    n: usize,
}

fn fixture() -> Fixture {
    let mut f = Fixture {
        keys: [[0; 3]; SLOTS],
        heads: [0; SLOTS],
        counts: [0; SLOTS],
        points: [[0.0; 3]; BLOCKS * BLOCK],
        links: [0; BLOCKS],
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
    let mut map = LocalMap::<f64, Exact>::new(
        1.0,
        100.0,
        20,
        3000,
        MapBuffers {
            keys: &mut f.keys,
            heads: &mut f.heads,
            counts: &mut f.counts,
            points: &mut f.points,
            links: &mut f.links,
        },
    )
    .unwrap();
    let st = map.update(&scene[..n], &Pose::identity());
    assert_eq!(st.added, n, "every scene point must be in the map");
    let mut source = [[0.0; 3]; N];
    let inv = truth.inverse();
    for (s, p) in source.iter_mut().zip(scene[..n].iter()) {
        let q = inv * Point::from(*p);
        *s = [q.x, q.y, q.z];
    }
    let mut systems = [[0.0; SYSTEM_LEN]; N / CHUNK + 1];
    align_points_to_map(
        exec,
        &mut source[..n],
        &mut systems,
        &map,
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
    let mut map = LocalMap::<f64, Exact>::new(
        1.0,
        100.0,
        20,
        3000,
        MapBuffers {
            keys: &mut f.keys,
            heads: &mut f.heads,
            counts: &mut f.counts,
            points: &mut f.points,
            links: &mut f.links,
        },
    )
    .unwrap();
    map.update(&scene[..n], &Pose::identity());
    let mut source = [[0.0; 3]; N];
    for (s, p) in source.iter_mut().zip(scene[..n].iter()) {
        *s = [p[0] - 0.4, p[1] - 0.1, p[2]];
    }
    let mut systems = [[0.0; SYSTEM_LEN]; N / CHUNK + 1];
    let capped = IcpParams {
        convergence_criterion: 1e-4,
        max_iterations: 2,
    };
    let a = align_points_to_map(
        &Sequential,
        &mut source[..n],
        &mut systems,
        &map,
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
    fn for_each_chunk<P: Send, R: Send>(
        &self,
        points: &mut [P],
        out: &mut [R],
        f: &(dyn Fn(&mut [P], &mut R) + Sync),
    ) {
        for (c, r) in points.chunks_mut(CHUNK).zip(out.iter_mut()).rev() {
            f(c, r);
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
