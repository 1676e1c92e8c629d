use super::*;
use crate::local_map::{Exact, LocalMap, MapView, PointCodec};
use crate::testutil::yard;
use nalgebra::{Translation3, UnitQuaternion};
use std::vec::Vec;

const VOXELS: usize = 3000;
const POINTS: usize = 8192;
const MAP_WORDS: usize = LocalMap::<f64, Exact, &mut [u64]>::words(VOXELS, POINTS);
const N: usize = 6000;
const WORK_WORDS: usize = work_words::<f64>(N, false);

/// The map's and ICP's words (about 0.7 MB) live on the heap: a test thread's stack is 2 MiB.
struct Fixture {
    map: Vec<u64>,
    work: Vec<u64>,
    scene: Vec<[f64; 3]>,
    n: usize,
}

impl Fixture {
    /// A map over the fixture's words holding the scene, and the ICP work words.
    fn map_and_work(&mut self) -> (LocalMap<f64, Exact, &mut [u64]>, &mut [u64]) {
        let mut map = LocalMap::new(1.0, 100.0, 20, VOXELS, POINTS, &mut self.map[..]).unwrap();
        let st = map.update(&self.scene[..self.n], &Pose::identity());
        assert_eq!(st.added, self.n, "every scene point must be in the map");
        (map, &mut self.work[..])
    }
}

fn fixture() -> Fixture {
    let mut f = Fixture {
        map: std::vec![0; MAP_WORDS],
        work: std::vec![0; WORK_WORDS],
        scene: std::vec![[0.0; 3]; N],
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
        budget: None,
        planes: false,
        prior: None,
        stop_on_cycle: false,
    }
}

/// Builds a map of the scene, moves a copy of the scene by `truth^-1` and registers it back.
fn register(
    f: &mut Fixture,
    truth: &Pose<f64>,
    guess: &Pose<f64>,
    exec: &impl Executor,
) -> Alignment<f64> {
    let scene = f.scene.clone();
    let n = f.n;
    let mut source = std::vec![[0.0; 3]; N];
    let inv = truth.inverse();
    for (s, p) in source.iter_mut().zip(scene[..n].iter()) {
        let q = inv * Point::from(*p);
        *s = [q.x, q.y, q.z];
    }
    let (map, work) = f.map_and_work();
    align_points_to_map(
        exec,
        &source[..n],
        work,
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
    let scene = f.scene.clone();
    let n = f.n;
    let mut source = std::vec![[0.0; 3]; N];
    for (s, p) in source.iter_mut().zip(scene[..n].iter()) {
        *s = [p[0] - 0.4, p[1] - 0.1, p[2]];
    }
    let (map, work) = f.map_and_work();
    let capped = IcpParams {
        convergence_criterion: 1e-4,
        max_iterations: 2,
        budget: None,
        planes: false,
        prior: None,
        stop_on_cycle: false,
    };
    let a = align_points_to_map(
        &Sequential,
        &source[..n],
        work,
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

/// Walks `walkers` queries through `map` by steps of every size (1e-7 m to 0.4 m, some landing
/// exactly on voxel faces or halfway between two map points), answering each step as ICP does
/// (keeping answers) and by a fresh search; every answer must be identical, bit for bit.
/// Returns (steps, answers kept).
fn walk_and_compare<T: Real, P: PointCodec<T>>(
    map: &MapView<'_, T, P>,
    scene: &[[f64; 3]],
    max_distance: T,
    seed: u64,
) -> (usize, usize) {
    walk_with_steps(map, scene, max_distance, seed, 0.4)
}

/// [`walk_and_compare`] with steps up to `largest_step` (m).
fn walk_with_steps<T: Real, P: PointCodec<T>>(
    map: &MapView<'_, T, P>,
    scene: &[[f64; 3]],
    max_distance: T,
    seed: u64,
    largest_step: f64,
) -> (usize, usize) {
    let mut rng = crate::testutil::Rng(seed);
    let v = map.voxel_size().wide();
    let slack = slack_for(T::of(2.0 * 20.0 + 4.0 * v));
    let (mut steps, mut kept_answers) = (0, 0);
    let walkers = if cfg!(miri) { 3 } else { 120 };
    let largest = largest_step.log10();
    for w in 0..walkers {
        let start = scene[(rng.next() * scene.len() as f64) as usize];
        let mut at = Vector3::new(
            T::of(start[0] + rng.next() - 0.5),
            T::of(start[1] + rng.next() - 0.5),
            T::of(start[2] + rng.next() * 0.4 - 0.2),
        );
        let mut kept = [T::zero(), T::zero(), T::zero(), -T::one(), -T::one()];
        let moves = if cfg!(miri) { 20 } else { 200 };
        for k in 0..moves {
            let next = match k % 7 {
                // Onto the nearest voxel face along x.
                5 => {
                    let f = (at.x.wide() / v).round() * v;
                    Vector3::new(T::of(f), at.y, at.z)
                }
                // Halfway between two map points: equidistant, ties decided by rank.
                6 => {
                    let i = (rng.next() * (scene.len() - 1) as f64) as usize;
                    let (a, b) = (scene[i], scene[i + 1]);
                    Vector3::new(
                        T::of((a[0] + b[0]) / 2.0),
                        T::of((a[1] + b[1]) / 2.0),
                        T::of((a[2] + b[2]) / 2.0),
                    )
                }
                _ => {
                    let size = 10f64.powf(-7.0 + rng.next() * (largest + 7.0));
                    let d = Vector3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5);
                    at + (d.normalize() * size).map(T::of)
                }
            };
            let (got, work) =
                closest_from(&mut kept, map, &at, &next, max_distance, slack, u32::MAX).unwrap();
            let from_kept = work == 1;
            let want = map.closest_neighbor(&Point::from(next), max_distance);
            assert_eq!(got, want, "walker {w} step {k}: {next:?}");
            steps += 1;
            kept_answers += usize::from(from_kept);
            at = next;
        }
    }
    (steps, kept_answers)
}

#[test]
#[cfg_attr(miri, ignore = "minutes per walk under Miri; no unsafe on this path")]
fn kept_answers_equal_a_new_search_f64_exact() {
    let mut f = fixture();
    let scene = f.scene.clone();
    let n = f.n;
    let (map, _) = f.map_and_work();
    for (i, tau) in [0.3, 1.0, 6.0].into_iter().enumerate() {
        let (steps, kept) = walk_and_compare(&map.view(), &scene[..n], tau, 17 + i as u64);
        std::println!("tau {tau} m: {steps} steps, {kept} answered from what was kept");
        assert!(kept * 4 > steps, "too few kept answers to test anything");
    }
}

#[test]
#[cfg_attr(miri, ignore = "minutes per walk under Miri; no unsafe on this path")]
fn kept_answers_equal_a_new_search_f32_quantized() {
    use crate::local_map::Quantized;
    const W: usize = LocalMap::<f32, Quantized, &mut [u64]>::words(VOXELS, POINTS);
    let f = fixture();
    let mut words = [0u64; W];
    let mut map =
        LocalMap::<f32, Quantized, _>::new(1.0, 100.0, 20, VOXELS, POINTS, &mut words[..]).unwrap();
    let scene32: [[f32; 3]; N] = core::array::from_fn(|i| f.scene[i].map(|c| c as f32));
    map.update(&scene32[..f.n], &Pose::identity());
    for (i, tau) in [0.3f32, 1.0, 6.0].into_iter().enumerate() {
        let (steps, kept) = walk_and_compare(&map.view(), &f.scene[..f.n], tau, 91 + i as u64);
        std::println!(
            "tau {tau} m (f32, quantized): {steps} steps, {kept} answered from what was kept"
        );
        assert!(kept * 4 > steps, "too few kept answers to test anything");
    }
}

#[test]
#[cfg_attr(miri, ignore = "minutes per walk under Miri; no unsafe on this path")]
fn kept_answers_equal_a_new_search_in_a_sparse_map() {
    // Isolated points far apart: a kept answer stays valid across voxel faces, until the point
    // it names drops out of the 27 voxels or a voxel that enters them holds a closer one.
    const W: usize = LocalMap::<f64, Exact, &mut [u64]>::words(64, 256);
    let mut words = [0u64; W];
    let mut map = LocalMap::<f64, Exact, _>::new(1.0, 100.0, 20, 64, 256, &mut words[..]).unwrap();
    let mut rng = crate::testutil::Rng(5);
    let mut scene = [[0.0f64; 3]; 40];
    for p in scene.iter_mut() {
        *p = [rng.next() * 6.0, rng.next() * 6.0, rng.next() * 6.0];
    }
    map.add_points(scene.iter().map(|p| Point::from(*p)));
    for (i, tau) in [0.5, 2.0, 6.0].into_iter().enumerate() {
        let (steps, kept) = walk_with_steps(&map.view(), &scene, tau, 3 + i as u64, 1.5);
        std::println!("sparse map, tau {tau} m: {steps} steps, {kept} answered from what was kept");
        assert!(kept * 4 > steps, "too few kept answers to test anything");
    }
}

#[test]
#[cfg_attr(miri, ignore = "minutes per ICP run under Miri")]
fn a_short_work_area_registers_the_chunks_that_fit() {
    // Room for 10 chunks of the scene's points: ICP uses those 640 points, and only those.
    let mut f = fixture();
    let truth = Pose::translation(0.2, -0.1, 0.0);
    f.work.truncate(work_words::<f64>(10 * CHUNK, false));
    let a = register(&mut f, &truth, &Pose::identity(), &Sequential);
    let (et, er) = errors(&a.pose, &truth);
    std::println!(
        "{} correspondences of {} points; error {et:.1e} m, {er:.1e} rad (tolerance 1e-6)",
        a.correspondences,
        f.n
    );
    assert!(a.correspondences > 0 && a.correspondences as usize <= 10 * CHUNK);
    assert!(et < 1e-6 && er < 1e-6);
}

#[test]
#[cfg_attr(miri, ignore = "minutes per ICP run under Miri")]
fn the_moved_points_are_the_source_at_the_registered_pose_in_either_layout() {
    let mut f = fixture();
    let truth = Pose::translation(0.2, -0.1, 0.05);
    let inv = truth.inverse();
    let source: Vec<[f64; 3]> = f.scene[..f.n]
        .iter()
        .map(|p| (inv * Point::from(*p)).coords.into())
        .collect();
    let (map, _) = f.map_and_work();
    for planes in [false, true] {
        let mut work = std::vec![0u64; work_words::<f64>(source.len(), planes)];
        let params = IcpParams { planes, ..params() };
        let a = align_points_to_map(
            &Sequential,
            &source,
            &mut work,
            &map.view(),
            &Pose::identity(),
            6.0,
            2.0,
            &params,
        );
        let moved: Vec<Point<f64>> = moved_points::<f64>(&mut work, source.len(), planes).collect();
        assert_eq!(moved.len(), source.len(), "planes: {planes}");
        // The last iteration moved them by the last step, which is below gamma.
        let worst = moved
            .iter()
            .zip(&source)
            .map(|(m, s)| (m - a.pose * Point::from(*s)).norm())
            .fold(0.0, f64::max);
        std::println!(
            "planes {planes}: worst |moved - pose * source| {worst:.1e} m (tolerance 1e-3); \
             {} of {} correspondences point-to-plane",
            a.plane_correspondences,
            a.correspondences
        );
        assert!(worst < 1e-3);
        // The fixture's walls and ground are planar: with plane terms most correspondences
        // are point-to-plane, without them none.
        if planes {
            assert!(a.plane_correspondences > a.correspondences / 2);
            assert!(a.plane_correspondences <= a.correspondences);
        } else {
            assert_eq!(a.plane_correspondences, 0);
        }
    }
}

/// Every scalar of a chunk belongs to one of its parts, in either layout: the layouts are no
/// longer than what `parts` hands out (a longer one would only waste the arena).
#[test]
fn a_chunk_is_exactly_its_parts_in_either_layout() {
    fn fill_parts<C: WorkChunk<f64>>(c: &mut C) {
        let Some(p) = c.parts() else {
            panic!("a chunk has its parts")
        };
        p.points.fill(1.0);
        p.kept.fill(1.0);
        p.system.fill(1.0);
        *p.count = 1.0;
        p.progress.fill(1.0);
        if let Some(pl) = p.planes {
            pl.system.fill(1.0);
            pl.cached.fill(1.0);
        }
    }
    let mut reference: Chunk<f64> = [f64::NAN; CHUNK_LEN];
    fill_parts(&mut reference);
    assert!(reference.iter().all(|v| *v == 1.0), "reference layout");
    let mut robust: PlaneChunk<f64> = [f64::NAN; PLANE_CHUNK_LEN];
    fill_parts(&mut robust);
    assert!(robust.iter().all(|v| *v == 1.0), "robust layout");
}
