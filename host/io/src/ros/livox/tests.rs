//! Tests of `livox`.

use super::*;
use crate::dataset::SensorOptions;
use crate::ros::test_messages::{custom_msg, metadata_yaml, write_db3};

const TYPE: &str = "livox_ros_driver2/msg/CustomMsg";

/// Points of message `k`: 4 points 1 ms apart, x = k, line = point number.
fn points(k: u32) -> Vec<(u32, [f32; 3], u8, u8, u8)> {
    (0..4u8)
        .map(|i| {
            (
                u32::from(i) * 1_000_000,
                [k as f32, f32::from(i), 0.5],
                10 * i,
                0,
                i,
            )
        })
        .collect()
}

#[test]
fn a_message_gives_its_points_timebase_and_offsets_in_both_generations_and_byte_orders() {
    let want = points(2);
    for (ros1, big) in [(true, false), (false, false), (false, true)] {
        let body = custom_msg(ros1, big, 1_700_000_000_123_456_789, &want, 4);
        let m = parse(ros1, &body).unwrap();
        assert_eq!(m.timebase, 1_700_000_000_123_456_789);
        assert_eq!((m.point_num, m.lidar_id), (4, 3));
        assert_eq!(m.stamp.sec, 1_700_000_000);
        let got: Vec<_> = (m.points.iter())
            .map(|p| (p.offset_time, p.xyz, p.reflectivity, p.tag, p.line))
            .collect();
        assert_eq!(got, want, "ros1 {ros1} big-endian {big}");
        for cut in 0..body.len() {
            assert!(parse(ros1, &body[..cut]).is_err(), "cut at {cut}");
        }
    }
}

#[test]
fn a_point_num_that_disagrees_with_the_points_is_refused() {
    let body = custom_msg(false, false, 5, &points(0), 7);
    let e = parse(false, &body).unwrap_err();
    assert!(
        e.contains("point_num is 7 but the message holds 4 points"),
        "{e}"
    );
}

/// A db3 bag of CustomMsg messages `k` at `timebase(k)`, message 3's `point_num` wrong.
fn bag(dir: &std::path::Path, timebase: impl Fn(u32) -> u64, n: u32) -> std::path::PathBuf {
    let msgs: Vec<(usize, u64, Vec<u8>)> = (0..n)
        .map(|k| {
            let num = if k == 3 { 9 } else { 4 };
            (
                0,
                timebase(k),
                custom_msg(false, false, timebase(k), &points(k), num),
            )
        })
        .collect();
    write_db3(&dir.join("b_0.db3"), &[("/livox/lidar", TYPE)], &msgs);
    let yaml = metadata_yaml(
        &[("b_0.db3", n.into())],
        &[("/livox/lidar", TYPE, n.into())],
    );
    std::fs::write(dir.join("metadata.yaml"), yaml).unwrap();
    dir.to_path_buf()
}

fn open_with(path: &std::path::Path, period: Option<f64>) -> Vec<Item> {
    let opts = OpenOptions {
        sensor: SensorOptions {
            frame_period_s: period,
            ..SensorOptions::default()
        },
        ..OpenOptions::default()
    };
    let mut ds = crate::open(path, crate::Format::Auto, &opts).unwrap();
    std::iter::from_fn(|| ds.frames.next_item().unwrap()).collect()
}

#[test]
fn each_message_is_a_frame_with_point_times_from_timebase_and_a_bad_one_is_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let base = 1_700_000_000_000_000_000u64;
    let path = bag(dir.path(), |k| base + u64::from(k) * 100_000_000, 6);
    let items = open_with(&path, None);
    assert_eq!(items.len(), 6);
    let Item::Skipped {
        index: 3, reason, ..
    } = &items[3]
    else {
        panic!("{:?}", items[3]);
    };
    assert!(
        reason.contains("message 3") && reason.contains("point_num is 9"),
        "{reason}"
    );
    let Item::Frame(f) = &items[2] else { panic!() };
    assert_eq!(f.index, 2);
    assert_eq!(f.points[1], [2.0, 1.0, 0.5]);
    let stamps = f.stamps.as_ref().unwrap();
    let worst = (0..4)
        .map(|i| (stamps[i] - i as f64 * 1e-3).abs())
        .fold(0.0, f64::max);
    println!("point times against offset_time: worst {worst:.1e} s, tolerance 1e-12 s");
    assert!(worst < 1e-12);
    assert_eq!(f.intensity.as_deref(), Some(&[0.0, 10.0, 20.0, 30.0][..]));
    // The sweep ends at its last point on the sensor's clock: timebase + 3 ms.
    let end = (base + 203_000_000) as f64 * 1e-9;
    assert_eq!(f.sweep_end(), Some(end));
}

#[test]
fn a_frame_period_merges_the_messages_of_each_period_despite_jitter() {
    let dir = tempfile::tempdir().unwrap();
    let base = 1_700_000_000_000_000_000u64;
    // 50 Hz messages whose first points come up to 0.4 ms early or late.
    let jitter = [
        0i64, 300_000, -400_000, 100_000, -200_000, 400_000, -300_000,
    ];
    let at = |k: u32| (base as i64 + i64::from(k) * 20_000_000 + jitter[k as usize % 7]) as u64;
    let path = bag(dir.path(), at, 23);
    let items = open_with(&path, Some(0.1));
    let sizes: Vec<usize> = items
        .iter()
        .map(|i| match i {
            Item::Frame(f) => f.points.len() / 4,
            Item::Skipped { .. } => 0,
        })
        .collect();
    // Five messages a frame; message 3 (in frame 0) is left out with a warning.
    assert_eq!(sizes, [4, 5, 5, 5, 3]);
    let Item::Frame(f) = &items[0] else { panic!() };
    assert!(
        f.warnings[0].contains("message 3 left out"),
        "{:?}",
        f.warnings
    );
    let Item::Frame(f) = &items[1] else { panic!() };
    assert_eq!((f.index, f.points[0][0]), (1, 5.0));
}
