//! The embedding surface of `Odometry`: storage it owns, `reset`, scans streamed and abandoned,
//! and what a user of kiss-icp's `KissICP` reaches for (last pose and delta, the deskewed scan,
//! the registration cloud, the local map's points).

use crate::common;

use common::*;
use kiss_odom_core::stages::{
    chunks_for, preprocess, scratch_words_for, voxel_downsample, Dedup, CHUNK, SYSTEM_LEN,
};
use kiss_odom_core::{
    Capacities, Config, ConfigError, Exact, Flag, FrameReport, Odometry, Pose, Quantized, Storage,
    Words,
};

const RANGE: f64 = 40.0;
const FRAMES: usize = 12;

fn scans() -> Vec<Vec<[f64; 3]>> {
    let s = street(11);
    (0..FRAMES).map(|i| scan(&s, i, RANGE)).collect()
}

/// Per-point times by azimuth over a 0.1 s sweep, so every frame is deskewed.
fn stamps(scan: &[[f64; 3]]) -> Vec<f64> {
    scan.iter()
        .map(|p| 5.0 + (p[1].atan2(p[0]) + std::f64::consts::PI) / std::f64::consts::TAU * 0.1)
        .collect()
}

/// A tracker that owns its odometry and the odometry's storage: nothing borrowed, so it can
/// live in a struct field, be moved, boxed or sent to another thread.
struct Tracker<S: Storage> {
    odom: Odometry<f64, Exact, S>,
    poses: Vec<Pose<f64>>,
}

impl<S: Storage + Send + 'static> Tracker<S> {
    fn new(storage: S) -> Self {
        let odom = Odometry::new(Config::new(RANGE), caps(), storage).unwrap();
        Self {
            odom,
            poses: Vec::new(),
        }
    }

    fn track(&mut self, scan: &[[f64; 3]]) {
        let r = self.odom.register_frame(scan, Some(&stamps(scan))).unwrap();
        self.poses.push(r.pose);
    }
}

fn borrowed_run(frames: &[Vec<[f64; 3]>]) -> Vec<Pose<f64>> {
    let mut words = vec![0u64; caps().arena_words::<f64, Exact>()];
    let mut odom =
        Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps(), &mut words[..]).unwrap();
    frames
        .iter()
        .map(|s| odom.register_frame(s, Some(&stamps(s))).unwrap().pose)
        .collect()
}

#[test]
fn a_struct_owns_its_odometry_and_storage_and_tracks_like_a_borrowed_one() {
    let frames = scans();
    let want = borrowed_run(&frames);
    // Owned words in a Vec; the tracker is moved to another thread half way.
    let mut t = Tracker::new(vec![0u64; caps().arena_words::<f64, Exact>()]);
    for s in &frames[..FRAMES / 2] {
        t.track(s);
    }
    let mut t = std::thread::spawn(move || {
        for s in &scans()[FRAMES / 2..] {
            t.track(s);
        }
        t
    })
    .join()
    .unwrap();
    assert_eq!(t.poses, want);
    // Owned words in a boxed slice, behind a Box of the tracker.
    let mut boxed = Box::new(Tracker::new(
        vec![0u64; caps().arena_words::<f64, Exact>()].into_boxed_slice(),
    ));
    for s in &frames {
        boxed.track(s);
    }
    assert_eq!(boxed.poses, want);
    t.odom.reset();
    t.poses.clear();
    t.track(&frames[0]);
    assert_eq!(t.poses[0], want[0]);
}

#[test]
fn const_constructed_words_hold_a_whole_odometry() {
    // As `common::caps()`, which is not a const fn.
    const CAPS: Capacities = Capacities {
        scan_points: 100_000,
        merge_points: 65_536,
        source_points: 16_384,
        map_voxels: 16_384,
        map_points: 262_144,
        plane_terms: false,
    };
    const N: usize = CAPS.arena_words::<f32, Quantized>();
    // In a `static`, as firmware holds it: built at compile time, never on a stack (a debug
    // build would build `Box::new(Words::new())` on the test thread's stack first).
    static WORDS: std::sync::Mutex<Words<N>> = std::sync::Mutex::new(Words::new());
    let mut words = WORDS.lock().unwrap();
    let mut odom =
        Odometry::<f32, Quantized, _>::new(Config::new(RANGE as f32), CAPS, &mut *words).unwrap();
    let frames = scans();
    for (i, s) in frames.iter().enumerate() {
        let r = odom.register_frame(&narrow::<f32>(s), None).unwrap();
        assert!(
            r.dropped == Default::default(),
            "frame {i}: {:?}",
            r.dropped
        );
        let err = error_at(&widen(&r.pose), i);
        assert!(err < 0.02, "frame {i}: {err} m");
    }
    assert_eq!(odom.state_bytes(), N * 8 + std::mem::size_of_val(&odom));
}

#[cfg(feature = "alloc")]
#[test]
fn a_boxed_odometry_sizes_its_own_storage() {
    let frames = scans();
    let mut odom = Odometry::<f64, Exact, _>::boxed(Config::new(RANGE), caps()).unwrap();
    let got: Vec<_> = frames
        .iter()
        .map(|s| odom.register_frame(s, Some(&stamps(s))).unwrap().pose)
        .collect();
    assert_eq!(got, borrowed_run(&frames));
    assert_eq!(odom.layout().words, caps().arena_words::<f64, Exact>());
}

#[test]
fn reset_gives_the_poses_of_a_new_odometry() {
    let frames = scans();
    let want = borrowed_run(&frames);
    let mut t = Tracker::new(vec![0u64; caps().arena_words::<f64, Exact>()]);
    // Another drive first: the reset must forget its map, velocity and threshold.
    for s in frames.iter().rev().take(5) {
        t.track(s);
    }
    let hw_before = t.odom.high_water();
    assert!(hw_before.map_voxels > 0 && t.odom.frames() == 5);
    t.odom.reset();
    assert_eq!(t.odom.frames(), 0);
    assert_eq!(t.odom.map().voxels(), 0);
    assert_eq!(*t.odom.last_pose(), Pose::identity());
    assert_eq!(*t.odom.last_delta(), Pose::identity());
    assert_eq!(t.odom.high_water(), Default::default());
    assert!(t.odom.merge_cloud().is_empty() && t.odom.source().is_empty());
    t.poses.clear();
    for s in &frames {
        t.track(s);
    }
    assert_eq!(t.poses, want);
}

/// Everything a frame leaves behind that the next frame or a user can observe.
#[derive(Debug, PartialEq)]
struct Observed {
    report: FrameReport<f64>,
    merge: Vec<[f64; 3]>,
    source: Vec<[f64; 3]>,
    map: Vec<[f64; 3]>,
    sigma: f64,
    frames: u64,
}

fn observe<S: Storage>(odom: &Odometry<f64, Exact, S>, report: FrameReport<f64>) -> Observed {
    let mut map = Vec::new();
    odom.map().for_each_point(|_, p| map.push([p.x, p.y, p.z]));
    Observed {
        report,
        merge: odom.merge_cloud().to_vec(),
        source: odom.source().to_vec(),
        map,
        sigma: odom.sigma(),
        frames: odom.frames(),
    }
}

#[test]
fn an_abandoned_streamed_frame_changes_nothing_the_next_frame_sees() {
    let frames = scans();
    let (mut a, mut b) = (
        vec![0u64; caps().arena_words::<f64, Exact>()],
        vec![0u64; caps().arena_words::<f64, Exact>()],
    );
    let mut clean = Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps(), &mut a[..]).unwrap();
    let mut tried = Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps(), &mut b[..]).unwrap();
    for (i, s) in frames.iter().enumerate() {
        let t = stamps(s);
        let before = (
            *tried.last_pose(),
            *tried.last_delta(),
            tried.sigma(),
            tried.frames(),
        );
        let (hw, source) = (tried.high_water(), tried.source().to_vec());
        {
            // Another sweep starts, a third of it arrives, then it is abandoned.
            let other = &frames[(i + 5) % FRAMES];
            let ot = stamps(other);
            let mut input = tried.begin_frame(Some((5.0, 5.1)));
            for (p, q) in other[..other.len() / 3].chunks(700).zip(ot.chunks(700)) {
                input.push(p, Some(q));
            }
        }
        let after = (
            *tried.last_pose(),
            *tried.last_delta(),
            tried.sigma(),
            tried.frames(),
        );
        assert_eq!(
            before, after,
            "frame {i}: state changed by an abandoned sweep"
        );
        assert_eq!((tried.high_water(), tried.source().to_vec()), (hw, source));
        // The merge buffer served the abandoned sweep: empty, never a mix of two scans.
        assert!(tried.merge_cloud().is_empty());

        let want = clean.register_frame(s, Some(&t)).unwrap();
        let got = tried.register_frame(s, Some(&t)).unwrap();
        assert_eq!(observe(&tried, got), observe(&clean, want), "frame {i}");
    }
}

#[test]
fn an_empty_scan_keeps_the_last_clouds() {
    let frames = scans();
    let mut words = vec![0u64; caps().arena_words::<f64, Exact>()];
    let mut odom =
        Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps(), &mut words[..]).unwrap();
    let r = odom.register_frame(&frames[0], None).unwrap();
    let kept = observe(&odom, r);
    assert!(odom.register_frame(&[[1e9, 0.0, 0.0]], None).is_err());
    let mut input = odom.begin_frame(None);
    input.push(&[[f64::NAN; 3]], None);
    assert!(input.finish().is_err());
    assert_eq!(observe(&odom, r), kept);
}

#[test]
fn the_last_frame_is_available_as_kiss_icp_returns_it() {
    let frames = scans();
    let cfg = Config::new(RANGE);
    let mut words = vec![0u64; caps().arena_words::<f64, Exact>()];
    let mut odom = Odometry::<f64, Exact, _>::new(cfg, caps(), &mut words[..]).unwrap();
    let mut last_pose = Pose::identity();
    let mut last_delta = Pose::identity();
    for (i, s) in frames.iter().enumerate() {
        let t = stamps(s);
        let r = odom.register_frame(s, Some(&t)).unwrap();
        // kiss-icp: last_delta = last_pose^-1 * new_pose, last_pose = new_pose.
        let delta = last_pose.inverse() * r.pose;
        assert!((odom.last_delta().to_homogeneous() - delta.to_homogeneous()).amax() < 1e-12);
        assert_eq!(*odom.last_pose(), r.pose);

        // The deskewed scan is the frame preprocessed with the motion before this frame.
        let mut deskewed = vec![[0.0; 3]; s.len()];
        let n = odom.deskewed_scan(s, Some(&t), &mut deskewed).kept;
        let mut want = vec![[0.0; 3]; s.len()];
        let m = preprocess(s, Some(&t), &last_delta, 0.0, RANGE, true, &mut want).kept;
        assert_eq!(&deskewed[..n], &want[..m], "frame {i}");

        // Both clouds are its downsamplings, in the reference's order.
        let caps = caps();
        let mut merge = vec![[0.0; 3]; caps.merge_points];
        let mut scratch = vec![0u64; scratch_words_for(caps.merge_points)];
        let v = cfg.voxel_size;
        let mk = voxel_downsample(&deskewed[..n], v * cfg.alpha, &mut merge, &mut scratch)
            .unwrap()
            .kept;
        assert_eq!(odom.merge_cloud(), &merge[..mk], "frame {i}");
        let mut source = vec![[0.0; 3]; caps.merge_points];
        let sk = voxel_downsample(&merge[..mk], v * cfg.beta, &mut source, &mut scratch)
            .unwrap()
            .kept;
        assert_eq!(odom.source(), &source[..sk], "frame {i}");
        assert_eq!(r.source_points as usize, sk);

        // The local map holds what the report says.
        let mut points = 0;
        odom.map().for_each_point(|_, _| points += 1);
        assert_eq!(
            (points, odom.map().voxels()),
            (r.map_points as usize, r.map_voxels as usize)
        );
        last_delta = *odom.last_delta();
        last_pose = r.pose;
    }
}

/// The first point of each voxel of size `v`, in the order `points` gives them.
fn first_seen(points: &[[f64; 3]], v: f64) -> Vec<[f64; 3]> {
    let mut out = vec![[0.0; 3]; points.len()];
    let mut scratch = vec![0u64; scratch_words_for(points.len())];
    let mut dedup = Dedup::new(&mut out, &mut scratch, v).unwrap();
    points.iter().for_each(|p| dedup.push(&(*p).into()));
    let kept = dedup.finish().kept;
    out.truncate(kept);
    out
}

fn sorted(mut points: Vec<[f64; 3]>) -> Vec<[f64; 3]> {
    points.sort_by(|a, b| a.partial_cmp(b).unwrap());
    points
}

#[test]
fn without_the_reference_order_both_clouds_keep_the_scan_order() {
    let frames = scans();
    let caps = caps();
    let scan_order = Config {
        reference_order: false,
        ..Config::new(RANGE)
    };
    let mut words = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut odom = Odometry::<f64, Exact, _>::new(scan_order, caps, &mut words[..]).unwrap();
    let mut words = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut reference =
        Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps, &mut words[..]).unwrap();
    let (v, mut reordered) = (scan_order.voxel_size, 0);
    for (i, s) in frames.iter().enumerate().take(3) {
        let t = stamps(s);
        odom.register_frame(s, Some(&t)).unwrap();
        reference.register_frame(s, Some(&t)).unwrap();
        let mut deskewed = vec![[0.0; 3]; s.len()];
        let n = odom.deskewed_scan(s, Some(&t), &mut deskewed).kept;
        let merge = first_seen(&deskewed[..n], v * scan_order.alpha);
        let source = first_seen(&merge, v * scan_order.beta);
        assert!(odom.merge_cloud() == &merge[..], "frame {i}: merge cloud");
        assert!(
            odom.source() == &source[..],
            "frame {i}: registration cloud"
        );
        // The reference's order of the same points, on the first frame (the poses part after
        // it: the map's points came in another order).
        if i == 0 {
            let (ours, theirs) = (
                odom.merge_cloud().to_vec(),
                reference.merge_cloud().to_vec(),
            );
            assert_eq!(sorted(ours.clone()), sorted(theirs.clone()));
            reordered += ours.iter().zip(&theirs).filter(|(a, b)| a != b).count();
        }
    }
    assert!(reordered > 0, "the reference's order is another");
}

fn widen(p: &Pose<f32>) -> Pose<f64> {
    nalgebra::convert(*p)
}

#[test]
fn robust_mode_needs_room_for_plane_terms_and_only_it_pays_for_them() {
    let (robust, caps) = (Config::<f64>::robust(RANGE), caps());
    let with = Capacities {
        plane_terms: true,
        ..caps
    };
    let mut words = vec![0u64; with.arena_words::<f64, Exact>()];
    let without = Odometry::<f64, Exact, _>::new(robust, caps, &mut words[..]).err();
    assert_eq!(without, Some(ConfigError::PlaneTerms));
    let mut odom = Odometry::<f64, Exact, _>::new(robust, with, &mut words[..]).unwrap();
    for scan in scans().iter().take(3) {
        assert!(odom.register_frame(scan, None).is_ok());
    }
    // The room: per 64 source points a second partial system and 64 cached planes (a voxel key
    // and a normal each), nothing else; reference mode does without it.
    let extra = with.arena_words::<f64, Exact>() - caps.arena_words::<f64, Exact>();
    let per_chunk = SYSTEM_LEN + 6 * CHUNK;
    assert_eq!(extra, chunks_for(caps.source_points) * per_chunk);
    let mut fewer = vec![0u64; caps.arena_words::<f64, Exact>()];
    assert!(Odometry::<f64, Exact, _>::new(Config::new(RANGE), caps, &mut fewer[..]).is_ok());
}

#[test]
fn a_dense_registration_cloud_is_made_again_with_voxels_scaled_to_the_desired_points() {
    // A street swept while the sensor's yaw swings (without the capture times): some
    // registrations measure every direction, some are flagged degenerate.
    use crate::redeskew::{pose, sweeps, SWEEP};
    let all: Vec<_> = sweeps().into_iter().map(|s| s.0).collect();
    let caps = plane_caps();
    let mut words = vec![0u64; caps.arena_words::<f64, Exact>()];
    let asked = Config {
        desired_source_points: 0,
        ..Config::<f64>::accurate(RANGE)
    };
    // Each frame's pose, registration cloud, merge cloud and whether it was flagged degenerate.
    type Run = Vec<(Pose<f64>, Vec<[f64; 3]>, Vec<[f64; 3]>, bool)>;
    let mut run = |desired_source_points| -> Run {
        let cfg = Config {
            desired_source_points,
            ..asked
        };
        let mut odom = Odometry::<f64, Exact, _>::new(cfg, caps, &mut words[..]).unwrap();
        all.iter()
            .map(|s| {
                let r = odom.register_frame(s, None).unwrap();
                let degenerate = r.status.contains(Flag::Degenerate);
                let clouds = (odom.source().to_vec(), odom.merge_cloud().to_vec());
                (r.pose, clouds.0, clouds.1, degenerate)
            })
            .collect()
    };
    let free = run(0);
    let most = free.iter().map(|f| f.1.len()).max().unwrap();
    let fewest = free.iter().map(|f| f.1.len()).min().unwrap();
    // A bound no frame reaches changes nothing, bit for bit.
    assert_eq!(run(most), free);
    // Below every frame's count: after a registration that measured every direction, each
    // cloud is the merge cloud's first point per voxel of `beta v` times the points `beta v`
    // keeps over the desired count, in the merge cloud's order (the preset keeps the scan's);
    // on the first two frames and after a registration flagged degenerate, every `beta v`
    // voxel's.
    assert!(!asked.reference_order);
    let desired = fewest / 2;
    let bound = run(desired);
    let beta_v = asked.voxel_size * asked.beta;
    let mut thinned = 0;
    for (i, (_, source, merge, _)) in bound.iter().enumerate() {
        let every = first_seen(merge, beta_v);
        let n = every.len();
        assert!(n > desired, "frame {i}: {n} points at beta v");
        let expected = if i < 2 || bound[i - 1].3 {
            every
        } else {
            thinned += 1;
            let coarser = first_seen(merge, beta_v * (n as f64 / desired as f64));
            assert!(coarser.len() < n, "frame {i}: {} of {n}", coarser.len());
            coarser
        };
        assert!(
            *source == expected,
            "frame {i}: {} points, {} expected",
            source.len(),
            expected.len()
        );
    }
    let kept = all.len() - 2 - thinned;
    println!("{thinned} frames thinned, {kept} after a degenerate registration");
    assert!(thinned >= 5 && kept >= 2, "both kinds of frame");
    assert_eq!(bound[..3], free[..3], "the first three frames are the same");
    // The run still follows the street.
    let worst = |r: &Run| {
        r.iter()
            .enumerate()
            .map(|(i, f)| gap(&f.0, &(pose(0.0).inverse() * pose(i as f64 * SWEEP))))
            .fold(0.0, f64::max)
    };
    let (b, f) = (worst(&bound), worst(&free));
    println!("worst position error: thinned {b:.4} m, every voxel {f:.4} m (bound 2x + 1 cm)");
    assert!(b < 2.0 * f + 0.01, "{b} against {f}");
}

/// Capacities with room for plane terms and a registration cloud as large as the merge cloud.
fn plane_caps() -> Capacities {
    Capacities {
        plane_terms: true,
        source_points: caps().merge_points,
        ..caps()
    }
}

/// `scans` through the `accurate` preset for a 100 m sensor (0.5 m voxels: the street's 0.3 m
/// sampling leaves too few points for a plane in the 27 voxels around a point at 40 m's 0.2 m),
/// changed by `with`: each frame's report and the last registration
/// cloud.
fn accurate_on(
    scans: &[Vec<[f64; 3]>],
    with: impl FnOnce(Config<f64>) -> Config<f64>,
) -> (Vec<FrameReport<f64>>, Vec<[f64; 3]>) {
    let caps = plane_caps();
    let cfg = with(Config::<f64>::accurate(100.0));
    let mut words = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut odom = Odometry::<f64, Exact, _>::new(cfg, caps, &mut words[..]).unwrap();
    let reports = scans
        .iter()
        .map(|s| odom.register_frame(s, None).unwrap())
        .collect();
    (reports, odom.source().to_vec())
}

#[test]
fn the_first_registration_starts_from_the_thinned_clouds_when_that_measured_every_direction() {
    // The street's sensor moves 0.8 m between the first two frames and the prediction stands
    // still: the first registration is the one that iterates longest.
    let scans = scans();
    let frame_1 = |desired_source_points, work_budget| {
        let (reports, cloud) = accurate_on(&scans[..2], |c| Config {
            desired_source_points,
            work_budget,
            ..c
        });
        let r = reports[1];
        assert!(
            !r.status.contains(Flag::Degenerate),
            "a street measures every direction"
        );
        (r, cloud)
    };
    let (every, every_cloud) = frame_1(0, None);
    let desired = every_cloud.len() / 4;
    let (coarse, coarse_cloud) = frame_1(desired, None);
    // The frame is registered on every voxel, from where the thinned cloud's registration
    // ended: the same cloud, the same optimum to well under a millimetre, for less work.
    assert_eq!(
        coarse_cloud, every_cloud,
        "the frame's cloud keeps every voxel"
    );
    assert_ne!(
        coarse.pose, every.pose,
        "the thinned cloud's registration was the start"
    );
    let apart = gap(&coarse.pose, &every.pose);
    let truth = error_at(&every.pose, 1);
    println!(
        "frame 1: {} points, from the thinned cloud ({desired} desired) {apart:.2e} m from a \
         start at the prediction (bound 1e-4 m; that one is {truth:.2e} m from the truth); \
         work {} against {}, iterations {} against {}",
        every_cloud.len(),
        coarse.work,
        every.work,
        coarse.iterations,
        every.iterations
    );
    assert!(apart < 1e-4, "{apart}");
    assert!(
        2 * coarse.work < every.work,
        "{} against {}",
        coarse.work,
        every.work
    );
    // A work budget bounds one registration: the first starts from the prediction.
    let budget = Some(every.work * 2);
    assert_eq!(frame_1(desired, budget).0.pose, frame_1(0, budget).0.pose);
}

#[test]
fn only_the_first_registration_is_run_twice_and_its_report_counts_both() {
    // One iteration a registration: frame 1 runs the thinned start and every voxel, each later
    // frame one registration.
    let scans = scans();
    let run = |desired_source_points| {
        let with = |c| Config {
            desired_source_points,
            max_iterations: 1,
            ..c
        };
        accurate_on(&scans[..6], with).0
    };
    let every = run(0);
    let desired = every[1].correspondences as usize / 4;
    let thinned = run(desired);
    let iterations: Vec<u32> = thinned.iter().map(|r| r.iterations).collect();
    println!(
        "iterations {iterations:?}; frame 1's work {} against {} on every voxel alone",
        thinned[1].work, every[1].work
    );
    assert_eq!(iterations, [0, 2, 1, 1, 1, 1]);
    assert!(thinned[1].work > every[1].work, "both registrations' work");
    // A cloud of exactly the desired count is not thinned, so it starts from the prediction.
    let exact = run(every[1].source_points as usize);
    assert_eq!((exact[1].iterations, exact[1].pose), (1, every[1].pose));
}

/// A scan of flat ground and nothing else, the street's, 1.8 m below the sensor, out to 40 m.
fn ground_only() -> Vec<[f64; 3]> {
    let mut rng = Rng(5);
    (0..20_000)
        .map(|_| {
            let (r, a) = (
                3.0 + 37.0 * rng.uniform(),
                std::f64::consts::TAU * rng.uniform(),
            );
            [
                r * a.cos(),
                r * a.sin(),
                -1.8 + 0.02 * (rng.uniform() - 0.5),
            ]
        })
        .collect()
}

#[test]
fn robust_mode_holds_a_scan_of_one_plane_to_the_prediction_and_flags_it() {
    let mut scans = scans()[..6].to_vec();
    scans[4] = ground_only();
    let (reports, _) = accurate_on(&scans, |c| c);
    let (r2, r3, r4) = (reports[2].pose, reports[3].pose, reports[4].pose);
    let prediction = r3 * (r2.inverse() * r3);
    let held = gap(&r4, &prediction);
    println!(
        "the ground-only frame: {held:.1e} m from the constant-velocity prediction (bound \
         1e-9 m), {:.3} m from the truth",
        error_at(&r4, 4)
    );
    assert!(held < 1e-9, "{held}");
    let s = reports[4].status;
    assert!(
        s.contains(Flag::OnePlane) && s.contains(Flag::Degenerate),
        "{s:?}"
    );
    assert!(!s.contains(Flag::NoCorrespondences), "{s:?}");
    assert_eq!(reports[4].iterations, 0);
    for (i, r) in reports.iter().enumerate().filter(|(i, _)| *i != 4) {
        assert!(
            !r.status.contains(Flag::OnePlane),
            "frame {i}: {:?}",
            r.status
        );
    }
    // The street after it is registered again, from the held pose.
    assert!(error_at(&reports[5].pose, 5) < 0.05);
    // Reference mode registers every scan, as the reference does.
    let mut words = vec![0u64; caps().arena_words::<f64, Exact>()];
    let mut odom =
        Odometry::<f64, Exact, _>::new(Config::new(100.0), caps(), &mut words[..]).unwrap();
    for s in &scans {
        let r = odom.register_frame(s, None).unwrap();
        assert!(!r.status.contains(Flag::OnePlane));
    }
}
