//! The accurate preset's cycle stop on real KITTI frames: on kitti-mini 02, frame 4's
//! registration with plane terms goes round a loop of two iterates 0.14 mm apart that
//! `|dx| < gamma` never ends. With the stop it ends in the loop; without it (`cycle_stop =
//! false`), it runs to the iteration cap (both with every voxel of the registration cloud,
//! `desired_source_points = 0`, in the reference's order). And the map it picks from the
//! first scan's density, and the second deskew where a scan's motion was not the model's.

use kiss_odom_tests::{repo, run, simulate, Run};

#[test]
fn the_accurate_preset_stops_a_registration_that_loops_before_the_cap() {
    let seq = repo().join("../shared/data/kitti-mini/sequences/02");
    let tmp = tempfile::tempdir().unwrap();
    // Every `beta v` voxel of the registration cloud, in the reference's order: the loop is
    // that cloud's.
    let full = "[mapping]\ndesired_source_points = 0\nreference_order = true\n";
    let (on, off) = (tmp.path().join("on.toml"), tmp.path().join("off.toml"));
    std::fs::write(&on, full).unwrap();
    std::fs::write(&off, format!("{full}[registration]\ncycle_stop = false\n")).unwrap();
    let frames = ["--frames", "0..5", "--preset", "accurate", "--threads", "1"];
    let with = run(
        &seq,
        &tmp.path().join("with"),
        &[&frames[..], &["--config", on.to_str().unwrap()]].concat(),
    );
    let config = ["--config", off.to_str().unwrap()];
    let without = run(
        &seq,
        &tmp.path().join("without"),
        &[&frames[..], &config].concat(),
    );
    let (stopped, capped) = (
        numbers(&with, "iterations"),
        numbers(&without, "iterations"),
    );
    println!("iterations with the cycle stop {stopped:?}, without {capped:?}");
    assert_eq!(capped[4], 500, "without the stop, frame 4 runs to the cap");
    assert!(stopped[4] < 50, "the stop ends frame 4's loop");
    assert_eq!(
        with.column("iteration_cap")[4],
        "0",
        "a loop ended is not flagged capped"
    );
    assert_eq!(without.column("iteration_cap")[4], "1");
    // The frames before it converge by |dx| < gamma alone: the same iterations and poses.
    assert_eq!(stopped[..4], capped[..4]);
    assert_eq!(
        with.lines("poses_kitti.txt")[..4],
        without.lines("poses_kitti.txt")[..4]
    );
    // The preset itself thins these dense scans' registration clouds toward 3,000 points
    // from the third frame (after a registration that measured every direction).
    let thinned = run(&seq, &tmp.path().join("thinned"), &frames);
    let column = "source_points";
    let (every, bound) = (numbers(&with, column), numbers(&thinned, column));
    println!("registration cloud points: every voxel {every:?}, the preset {bound:?}");
    assert!(every.iter().all(|&n| n > 3_000));
    assert_eq!(
        bound[..2],
        every[..2],
        "the first two frames keep every voxel"
    );
    assert!(bound[2..].iter().all(|&n| n <= 3_000), "{bound:?}");
}

/// A `frames.csv` column of a successful run, as numbers.
fn numbers(r: &Run, column: &str) -> Vec<u32> {
    r.ok();
    r.column(column)
        .iter()
        .map(|v| v.parse().unwrap())
        .collect()
}

/// `summary.json`'s map: voxel size, points a voxel, and whether the sparse-scan map was taken;
/// a run warns (once) exactly when it was.
fn map_of(r: &Run) -> (f64, u64, bool) {
    r.ok();
    let m = r.summary()["map"].clone();
    println!("{m}");
    let sparse = m["sparse_scan"].as_bool().unwrap();
    let warned = r
        .stderr
        .matches("fewer than [mapping] sparse_scan_points")
        .count();
    assert_eq!(warned, usize::from(sparse), "{}", r.stderr);
    (
        m["voxel_size"].as_f64().unwrap(),
        m["max_points_per_voxel"].as_u64().unwrap(),
        sparse,
    )
}

#[test]
fn the_accurate_preset_maps_a_sparse_sensor_on_genz_icp_s_sparse_sensor_map() {
    let tmp = tempfile::tempdir().unwrap();
    let vlp = tmp.path().join("vlp16");
    let sensor = ["--frames", "3", "--seed", "5", "--profile", "urban"];
    simulate(&vlp, &[&sensor[..], &["--sensor", "vlp16"]].concat());
    let accurate = ["--preset", "accurate", "--threads", "1"];
    // A 16-beam sweep (under 28,800 points): 1.2 times the preset's 0.5 m voxels, 3 points each.
    let sparse = map_of(&run(&vlp, &tmp.path().join("a"), &accurate));
    assert_eq!((sparse.1, sparse.2), (3, true));
    assert!((sparse.0 - 0.6).abs() < 1e-12);
    // The warning names the map's voxel as the core holds it, in f32 too, and the registration
    // settings that the map puts in place of the configured ones.
    let f32 = run(
        &vlp,
        &tmp.path().join("f"),
        &[&accurate[..], &["--set", "runtime.scalar=f32"]].concat(),
    );
    map_of(&f32);
    for said in [
        "maps on 0.6 m voxels of at most 3 points",
        "with beta 1 and plane_kernel_scale 0.01 (the sparse-sensor map, in place of",
    ] {
        assert!(f32.stderr.contains(said), "{said:?} in {}", f32.stderr);
    }
    // The reference keeps its map whatever the scan.
    assert_eq!(
        map_of(&run(&vlp, &tmp.path().join("d"), &["--threads", "1"])),
        (1.0, 20, false)
    );
    // A 64-beam KITTI sweep (124k points) keeps the preset's map...
    let seq = repo().join("../shared/data/kitti-mini/sequences/02");
    let two = [&accurate[..], &["--frames", "0..2"]].concat();
    assert_eq!(
        map_of(&run(&seq, &tmp.path().join("k"), &two)),
        (0.5, 20, false)
    );
    // ...unless the bound, a setting, is above it.
    let above = tmp.path().join("above.toml");
    std::fs::write(&above, "[mapping]\nsparse_scan_points = 1000000\n").unwrap();
    let config = ["--config", above.to_str().unwrap()];
    let moved = map_of(&run(
        &seq,
        &tmp.path().join("m"),
        &[&two[..], &config].concat(),
    ));
    assert_eq!((moved.1, moved.2), (3, true));
}

#[test]
fn the_accurate_preset_deskews_a_scan_again_where_the_motion_changed() {
    let tmp = tempfile::tempdir().unwrap();
    let fast = tmp.path().join("fast");
    simulate(
        &fast,
        &["--frames", "12", "--seed", "5", "--profile", "fast"],
    );
    let again = |r: &Run| -> usize {
        r.ok();
        r.column("redeskewed")
            .iter()
            .filter(|v| *v == "true")
            .count()
    };
    let accurate = [
        "--preset",
        "accurate",
        "--threads",
        "1",
        "--frames",
        "0..12",
    ];
    let preset = run(&fast, &tmp.path().join("a"), &accurate);
    let once = tmp.path().join("once.toml");
    std::fs::write(&once, "[data]\nredeskew = false\n").unwrap();
    let config = ["--config", once.to_str().unwrap()];
    let off = run(
        &fast,
        &tmp.path().join("o"),
        &[&accurate[..], &config].concat(),
    );
    let default = run(&fast, &tmp.path().join("d"), &["--threads", "1"]);
    let counts = (again(&preset), again(&off), again(&default));
    println!("frames deskewed twice: preset, preset without, default: {counts:?}");
    assert!(
        counts.0 > 0 && counts.0 < 12,
        "not the first frame, which has no map"
    );
    assert_eq!((counts.1, counts.2), (0, 0));
    // Frames before the first second pass are the same; the one that has it is not.
    let first = preset
        .column("redeskewed")
        .iter()
        .position(|v| v == "true")
        .unwrap();
    let (p, o) = (
        preset.lines("poses_kitti.txt"),
        off.lines("poses_kitti.txt"),
    );
    assert_eq!(p[..first], o[..first]);
    assert_ne!(p[first], o[first]);
}
