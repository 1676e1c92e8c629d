//! Tests of `db3`.

use super::*;
use crate::dataset::ImuInput;
use crate::ros::pointcloud2::fixture::{assert_frame_k, drain, frame, xyzt};
use crate::ros::test_messages::{cdr_body, imu_cdr, metadata_yaml, write_db3};

const CLOUD: &str = "sensor_msgs/msg/PointCloud2";
const IMU: &str = "sensor_msgs/msg/Imu";
const T0: u64 = 1_700_000_000 * 1_000_000_000;

/// Clouds `k` at T0 + k + 0.25 s and IMU samples every 0.25 s from T0 + 0.1 s (sample 6 not
/// CDR), receive-time ordered, as (topic, time, body) of topics [/points, /imu].
fn messages(clouds: u32) -> Vec<(usize, u64, Vec<u8>)> {
    let mut all = Vec::new();
    for k in 0..clouds * 4 {
        let ns = T0 + u64::from(k) * 250_000_000 + 100_000_000;
        let mut body = imu_cdr(ns, k);
        if k == 6 {
            body[1] = 7;
        }
        all.push((1, ns, body));
    }
    for k in 0..clouds {
        let ns = T0 + u64::from(k) * 1_000_000_000 + 250_000_000;
        all.push((0, ns, cdr_body(&xyzt(k, 6), false)));
    }
    all.sort_by_key(|m| m.1);
    all
}

/// A bag folder of `messages(4)` split into two files after the first `split` messages.
fn split_bag(dir: &Path, split: usize) -> Vec<(usize, u64, Vec<u8>)> {
    let all = messages(4);
    let topics = [("/points", CLOUD), ("/imu", IMU)];
    write_db3(&dir.join("b_0.db3"), &topics, &all[..split]);
    write_db3(&dir.join("b_1.db3"), &topics, &all[split..]);
    let yaml = metadata_yaml(
        &[
            ("b_0.db3", split as u64),
            ("b_1.db3", (all.len() - split) as u64),
        ],
        &[("/points", CLOUD, 4), ("/imu", IMU, 16)],
    );
    std::fs::write(dir.join("metadata.yaml"), yaml).unwrap();
    all
}

fn open_imu(path: &Path) -> Dataset {
    let opts = OpenOptions {
        imu: ImuInput::Auto,
        ..OpenOptions::default()
    };
    crate::open(path, Format::Auto, &opts).unwrap()
}

#[test]
fn a_split_bag_reads_every_cloud_and_imu_sample_through_its_folder_or_metadata() {
    let dir = tempfile::tempdir().unwrap();
    split_bag(dir.path(), 11);
    for path in [dir.path().to_path_buf(), dir.path().join("metadata.yaml")] {
        assert_eq!(crate::open::detect(&path).unwrap(), Format::Db3);
        let mut ds = open_imu(&path);
        assert_eq!(ds.info.format, Some(Format::Db3));
        assert_eq!(ds.frames.len_hint(), Some(4));
        let (items, err) = drain(ds.frames.as_mut());
        assert_eq!(err, None);
        for (k, item) in items.iter().enumerate() {
            assert_frame_k(frame(item), k, k as u32);
        }
        let got: Vec<Vec<f64>> = (items.iter())
            .map(|i| frame(i).imu.iter().map(|s| s.gyro[0]).collect())
            .collect();
        let want: Vec<Vec<f64>> = vec![
            vec![0.0],
            vec![1.0, 2.0, 3.0, 4.0],
            vec![5.0, 7.0, 8.0],
            (9..16).map(f64::from).collect(),
        ];
        assert_eq!(got, want);
        let w = ds.info.warnings.join("\n");
        assert!(
            w.contains("1 message(s) on /imu") && w.contains("0007"),
            "{w}"
        );
        assert_eq!(ds.info.warnings.len(), 1, "{w}");
    }
    // One file alone: its own messages (clouds 0 and 1), nothing said of the metadata.
    let mut ds = open_imu(&dir.path().join("b_0.db3"));
    let (items, err) = drain(ds.frames.as_mut());
    assert_eq!((items.len(), err), (2, None));
}

#[test]
fn seek_lands_on_the_frame_sequential_reading_gives() {
    let dir = tempfile::tempdir().unwrap();
    split_bag(dir.path(), 11);
    let mut ds = crate::open(dir.path(), Format::Db3, &OpenOptions::default()).unwrap();
    assert!(ds.frames.seek(3));
    assert_frame_k(frame(&ds.frames.next_item().unwrap().unwrap()), 3, 3);
    assert!(ds.frames.seek(1));
    assert_frame_k(frame(&ds.frames.next_item().unwrap().unwrap()), 1, 1);
}

#[test]
fn metadata_that_lies_is_named_and_the_storage_is_read_as_it_is() {
    let dir = tempfile::tempdir().unwrap();
    split_bag(dir.path(), 11);
    let yaml = std::fs::read_to_string(dir.path().join("metadata.yaml")).unwrap();
    // Wrong message counts and a wrong type.
    let lying = yaml
        .replace("message_count: 4\n", "message_count: 5\n")
        .replace("type: sensor_msgs/msg/Imu", "type: sensor_msgs/msg/Image");
    std::fs::write(dir.path().join("metadata.yaml"), &lying).unwrap();
    let mut ds = open_imu(dir.path());
    let w = ds.info.warnings.join("\n");
    println!("{w}");
    assert!(
        w.contains("says /points has 5 messages, the storage holds 4"),
        "{w}"
    );
    assert!(
        w.contains("says /imu carries sensor_msgs/msg/Image, the storage says sensor_msgs/msg/Imu"),
        "{w}"
    );
    assert!(w.contains("metadata.yaml"), "{w}");
    let (items, err) = drain(ds.frames.as_mut());
    assert_eq!((items.len(), err), (4, None));
    assert_eq!(frame(&items[1]).imu.len(), 4);
    // A file it lists that is not there.
    std::fs::remove_file(dir.path().join("b_1.db3")).unwrap();
    let e = format!(
        "{:#}",
        crate::open(dir.path(), Format::Auto, &OpenOptions::default())
            .err()
            .unwrap()
    );
    assert!(
        e.contains("metadata.yaml lists") && e.contains("b_1.db3, which does not exist"),
        "{e}"
    );
    // No metadata: the .db3 files in the order of their numbers, with a warning.
    std::fs::remove_file(dir.path().join("metadata.yaml")).unwrap();
    let ds = crate::open(dir.path(), Format::Auto, &OpenOptions::default()).unwrap();
    assert!(
        ds.info.warnings[0].contains("no metadata.yaml"),
        "{:?}",
        ds.info.warnings
    );
}

#[test]
fn a_truncated_db3_yields_what_it_can_then_an_error_naming_the_file_never_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let all = messages(12);
    let whole = dir.path().join("whole.db3");
    write_db3(&whole, &[("/points", CLOUD), ("/imu", IMU)], &all);
    let bytes = std::fs::read(&whole).unwrap();
    let cut = dir.path().join("cut.db3");
    let mut outcomes = BTreeMap::new();
    for keep in (0..bytes.len()).step_by(509).chain([bytes.len() - 1]) {
        std::fs::write(&cut, &bytes[..keep]).unwrap();
        let opened = crate::open(&cut, Format::Db3, &OpenOptions::default());
        let outcome = match opened {
            Err(e) => {
                let e = format!("{e:#}");
                assert!(e.contains("cut.db3"), "{keep}: {e}");
                "refused when opened"
            }
            Ok(mut ds) => {
                let said = ds.info.warnings.iter().any(|w| w.contains("cut short"));
                match drain(ds.frames.as_mut()) {
                    (items, Some(e)) => {
                        assert!(e.contains("cut.db3"), "{keep}: {e}");
                        assert!(items.len() < 12, "{keep}");
                        "frames, then an error"
                    }
                    (items, None) => {
                        for (k, item) in items.iter().enumerate() {
                            assert_frame_k(frame(item), k, k as u32);
                        }
                        assert!(said, "{keep}: {} frames, nothing said", items.len());
                        "every frame, with a warning that the file is cut short"
                    }
                }
            }
        };
        *outcomes.entry(outcome).or_insert(0) += 1;
    }
    println!("{} bytes cut every 509: {outcomes:?}", bytes.len());
    assert!(outcomes.contains_key("refused when opened"));
}

#[test]
fn zstd_compressed_files_and_messages_read_as_plain_ones() {
    let dir = tempfile::tempdir().unwrap();
    let all = messages(3);
    let topics = [("/points", CLOUD), ("/imu", IMU)];
    let yaml = metadata_yaml(
        &[("c_0.db3", all.len() as u64)],
        &[("/points", CLOUD, 3), ("/imu", IMU, 12)],
    );
    // Each message compressed.
    let packed: Vec<_> = (all.iter())
        .map(|(t, ns, b)| (*t, *ns, zstd::encode_all(&b[..], 3).unwrap()))
        .collect();
    write_db3(&dir.path().join("c_0.db3"), &topics, &packed);
    let mode = |m: &str| {
        yaml.replace("compression_format: \"\"", "compression_format: zstd")
            .replace("compression_mode: \"\"", &format!("compression_mode: {m}"))
    };
    std::fs::write(dir.path().join("metadata.yaml"), mode("MESSAGE")).unwrap();
    let (items, err) = drain(open_imu(dir.path()).frames.as_mut());
    assert_eq!((items.len(), err), (3, None));
    assert_frame_k(frame(&items[2]), 2, 2);
    // The whole file compressed.
    let plain = dir.path().join("plain.db3");
    write_db3(&plain, &topics, &all);
    let file = zstd::encode_all(&std::fs::read(&plain).unwrap()[..], 3).unwrap();
    std::fs::remove_file(dir.path().join("c_0.db3")).unwrap();
    std::fs::remove_file(&plain).unwrap();
    std::fs::write(dir.path().join("c_0.db3.zstd"), file).unwrap();
    let yaml = mode("FILE").replace("c_0.db3", "c_0.db3.zstd");
    std::fs::write(dir.path().join("metadata.yaml"), yaml).unwrap();
    let (items, err) = drain(open_imu(dir.path()).frames.as_mut());
    assert_eq!((items.len(), err), (3, None));
    assert_frame_k(frame(&items[1]), 1, 1);
}

#[test]
fn a_message_larger_than_the_limit_is_refused_before_it_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.db3");
    write_db3(
        &path,
        &[("/points", CLOUD)],
        &[(0, T0, cdr_body(&xyzt(0, 6), false))],
    );
    let bag = Db3::open(&path, 100).unwrap();
    let mut stream = Box::new(bag).stream(&["/points".to_string()]).unwrap();
    let e = format!("{:#}", stream.next_message().err().unwrap());
    assert!(
        e.contains("more than the 100-byte limit") && e.contains("big.db3"),
        "{e}"
    );
    // Files that are not bags.
    std::fs::write(&path, b"not a database at all, not even close").unwrap();
    let e = format!(
        "{:#}",
        crate::open(&path, Format::Db3, &OpenOptions::default())
            .err()
            .unwrap()
    );
    assert!(
        e.contains("big.db3") && e.contains("not a ROS 2 bag"),
        "{e}"
    );
}
