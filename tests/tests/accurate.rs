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

/// `summary.json`'s map: voxel size and points a voxel.
fn map_of(r: &Run) -> (f64, u64) {
    r.ok();
    let m = r.summary()["map"].clone();
    println!("{m}");
    (
        m["voxel_size"].as_f64().unwrap(),
        m["max_points_per_voxel"].as_u64().unwrap(),
    )
}

#[test]
fn the_accurate_preset_maps_a_sparse_and_a_dense_sensor_on_the_same_finer_map() {
    let tmp = tempfile::tempdir().unwrap();
    let vlp = tmp.path().join("vlp16");
    let sensor = ["--frames", "3", "--seed", "5", "--profile", "urban"];
    simulate(&vlp, &[&sensor[..], &["--sensor", "vlp16"]].concat());
    let accurate = ["--preset", "accurate", "--threads", "1"];
    // A 16-beam sweep: the preset's `r_max / 200` voxels (0.5 m at 100 m), 20 points each.
    let sparse = run(&vlp, &tmp.path().join("a"), &accurate);
    assert_eq!(map_of(&sparse), (0.5, 20));
    assert!(sparse.warnings().is_empty(), "{}", sparse.stderr);
    // The reference keeps its own.
    assert_eq!(
        map_of(&run(&vlp, &tmp.path().join("d"), &["--threads", "1"])),
        (1.0, 20)
    );
    // A 64-beam KITTI sweep (124k points) maps as the 16-beam one does.
    let seq = repo().join("../shared/data/kitti-mini/sequences/02");
    let two = [&accurate[..], &["--frames", "0..2"]].concat();
    assert_eq!(map_of(&run(&seq, &tmp.path().join("k"), &two)), (0.5, 20));
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
