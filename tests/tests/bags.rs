//! The ROS 1 bag and ROS 2 MCAP readers against files written by another implementation.
//!
//! `fixtures/bags/*.bag|*.mcap` were written by the Python `rosbags` 0.11.9 library
//! (`fixtures/bags/make_bags.py`), so a mistake shared by our reader and our own test writers
//! (in `host/io/src/ros/{bag,mcap}.rs`) cannot pass here. Every expected value below is the
//! formula of that script, recomputed; nothing is read back through the decoder under test.
//! Files are opened through `kiss_odom_io::open` with `--format auto`, the path `kiss-odom run`
//! takes.

use kiss_odom_io::{self as io, Dataset, Format, Frame, Item, OpenOptions};
use std::path::{Path, PathBuf};

const STAMP0: u32 = 1_700_000_000;
/// Points per frame in every fixture.
const N: usize = 16;
const EXTS: [&str; 2] = ["bag", "mcap"];

fn fixture(case: &str, ext: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures/bags")
        .join(format!("{case}.{ext}"))
}

fn open(path: &Path, topic: Option<&str>) -> Result<Dataset, String> {
    let opts = OpenOptions {
        topic: topic.map(String::from),
        ..OpenOptions::default()
    };
    io::open(path, Format::Auto, &opts).map_err(|e| format!("{e:#}"))
}

fn open_ok(path: &Path, topic: Option<&str>) -> Dataset {
    open(path, topic).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn open_err(path: &Path, topic: Option<&str>) -> String {
    match open(path, topic) {
        Ok(_) => panic!("{}: opened, expected an error", path.display()),
        Err(e) => e,
    }
}

/// Reads the stream to its end: the items, and the error that ended it, if any.
fn drain(dataset: &mut Dataset) -> (Vec<Item>, Option<String>) {
    let mut items = Vec::new();
    loop {
        match dataset.frames.next_item() {
            Ok(Some(item)) => items.push(item),
            Ok(None) => return (items, None),
            Err(e) => return (items, Some(format!("{e:#}"))),
        }
    }
}

fn frame(item: &Item) -> &Frame {
    match item {
        Item::Frame(f) => f,
        Item::Skipped { reason, .. } => panic!("unexpected skip: {reason}"),
    }
}

/// Header stamp of frame `k`: STAMP0 + k s and k * 0.1 s in nanoseconds.
fn check_stamp(f: &Frame, path: &Path, topic: &str, k: u32) {
    let (sec, nsec) = (STAMP0 + k, 100_000_000 * k);
    let want = f64::from(sec) + f64::from(nsec) * 1e-9;
    let got = f.time.expect("frame time");
    assert!(
        (got - want).abs() < 1e-6,
        "frame {k}: time {got} want {want}"
    );
    let name = format!("{}:{topic}@{sec}.{nsec:09}", path.display());
    assert_eq!(f.name, name);
}

/// `ouster(k)` of make_bags.py: x = k + i/8, y = -i/4, z = 0.5 + k/2, t = i/32; point 0 of
/// frame 1 is NaN.
fn check_ouster(f: &Frame, k: u32) {
    assert_eq!(f.points.len(), N, "NaN points are kept, not dropped");
    for (i, p) in f.points.iter().enumerate() {
        if k == 1 && i == 0 {
            assert!(p.iter().all(|v| v.is_nan()), "{p:?}");
            continue;
        }
        let i = i as f64;
        let k = f64::from(k);
        assert_eq!(
            *p,
            [k + i / 8.0, -i / 4.0, 0.5 + k / 2.0],
            "frame {k} point {i}"
        );
    }
    let want: Vec<f64> = (0..N).map(|i| i as f64 / 32.0).collect();
    assert_eq!(f.stamps.as_deref(), Some(&want[..]));
}

/// `abs_time(k)`: x = -k - i/8, y = i/4, z = 1, timestamp = 1700000000.0 + k * 0.1 + i * 1e-4 (f64).
fn check_abs_time(f: &Frame, k: u32) {
    let kf = f64::from(k);
    let want: Vec<[f64; 3]> = (0..N)
        .map(|i| [-kf - i as f64 / 8.0, i as f64 / 4.0, 1.0])
        .collect();
    assert_eq!(f.points, want, "frame {k}");
    let times: Vec<f64> = (0..N)
        .map(|i| 1700000000.0 + kf * 0.1 + i as f64 * 1e-4)
        .collect();
    // Python and Rust evaluate the same f64 expression, so the values must match to the bit.
    assert_eq!(f.stamps.as_deref(), Some(&times[..]), "frame {k}");
}

#[test]
fn ouster_style_f32_relative_times_are_read_and_the_imu_topic_is_ignored() {
    for ext in EXTS {
        let path = fixture("ouster", ext);
        let mut ds = open_ok(&path, None);
        let format = if ext == "bag" {
            Format::Bag
        } else {
            Format::Mcap
        };
        assert_eq!(ds.info.format, Some(format));
        assert_eq!(ds.frames.len_hint(), Some(4), "{ext}");
        let (items, err) = drain(&mut ds);
        assert_eq!(err, None, "{ext}");
        assert_eq!(items.len(), 4, "{ext}");
        for (k, item) in items.iter().enumerate() {
            let f = frame(item);
            assert_eq!(f.index, k);
            check_stamp(f, &path, "/os_cloud_node/points", k as u32);
            check_ouster(f, k as u32);
            assert!(f.warnings.is_empty(), "{:?}", f.warnings);
        }
    }
}

#[test]
fn absolute_f64_timestamp_field_is_read_bit_exact() {
    for ext in EXTS {
        let path = fixture("abs_time", ext);
        let (items, err) = drain(&mut open_ok(&path, None));
        assert_eq!(err, None, "{ext}");
        assert_eq!(items.len(), 3, "{ext}");
        for (k, item) in items.iter().enumerate() {
            check_stamp(frame(item), &path, "/hesai/pandar", k as u32);
            check_abs_time(frame(item), k as u32);
        }
    }
}

#[test]
fn organized_f64_cloud_without_time_field_skips_row_padding_and_has_no_stamps() {
    for ext in EXTS {
        let path = fixture("xyz64", ext);
        let (items, err) = drain(&mut open_ok(&path, None));
        assert_eq!(err, None, "{ext}");
        assert_eq!(items.len(), 3, "{ext}");
        for (k, item) in items.iter().enumerate() {
            let f = frame(item);
            check_stamp(f, &path, "/velodyne_points", k as u32);
            // Two rows of 8 points, each row padded with 8 bytes of 0xEE.
            let want: Vec<[f64; 3]> = (0..2)
                .flat_map(|r| (0..8).map(move |c| [(k + r) as f64, c as f64 / 8.0, -1.0]))
                .collect();
            assert_eq!(f.points, want, "{ext} frame {k}");
            assert_eq!(f.stamps, None);
        }
    }
}

#[test]
fn two_point_cloud_topics_are_an_error_unless_one_is_chosen() {
    for ext in EXTS {
        let path = fixture("two_topics", ext);
        let err = open_err(&path, None);
        assert!(
            err.contains(&path.display().to_string())
                && err.contains("/lidar_front, /lidar_rear")
                && err.contains("--topic"),
            "{err}"
        );
        let mut ds = open_ok(&path, Some("/lidar_rear"));
        assert_eq!(ds.frames.len_hint(), Some(3));
        let (items, err) = drain(&mut ds);
        assert_eq!(err, None);
        assert_eq!(items.len(), 3, "only /lidar_rear's frames");
        for (k, item) in items.iter().enumerate() {
            check_stamp(frame(item), &path, "/lidar_rear", k as u32);
            check_abs_time(frame(item), k as u32);
        }
        let err = open_err(&path, Some("/nope"));
        assert!(err.contains("no topic /nope"), "{err}");
    }
}

#[test]
fn choosing_a_topic_that_is_not_a_point_cloud_is_an_error_naming_its_type() {
    for ext in EXTS {
        let path = fixture("ouster", ext);
        let err = open_err(&path, Some("/imu"));
        assert!(err.contains("/imu") && err.contains("Imu"), "{err}");
    }
}

#[test]
fn message_with_inconsistent_point_step_is_a_skipped_frame_and_the_stream_goes_on() {
    for ext in EXTS {
        let path = fixture("bad_step", ext);
        let (items, err) = drain(&mut open_ok(&path, None));
        assert_eq!(err, None, "{ext}");
        assert_eq!(items.len(), 3, "{ext}");
        check_ouster(frame(&items[0]), 0);
        match &items[1] {
            Item::Skipped { index, reason, .. } => {
                assert_eq!(*index, 1);
                assert!(reason.contains(&path.display().to_string()), "{reason}");
                assert!(reason.contains("point_step 8"), "{reason}");
            }
            other => panic!("{ext}: expected a skipped frame, got {other:?}"),
        }
        check_ouster(frame(&items[2]), 2);
    }
}

#[test]
fn file_cut_in_the_middle_yields_the_frames_before_then_an_error_naming_the_file() {
    for ext in EXTS {
        // make_bags.py cut the file halfway through the payload of frame 3.
        let path = fixture("truncated", ext);
        let mut ds = open_ok(&path, None);
        let (items, err) = drain(&mut ds);
        assert_eq!(items.len(), 3, "{ext}");
        for (k, item) in items.iter().enumerate() {
            check_ouster(frame(item), k as u32);
        }
        let err = err.unwrap_or_else(|| panic!("{ext}: a cut file must end with an error"));
        assert!(err.contains(&path.display().to_string()), "{err}");
        assert!(err.contains("cut short"), "{err}");
        assert!(
            ds.frames.next_item().unwrap().is_none(),
            "the stream stays ended"
        );
    }
}

#[test]
fn bag_and_mcap_of_the_same_recording_give_the_same_frames() {
    for case in ["ouster", "abs_time", "xyz64", "bad_step"] {
        let read = |ext| drain(&mut open_ok(&fixture(case, ext), None)).0;
        let (bag, mcap) = (read("bag"), read("mcap"));
        assert_eq!(bag.len(), mcap.len(), "{case}");
        for (a, b) in bag.iter().zip(&mcap) {
            match (a, b) {
                (Item::Frame(a), Item::Frame(b)) => {
                    // Compare bits so that NaN points count as equal.
                    let bits = |f: &Frame| -> Vec<u64> {
                        f.points.iter().flatten().map(|v| v.to_bits()).collect()
                    };
                    assert_eq!(bits(a), bits(b), "{case} frame {}", a.index);
                    assert_eq!(a.stamps, b.stamps, "{case} frame {}", a.index);
                    assert_eq!(a.time, b.time, "{case} frame {}", a.index);
                }
                (Item::Skipped { index: i, .. }, Item::Skipped { index: j, .. }) => {
                    assert_eq!(i, j)
                }
                _ => panic!("{case}: {a:?} vs {b:?}"),
            }
        }
    }
}
