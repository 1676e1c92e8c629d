//! ROS 1 bags and ROS 2 MCAP files that are out of time order or damaged, run end
//! to end through `kiss-odom run`. The fixtures were written by the Python `rosbags` library
//! (`fixtures/bags/make_bags.py`), independent of our readers: `out_of_order.*` holds the
//! Ouster-style clouds of frames 0..5 written in the order 0, 2, 1, 4, 3, each with the
//! receive time and header stamp of its frame; `ouster.*` holds frames 0..4 in order.

use kiss_odom_tests::{repo, run};
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    repo().join("fixtures/bags").join(name)
}

/// A bag (or MCAP file) recorded out of time order is read in time order, with a warning: in
/// file order its TUM times would go backwards.
#[test]
fn bags_and_mcap_files_out_of_time_order_are_read_in_time_order_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["bag", "mcap"] {
        let path = fixture(&format!("out_of_order.{ext}"));
        let r = run(&path, &dir.path().join(format!("out-{ext}")), &[]);
        r.ok().warning_with(&[
            &path.display().to_string(),
            "not in time order",
            "message 2",
        ]);
        let want: Vec<f64> = (0..5u32)
            .map(|k| f64::from(1_700_000_000 + k) + f64::from(k) * 0.1)
            .collect();
        let got = r.tum_times();
        assert_eq!(got.len(), 5, "{ext}");
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() < 1e-6, "{ext}: times {got:?}, want {want:?}");
        }
        // The same clouds in order (ouster.*, another topic) give the same poses.
        let inorder = run(
            &fixture(&format!("ouster.{ext}")),
            &dir.path().join(format!("out-inorder-{ext}")),
            &[],
        );
        inorder.ok();
        assert_eq!(
            r.lines("poses_kitti.txt")[..4],
            inorder.lines("poses_kitti.txt")[..4],
            "{ext}: frames 0..4"
        );
    }
}

/// A ROS 1 bag cut inside its first chunk is reported as damaged, not as a bag with no
/// PointCloud2 topic.
#[test]
fn a_bag_cut_inside_its_first_chunk_is_reported_as_damaged() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(fixture("ouster.bag")).unwrap();
    let chunk = bytes
        .windows(4)
        .position(|w| w == b"op=\x05")
        .expect("a chunk record");
    let path = dir.path().join("cut-first-chunk.bag");
    std::fs::write(&path, &bytes[..chunk + 200]).unwrap();
    let r = run(&path, &dir.path().join("out"), &[]);
    let line = r.failed_with(&[&path.display().to_string(), "damaged", "cut short"]);
    assert!(!line.contains("no sensor_msgs/PointCloud2 topic"), "{line}");
}

/// The chunk compressions rosbag writes (bz2, lz4), read by our container reader, give the
/// frames of the uncompressed bag.
#[test]
fn bz2_and_lz4_chunks_give_the_frames_of_the_uncompressed_bag() {
    let dir = tempfile::tempdir().unwrap();
    let plain = run(&fixture("ouster.bag"), &dir.path().join("out-plain"), &[]);
    plain.ok();
    for c in ["bz2", "lz4"] {
        let r = run(
            &fixture(&format!("ouster_{c}.bag")),
            &dir.path().join(format!("out-{c}")),
            &[],
        );
        r.ok();
        assert_eq!(
            r.lines("poses_tum.txt"),
            plain.lines("poses_tum.txt"),
            "{c}"
        );
    }
}
