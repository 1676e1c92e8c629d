//! The per-frame work budget through the tool: on the hardest inputs we have
//! (generated fast and corridor drives, kitti-mini, scenes of random points) no frame's counted
//! work (`frames.csv` `work`) exceeds `--budget`, the frames it stopped are flagged and counted,
//! the frames before the first stop are the unbudgeted run's bit for bit, and the thread count
//! changes nothing.

use kiss_odom_tests::{repo, run, Run};
use std::path::{Path, PathBuf};

/// The microcontroller configuration the budget is meant for (as `bench/budget.sh`).
const SMALL: [&str; 10] = [
    "--set",
    "capacities=small",
    "--set",
    "runtime.scalar=f32",
    "--set",
    "runtime.map_storage=quantized",
    "--max-range",
    "50",
    "--set",
    "mapping.voxel_size=1",
];

fn simulate(dir: &Path, profile: &str, seed: &str, frames: &str) -> PathBuf {
    let out = dir.join(format!("{profile}-{seed}"));
    let argv = [
        "kiss-odom",
        "simulate",
        "--out",
        &out.to_string_lossy(),
        "--frames",
        frames,
        "--seed",
        seed,
        "--profile",
        profile,
    ];
    let mut err = Vec::new();
    let code = kiss_odom::cli::main_with(argv.iter().map(Into::into).collect(), &mut err);
    assert_eq!(code, 0, "{}", String::from_utf8_lossy(&err));
    out
}

/// Frames of points drawn uniformly in a box, a new draw each frame: nothing to register
/// against, so ICP works until its cap unless the budget stops it.
fn random_scenes(dir: &Path, frames: usize, points: usize) -> PathBuf {
    let out = dir.join("random");
    std::fs::create_dir_all(&out).unwrap();
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut rnd = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f32 / (1u64 << 53) as f32
    };
    for k in 0..frames {
        let mut bytes = Vec::with_capacity(points * 16);
        for _ in 0..points {
            let p = [
                rnd() * 80.0 - 40.0,
                rnd() * 80.0 - 40.0,
                rnd() * 6.0 - 3.0,
                0.0,
            ];
            bytes.extend(p.iter().flat_map(|v| v.to_le_bytes()));
        }
        std::fs::write(out.join(format!("{k:06}.bin")), bytes).unwrap();
    }
    out
}

fn numbers(r: &Run, column: &str) -> Vec<Option<u64>> {
    r.column(column).iter().map(|v| v.parse().ok()).collect()
}

/// Runs `input` without and with `budget` (and with the budget on one and two threads), and
/// checks the budget's promises. Returns the unbudgeted run's worst frame.
fn check(dir: &Path, name: &str, input: &Path, extra: &[&str], budget: u64) -> u64 {
    let b = format!("registration.work_budget={budget}");
    let free = run(input, &dir.join(format!("{name}-free")), extra);
    let mut with: Vec<&str> = extra.to_vec();
    with.extend(["--set", &b, "--threads", "1"]);
    let capped = run(input, &dir.join(format!("{name}-capped")), &with);
    with.pop();
    with.push("2");
    let capped2 = run(input, &dir.join(format!("{name}-capped2")), &with);
    for r in [&free, &capped, &capped2] {
        assert_eq!(r.code, 0, "{name}: {}", r.stderr);
    }

    let work = numbers(&capped, "work");
    let worst = work.iter().flatten().copied().max().unwrap_or(0);
    let free_worst = numbers(&free, "work").iter().flatten().copied().max();
    let free_worst = free_worst.unwrap_or(0);
    let stopped = capped.column("budget");
    let n_stopped = stopped.iter().filter(|v| *v == "1").count();
    println!(
        "{name}: budget {budget}: worst frame work {worst} (unbudgeted {free_worst}), \
         {n_stopped} of {} frames stopped",
        work.len()
    );
    assert!(worst <= budget, "{name}: a frame spent {worst} > {budget}");
    // Every frame over the budget without it is stopped with it, and only those can be.
    let first_stop = stopped.iter().position(|v| v == "1");
    if free_worst > budget {
        assert!(n_stopped > 0, "{name}: over the budget and never stopped");
    }
    let summary = capped.summary();
    let counted = summary["degraded_frames"]["budget"].as_u64().unwrap_or(0);
    assert_eq!(
        counted as usize, n_stopped,
        "{name}: summary counts the stops"
    );

    // Up to the first stop, the budget changed nothing.
    let (a, b) = (
        free.lines("poses_kitti.txt"),
        capped.lines("poses_kitti.txt"),
    );
    let same = first_stop.unwrap_or(a.len());
    assert_eq!(a[..same], b[..same], "{name}: frames before the first stop");
    // The same stops on any thread count.
    assert_eq!(
        capped.lines("poses_kitti.txt"),
        capped2.lines("poses_kitti.txt"),
        "{name}: one and two threads"
    );
    assert_eq!(
        stopped,
        capped2.column("budget"),
        "{name}: same frames stopped"
    );
    free_worst
}

#[test]
fn no_frame_of_the_hardest_inputs_spends_more_than_its_budget() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let kitti = repo().join("../shared/data/kitti-mini/sequences/01");
    let mut over = 0;
    let mut inputs: Vec<(&str, PathBuf, u64)> = vec![
        ("fast", simulate(d, "fast", "5", "40"), 150_000),
        ("corridor", simulate(d, "corridor", "3", "40"), 30_000),
        ("random", random_scenes(d, 12, 20_000), 150_000),
    ];
    if kitti.is_dir() {
        inputs.push(("kitti-mini-01", kitti, 150_000));
    } else {
        println!("SKIP kitti-mini 01: {} not found", kitti.display());
    }
    for (name, input, budget) in &inputs {
        let worst = check(d, name, input, &SMALL, *budget);
        over += usize::from(worst > *budget);
    }
    // The full-scale f64 build on the shipped sample, with a budget a frame hits.
    let sample = repo().join("fixtures/kitti-05-reduced");
    over += usize::from(check(d, "sample-f64", &sample, &[], 100_000) > 100_000);
    assert!(
        over >= 4,
        "the budgets must bind on most inputs to test anything ({over})"
    );
}
