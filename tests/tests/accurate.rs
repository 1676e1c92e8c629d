//! The accurate preset's cycle stop on real KITTI frames: on kitti-mini 02, frame 4's
//! registration with plane terms goes round a loop of two iterates 0.14 mm apart that
//! `|dx| < gamma` never ends. With the stop it ends in the loop; without it (`cycle_stop =
//! false`), it runs to the iteration cap.

use kiss_odom_tests::{repo, run};

#[test]
fn the_accurate_preset_stops_a_registration_that_loops_before_the_cap() {
    let seq = repo().join("../shared/data/kitti-mini/sequences/02");
    let tmp = tempfile::tempdir().unwrap();
    let off = tmp.path().join("off.toml");
    std::fs::write(&off, "[registration]\ncycle_stop = false\n").unwrap();
    let frames = ["--frames", "0..5", "--preset", "accurate", "--threads", "1"];
    let with = run(&seq, &tmp.path().join("with"), &frames);
    let config = ["--config", off.to_str().unwrap()];
    let without = run(
        &seq,
        &tmp.path().join("without"),
        &[&frames[..], &config].concat(),
    );
    let iterations = |r: &kiss_odom_tests::Run| -> Vec<u32> {
        r.ok();
        r.column("iterations")
            .iter()
            .map(|v| v.parse().unwrap())
            .collect()
    };
    let (stopped, capped) = (iterations(&with), iterations(&without));
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
}
