//! IMU samples from every place a run takes them, end to end: a simulated drone flight written
//! as a folder (`imu.csv`), a ROS 1 bag and an MCAP file (`sensor_msgs/Imu` on `/imu`) gives
//! the same poses with `run --imu auto` from each, and the prior is used on every frame after
//! the first; `--imu FILE` gives a bag without an IMU topic the folder's samples; a topic the
//! file does not have is an error naming the ones it has.

use kiss_odom_tests::{run, Run};
use std::path::Path;

/// 30 frames of a drone flight (seed 41) into `dir`, as the folder and `format`; with an IMU
/// at 200 Hz if `imu`.
fn simulate(dir: &Path, format: &str, imu: bool) {
    let mut args = vec![
        "--profile",
        "drone",
        "--seed",
        "41",
        "--frames",
        "30",
        "--beams",
        "32",
        "--columns",
        "512",
        "--format",
        format,
    ];
    if imu {
        args.extend(["--imu-rate", "200"]);
    }
    kiss_odom_tests::simulate(dir, &args);
}

/// The prior was used on every frame after the first.
fn used_after_the_first(r: &Run, what: &str) {
    let states = r.column("imu_prior");
    assert_eq!(states.len(), 30, "{what}");
    assert_eq!(states[0], "first", "{what}");
    assert!(
        states[1..].iter().all(|s| s == "used"),
        "{what}: {states:?}"
    );
}

#[test]
fn a_bag_and_an_mcap_file_with_an_imu_topic_give_the_folders_poses() {
    let tmp = tempfile::tempdir().unwrap();
    let (bag, mcap) = (tmp.path().join("bag"), tmp.path().join("mcap"));
    simulate(&bag, "bag", true);
    simulate(&mcap, "mcap", true);
    let folder = run(&bag, &tmp.path().join("folder-run"), &["--imu", "auto"]);
    let poses = folder.ok().lines("poses_kitti.txt");
    used_after_the_first(&folder, "folder");
    let samples = folder.column("imu_samples");
    let off = run(&bag, &tmp.path().join("off-run"), &[]);
    assert_ne!(
        off.ok().lines("poses_kitti.txt"),
        poses,
        "the prior changes the poses"
    );
    for (file, name) in [
        (bag.join("points.bag"), "bag"),
        (mcap.join("points.mcap"), "mcap"),
    ] {
        let r = run(
            &file,
            &tmp.path().join(format!("{name}-run")),
            &["--imu", "auto"],
        );
        assert_eq!(r.ok().number("warnings"), 0.0, "{name}: {}", r.stderr);
        used_after_the_first(&r, name);
        // The same samples with every frame, the same poses, bit for bit.
        assert_eq!(r.column("imu_samples"), samples, "{name}");
        assert_eq!(r.lines("poses_kitti.txt"), poses, "{name}");
        println!("{name}: 30 poses equal to the folder's, imu_samples {samples:?}");
        // The topic by name is the same topic.
        let named = run(
            &file,
            &tmp.path().join(format!("{name}-named")),
            &["--imu", "/imu"],
        );
        assert_eq!(
            named.ok().lines("poses_kitti.txt"),
            poses,
            "{name} --imu /imu"
        );
        // A topic the file does not have is refused, naming the IMU topics it has.
        let nope = run(
            &file,
            &tmp.path().join(format!("{name}-nope")),
            &["--imu", "/nope"],
        );
        nope.failed_with(&["no topic /nope", "IMU topics: /imu"]);
    }
    // Without --imu a recording's IMU topic changes nothing.
    let bag_off = run(&bag.join("points.bag"), &tmp.path().join("bag-off"), &[]);
    assert_eq!(
        bag_off.ok().lines("poses_kitti.txt"),
        off.lines("poses_kitti.txt")
    );
    assert!(bag_off.column("imu_prior").iter().all(String::is_empty));
}

#[test]
fn an_imu_csv_given_with_a_bag_without_an_imu_topic_gives_the_folders_poses() {
    let tmp = tempfile::tempdir().unwrap();
    let (with, without) = (tmp.path().join("with"), tmp.path().join("without"));
    simulate(&with, "generic", true);
    simulate(&without, "bag", false);
    let folder = run(&with, &tmp.path().join("folder-run"), &["--imu", "auto"]);
    let csv = with.join("imu.csv");
    let bag = without.join("points.bag");
    let r = run(
        &bag,
        &tmp.path().join("bag-run"),
        &["--imu", csv.to_str().unwrap()],
    );
    used_after_the_first(&r, "bag with --imu FILE");
    assert_eq!(r.column("imu_samples"), folder.ok().column("imu_samples"));
    assert_eq!(r.lines("poses_kitti.txt"), folder.lines("poses_kitti.txt"));
    // `auto` finds no IMU topic in it: every frame goes without.
    let auto = run(&bag, &tmp.path().join("bag-auto"), &["--imu", "auto"]);
    let states = auto.ok().column("imu_prior");
    assert!(states[1..].iter().all(|s| s == "no_samples"), "{states:?}");
    // A topic name for a folder, which has none.
    let topic = run(&with, &tmp.path().join("folder-topic"), &["--imu", "/imu"]);
    topic.failed_with(&["--imu /imu", "not a bag or MCAP file"]);
}
