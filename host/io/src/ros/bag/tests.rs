//! Tests of `bag`.

use super::*;
use crate::dataset::{ImuInput, Item};
use crate::ros::bag_records::MAGIC;
use crate::ros::imu_msg;
use crate::ros::message::parse_ros1;
use crate::ros::pointcloud2::fixture::{assert_frame_k, drain, frame, save, xyzt, RawCloud};
use std::collections::{BTreeMap, BTreeSet};

/// ROS 1 serialization of `c`, written field by field from the message definition.
fn ros1_body(c: &RawCloud) -> Vec<u8> {
    let mut b = Vec::new();
    let u32_ = |b: &mut Vec<u8>, v: u32| b.extend_from_slice(&v.to_le_bytes());
    let str_ = |b: &mut Vec<u8>, s: &str| {
        b.extend_from_slice(&(s.len() as u32).to_le_bytes());
        b.extend_from_slice(s.as_bytes());
    };
    u32_(&mut b, 7); // seq
    u32_(&mut b, c.sec);
    u32_(&mut b, c.nsec);
    str_(&mut b, &c.frame_id);
    u32_(&mut b, c.height);
    u32_(&mut b, c.width);
    u32_(&mut b, c.fields.len() as u32);
    for f in &c.fields {
        str_(&mut b, &f.name);
        u32_(&mut b, f.offset);
        b.push(f.datatype);
        u32_(&mut b, f.count);
    }
    b.push(u8::from(c.is_bigendian));
    u32_(&mut b, c.point_step);
    u32_(&mut b, c.row_step);
    u32_(&mut b, c.data.len() as u32);
    b.extend_from_slice(&c.data);
    b.push(u8::from(c.is_dense));
    b
}

/// A connection of a test bag.
struct TestConn {
    topic: &'static str,
    tp: &'static str,
    md5: &'static str,
}

const CLOUD: (&str, &str) = (POINTCLOUD2_TYPE, POINTCLOUD2_MD5);
const STRING: (&str, &str) = ("std_msgs/String", "992ce8a1687cec8c8bd883ec73ca41d1");

fn conn(topic: &'static str, (tp, md5): (&'static str, &'static str)) -> TestConn {
    TestConn { topic, tp, md5 }
}

fn record(out: &mut Vec<u8>, fields: &[(&str, &[u8])], data: &[u8]) {
    let mut header = Vec::new();
    for (name, value) in fields {
        let len = (name.len() + 1 + value.len()) as u32;
        header.extend_from_slice(&len.to_le_bytes());
        header.extend_from_slice(name.as_bytes());
        header.push(b'=');
        header.extend_from_slice(value);
    }
    out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    out.extend_from_slice(&header);
    out.extend_from_slice(&(data.len() as u32).to_le_bytes());
    out.extend_from_slice(data);
}

fn time(ns: u64) -> [u8; 8] {
    let mut t = [0u8; 8];
    t[..4].copy_from_slice(&((ns / 1_000_000_000) as u32).to_le_bytes());
    t[4..].copy_from_slice(&((ns % 1_000_000_000) as u32).to_le_bytes());
    t
}

fn conn_record(out: &mut Vec<u8>, id: u32, c: &TestConn) {
    let mut data = Vec::new();
    record_fields(
        &mut data,
        &[
            ("topic", c.topic.as_bytes()),
            ("type", c.tp.as_bytes()),
            ("md5sum", c.md5.as_bytes()),
            ("message_definition", b"# test"),
        ],
    );
    record(
        out,
        &[
            ("op", &[7]),
            ("conn", &id.to_le_bytes()),
            ("topic", c.topic.as_bytes()),
        ],
        &data,
    );
}

fn record_fields(out: &mut Vec<u8>, fields: &[(&str, &[u8])]) {
    for (name, value) in fields {
        let len = (name.len() + 1 + value.len()) as u32;
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(name.as_bytes());
        out.push(b'=');
        out.extend_from_slice(value);
    }
}

/// Writes a bag v2.0 following http://wiki.ros.org/Bags/Format/2.0: uncompressed chunks of
/// `per_chunk` messages (connection record before a connection's first message), index data
/// after each chunk and, if `indexed`, the index section (connections, chunk infos).
/// Messages are (connection id = position in `conns`, receive time ns, body). Returns the
/// file and the offset of every chunk record.
fn write_bag(
    conns: &[TestConn],
    msgs: &[(u32, u64, Vec<u8>)],
    per_chunk: usize,
    indexed: bool,
) -> (Vec<u8>, Vec<u64>) {
    let header = |index_pos: u64, chunk_count: u32| {
        let mut h = Vec::new();
        record(
            &mut h,
            &[
                ("op", &[3]),
                ("index_pos", &index_pos.to_le_bytes()),
                ("conn_count", &(conns.len() as u32).to_le_bytes()),
                ("chunk_count", &chunk_count.to_le_bytes()),
            ],
            &[b' '; 64],
        );
        h
    };
    let base = (MAGIC.len() + header(0, 0).len()) as u64;
    let mut section = Vec::new();
    let mut chunk_pos = Vec::new();
    let mut infos = Vec::new();
    let mut seen = BTreeSet::new();
    for group in msgs.chunks(per_chunk) {
        let mut data = Vec::new();
        let mut index: BTreeMap<u32, Vec<(u64, u32)>> = BTreeMap::new();
        for (c, t, body) in group {
            if seen.insert(*c) {
                conn_record(&mut data, *c, &conns[*c as usize]);
            }
            index.entry(*c).or_default().push((*t, data.len() as u32));
            record(
                &mut data,
                &[
                    ("op", &[2]),
                    ("conn", &c.to_le_bytes()),
                    ("time", &time(*t)),
                ],
                body,
            );
        }
        let pos = base + section.len() as u64;
        chunk_pos.push(pos);
        record(
            &mut section,
            &[
                ("op", &[5]),
                ("compression", b"none"),
                ("size", &(data.len() as u32).to_le_bytes()),
            ],
            &data,
        );
        for (c, entries) in &index {
            let mut d = Vec::new();
            for (t, off) in entries {
                d.extend_from_slice(&time(*t));
                d.extend_from_slice(&off.to_le_bytes());
            }
            record(
                &mut section,
                &[
                    ("op", &[4]),
                    ("ver", &1u32.to_le_bytes()),
                    ("conn", &c.to_le_bytes()),
                    ("count", &(entries.len() as u32).to_le_bytes()),
                ],
                &d,
            );
        }
        let (t0, t1) = (group[0].1, group[group.len() - 1].1);
        infos.push((
            pos,
            t0,
            t1,
            index
                .iter()
                .map(|(c, e)| (*c, e.len() as u32))
                .collect::<Vec<_>>(),
        ));
    }
    let index_pos = base + section.len() as u64;
    let mut out = MAGIC.to_vec();
    out.extend(header(
        if indexed { index_pos } else { 0 },
        infos.len() as u32,
    ));
    out.extend(section);
    if indexed {
        for (id, c) in conns.iter().enumerate() {
            conn_record(&mut out, id as u32, c);
        }
        for (pos, t0, t1, counts) in &infos {
            let mut d = Vec::new();
            for (c, n) in counts {
                d.extend_from_slice(&c.to_le_bytes());
                d.extend_from_slice(&n.to_le_bytes());
            }
            record(
                &mut out,
                &[
                    ("op", &[6]),
                    ("ver", &1u32.to_le_bytes()),
                    ("chunk_pos", &pos.to_le_bytes()),
                    ("start_time", &time(*t0)),
                    ("end_time", &time(*t1)),
                    ("count", &(counts.len() as u32).to_le_bytes()),
                ],
                &d,
            );
        }
    }
    (out, chunk_pos)
}

/// Frame `k` of a test stream: 6 points of [`xyzt`], ROS 1 serialized.
fn cloud_msg(k: u32) -> Vec<u8> {
    ros1_body(&xyzt(k, 6))
}

fn open_bag(path: &Path, topic: Option<&str>) -> Result<Dataset> {
    open(
        path,
        &OpenOptions {
            topic: topic.map(String::from),
            ..OpenOptions::default()
        },
    )
}

/// Five clouds on /points interleaved with strings on /chatter, two messages per chunk.
fn mixed_messages() -> Vec<(u32, u64, Vec<u8>)> {
    let mut msgs = Vec::new();
    for k in 0..5u32 {
        msgs.push((0, u64::from(k) * 100_000_000, cloud_msg(k)));
        msgs.push((1, u64::from(k) * 100_000_000 + 1, b"\x02\0\0\0hi".to_vec()));
    }
    msgs
}

#[test]
fn reads_every_cloud_of_the_only_pointcloud2_topic_with_times_and_stamps() {
    let dir = tempfile::tempdir().unwrap();
    let conns = [conn("/points", CLOUD), conn("/chatter", STRING)];
    for per_chunk in [1, 3, 100] {
        let (bytes, _) = write_bag(&conns, &mixed_messages(), per_chunk, true);
        let p = save(&dir, "a.bag", &bytes);
        let mut ds = open_bag(&p, None).unwrap();
        assert_eq!(ds.info.format, Some(Format::Bag));
        assert_eq!(ds.frames.len_hint(), Some(5));
        let (items, err) = drain(ds.frames.as_mut());
        assert_eq!(err, None);
        assert_eq!(items.len(), 5);
        for (k, item) in items.iter().enumerate() {
            let f = frame(item);
            assert_frame_k(f, k, k as u32);
            assert!(f.warnings.is_empty(), "{:?}", f.warnings);
        }
    }
}

#[test]
fn bag_without_index_is_scanned_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let conns = [conn("/points", CLOUD), conn("/chatter", STRING)];
    let (bytes, _) = write_bag(&conns, &mixed_messages(), 3, false);
    let p = save(&dir, "open.bag", &bytes);
    let mut ds = open_bag(&p, None).unwrap();
    assert_eq!(ds.frames.len_hint(), Some(5));
    let (items, err) = drain(ds.frames.as_mut());
    assert_eq!(err, None);
    assert_eq!(items.len(), 5);
    for (k, item) in items.iter().enumerate() {
        assert_frame_k(frame(item), k, k as u32);
    }
    assert!(ds.info.warnings[0].contains("no usable index"));
}

#[test]
fn bag_cut_inside_a_chunk_yields_the_frames_before_then_an_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let conns = [conn("/points", CLOUD)];
    let msgs: Vec<_> = (0..6).map(|k| (0, u64::from(k), cloud_msg(k))).collect();
    let (bytes, chunks) = write_bag(&conns, &msgs, 1, true);
    // Cut 40 bytes into the fifth chunk: chunks 0..4 are whole.
    let cut = chunks[4] as usize + 40;
    let p = save(&dir, "cut.bag", &bytes[..cut]);
    let mut ds = open_bag(&p, None).unwrap();
    let (items, err) = drain(ds.frames.as_mut());
    assert_eq!(items.len(), 4);
    for (k, item) in items.iter().enumerate() {
        assert_frame_k(frame(item), k, k as u32);
    }
    let err = err.expect("a cut bag must end with an error");
    assert!(err.contains(&p.display().to_string()), "{err}");
    assert!(err.contains("cut short"), "{err}");
}

#[test]
fn bag_cut_inside_its_index_still_yields_every_frame() {
    let dir = tempfile::tempdir().unwrap();
    let conns = [conn("/points", CLOUD)];
    let msgs: Vec<_> = (0..4).map(|k| (0, u64::from(k), cloud_msg(k))).collect();
    let (bytes, _) = write_bag(&conns, &msgs, 1, true);
    let p = save(&dir, "cut_index.bag", &bytes[..bytes.len() - 10]);
    let mut ds = open_bag(&p, None).unwrap();
    let (items, err) = drain(ds.frames.as_mut());
    assert_eq!(err, None);
    assert_eq!(items.len(), 4);
    assert!(ds.info.warnings[0].contains("no usable index"));
}

#[test]
fn other_type_on_the_chosen_topic_ends_the_stream_after_the_frames_before() {
    let dir = tempfile::tempdir().unwrap();
    let conns = [conn("/points", CLOUD), conn("/points", STRING)];
    let msgs = vec![
        (0, 1, cloud_msg(0)),
        (0, 2, cloud_msg(1)),
        (1, 3, b"\x02\0\0\0hi".to_vec()),
        (0, 4, cloud_msg(2)),
    ];
    let (bytes, _) = write_bag(&conns, &msgs, 2, true);
    let p = save(&dir, "mixed.bag", &bytes);
    let mut ds = open_bag(&p, None).unwrap();
    let (items, err) = drain(ds.frames.as_mut());
    assert_eq!(items.len(), 2);
    let err = err.unwrap();
    assert!(
        err.contains("std_msgs/String") && err.contains(&p.display().to_string()),
        "{err}"
    );
}

#[test]
fn pointcloud2_with_another_definition_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let conns = [conn(
        "/points",
        (POINTCLOUD2_TYPE, "00000000000000000000000000000000"),
    )];
    let (bytes, _) = write_bag(&conns, &[(0, 1, cloud_msg(0))], 1, true);
    let p = save(&dir, "md5.bag", &bytes);
    let (items, err) = drain(open_bag(&p, None).unwrap().frames.as_mut());
    assert!(items.is_empty());
    assert!(err.unwrap().contains("md5"));
}

#[test]
fn inconsistent_point_step_is_a_skipped_frame_and_the_stream_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let mut bad = xyzt(1, 6);
    bad.point_step = 12; // the `t` field at offset 12 no longer fits
    let msgs = vec![
        (0, 1, cloud_msg(0)),
        (0, 2, ros1_body(&bad)),
        (0, 3, cloud_msg(2)),
    ];
    let (bytes, _) = write_bag(&[conn("/points", CLOUD)], &msgs, 2, true);
    let p = save(&dir, "step.bag", &bytes);
    let (items, err) = drain(open_bag(&p, None).unwrap().frames.as_mut());
    assert_eq!(err, None);
    assert_eq!(items.len(), 3);
    assert_frame_k(frame(&items[0]), 0, 0);
    match &items[1] {
        Item::Skipped { index, reason, .. } => {
            assert_eq!(*index, 1);
            assert!(
                reason.contains(&p.display().to_string()) && reason.contains("/points"),
                "{reason}"
            );
            assert!(reason.contains("point_step 12"), "{reason}");
        }
        other => panic!("expected a skip, got {other:?}"),
    }
    assert_frame_k(frame(&items[2]), 2, 2);
}

#[test]
fn several_cloud_topics_need_a_topic_and_the_chosen_one_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let conns = [
        conn("/b", CLOUD),
        conn("/a", CLOUD),
        conn("/chatter", STRING),
    ];
    let msgs = vec![
        (0, 1, cloud_msg(0)),
        (1, 2, cloud_msg(1)),
        (2, 3, b"\0\0\0\0".to_vec()),
        (1, 4, cloud_msg(2)),
    ];
    let (bytes, _) = write_bag(&conns, &msgs, 2, true);
    let p = save(&dir, "two.bag", &bytes);
    let err = format!("{:#}", open_bag(&p, None).err().unwrap());
    assert!(err.contains("/a, /b") && err.contains("--topic"), "{err}");
    let err = format!("{:#}", open_bag(&p, Some("/chatter")).err().unwrap());
    assert!(err.contains("std_msgs/String"), "{err}");
    let mut ds = open_bag(&p, Some("/a")).unwrap();
    assert_eq!(ds.frames.len_hint(), Some(2));
    let (items, err) = drain(ds.frames.as_mut());
    assert_eq!(err, None);
    let ks: Vec<f64> = items.iter().map(|i| frame(i).points[0][0]).collect();
    assert_eq!(ks, vec![1.0, 2.0], "only /a's clouds (frames 1 and 2)");
}

#[test]
fn bag_without_clouds_is_an_error_listing_its_topics() {
    let dir = tempfile::tempdir().unwrap();
    let (bytes, _) = write_bag(
        &[conn("/chatter", STRING)],
        &[(0, 1, b"\0\0\0\0".to_vec())],
        1,
        true,
    );
    let p = save(&dir, "none.bag", &bytes);
    let err = format!("{:#}", open_bag(&p, None).err().unwrap());
    assert!(
        err.contains("no sensor_msgs/PointCloud2 topic") && err.contains("/chatter"),
        "{err}"
    );
}

#[test]
fn messages_out_of_time_order_are_read_in_time_order_indexed_or_not() {
    let dir = tempfile::tempdir().unwrap();
    let conns = [conn("/points", CLOUD), conn("/chatter", STRING)];
    let msgs: Vec<_> = [0u32, 2, 1, 4, 3]
        .iter()
        .flat_map(|&k| {
            let t = u64::from(k) * 100_000_000;
            [(0, t, cloud_msg(k)), (1, t + 1, b"\x02\0\0\0hi".to_vec())]
        })
        .collect();
    for indexed in [true, false] {
        for per_chunk in [1, 3, 100] {
            let (bytes, _) = write_bag(&conns, &msgs, per_chunk, indexed);
            let p = save(&dir, "late.bag", &bytes);
            let mut ds = open_bag(&p, None).unwrap();
            let w = ds.info.warnings.join("\n");
            assert!(
                w.contains("not in time order") && w.contains("message 2"),
                "{w}"
            );
            let (items, err) = drain(ds.frames.as_mut());
            assert_eq!(err, None);
            assert_eq!(items.len(), 5);
            for (k, item) in items.iter().enumerate() {
                assert_frame_k(frame(item), k, k as u32);
            }
        }
    }
}

#[test]
fn a_chunk_larger_than_the_record_limit_is_refused_before_it_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let msgs: Vec<_> = (0..2).map(|k| (0, u64::from(k), cloud_msg(k))).collect();
    let (mut bytes, chunks) = write_bag(&[conn("/points", CLOUD)], &msgs, 1, true);
    let at = chunks[1] as usize;
    let size = at + bytes[at..].windows(5).position(|w| w == b"size=").unwrap() + 5;
    bytes[size..size + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    let p = save(&dir, "huge.bag", &bytes);
    let (items, err) = drain(open_bag(&p, None).unwrap().frames.as_mut());
    assert_eq!(items.len(), 1);
    let err = err.unwrap();
    assert!(
        err.contains("4294967295 bytes") && err.contains("limit"),
        "{err}"
    );
}

#[test]
fn seek_lands_on_the_frame_sequential_reading_gives() {
    let dir = tempfile::tempdir().unwrap();
    let conns = [conn("/points", CLOUD), conn("/chatter", STRING)];
    let mut msgs = mixed_messages();
    msgs.extend((5..7).map(|k| (0, 1_000_000_000 + u64::from(k), cloud_msg(k))));
    for indexed in [true, false] {
        let (bytes, _) = write_bag(&conns, &msgs, 3, indexed);
        let p = save(&dir, "seek.bag", &bytes);
        for target in [0, 1, 4, 6, 7, 9] {
            let mut ds = open_bag(&p, None).unwrap();
            assert!(ds.frames.seek(target));
            let (items, err) = drain(ds.frames.as_mut());
            assert_eq!(err, None);
            assert_eq!(
                items.len(),
                7usize.saturating_sub(target),
                "seek to {target}"
            );
            for (j, item) in items.iter().enumerate() {
                assert_frame_k(frame(item), target + j, (target + j) as u32);
            }
        }
    }
}

#[test]
fn ros1_body_cut_anywhere_or_padded_is_an_error_not_a_panic() {
    let body = cloud_msg(3);
    assert_eq!(parse_ros1(&body).unwrap().data, &xyzt(3, 6).data[..]);
    for cut in 0..body.len() {
        assert!(parse_ros1(&body[..cut]).is_err(), "cut at {cut}");
    }
    let mut long = body.clone();
    long.push(0);
    assert!(parse_ros1(&long).unwrap_err().contains("1 bytes after"));
}

#[test]
fn files_that_are_not_bags_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in [
        ("text.bag", &b"hello, world\n"[..]),
        ("empty.bag", b""),
        ("v12.bag", b"#ROSBAG V1.2\n\0\0\0\0"),
    ] {
        let p = save(&dir, name, bytes);
        let err = format!("{:#}", open_bag(&p, None).err().unwrap());
        assert!(err.contains(&p.display().to_string()), "{err}");
    }
    let err = format!(
        "{:#}",
        open_bag(&dir.path().join("missing.bag"), None)
            .err()
            .unwrap()
    );
    assert!(err.contains("cannot open"), "{err}");
}

/// A ROS 1 `sensor_msgs/Imu` stamped `ns`, angular velocity (k, 0, 0) for sample `k`.
fn imu_msg(ns: u64, k: u32) -> Vec<u8> {
    let mut b = Vec::new();
    let sec = (ns / 1_000_000_000) as u32;
    let nsec = (ns % 1_000_000_000) as u32;
    for v in [k, sec, nsec, 3] {
        b.extend(v.to_le_bytes());
    }
    b.extend(b"imu");
    let mut block = [0.0f64; 37];
    block[13] = f64::from(k); // angular_velocity.x
    block[27] = 9.8; // linear_acceleration.z
    for v in block {
        b.extend(v.to_le_bytes());
    }
    b
}

#[test]
fn an_imu_topic_gives_each_frame_the_samples_up_to_its_stamp_and_a_bad_message_is_counted() {
    let dir = tempfile::tempdir().unwrap();
    const IMU: (&str, &str) = (imu_msg::ROS1_TYPE, imu_msg::ROS1_MD5);
    let conns = [conn("/points", CLOUD), conn("/imu", IMU)];
    let t0 = 1_700_000_000u64 * 1_000_000_000;
    let mut msgs = Vec::new();
    // Samples every 0.25 s from t0 + 0.1 s to t0 + 4.85 s; number 6 cut short.
    for k in 0..20u32 {
        let ns = t0 + u64::from(k) * 250_000_000 + 100_000_000;
        let mut body = imu_msg(ns, k);
        if k == 6 {
            body.truncate(100);
        }
        msgs.push((1, ns, body));
    }
    // Clouds stamped t0 + k + 0.25 s, point times offsets from it.
    for k in 0..4u32 {
        msgs.push((
            0,
            t0 + u64::from(k) * 1_000_000_000 + 250_000_000,
            cloud_msg(k),
        ));
    }
    msgs.sort_by_key(|m| m.1);
    let (bytes, _) = write_bag(&conns, &msgs, 5, true);
    let p = save(&dir, "imu.bag", &bytes);
    let with = |imu: ImuInput| {
        let opts = OpenOptions {
            imu,
            ..OpenOptions::default()
        };
        open(&p, &opts)
    };
    let mut ds = with(ImuInput::Auto).unwrap();
    let (items, err) = drain(ds.frames.as_mut());
    assert_eq!(err, None);
    let got: Vec<Vec<f64>> = items
        .iter()
        .map(|i| frame(i).imu.iter().map(|s| s.gyro[0]).collect())
        .collect();
    // Frame k ends at its stamp, t0 + k + 0.25 s: samples 4k - 3 ..= 4k; the last takes the
    // rest; sample 6 is missing.
    let want: Vec<Vec<f64>> = vec![
        vec![0.0],
        vec![1.0, 2.0, 3.0, 4.0],
        vec![5.0, 7.0, 8.0],
        (9..20).map(f64::from).collect(),
    ];
    assert_eq!(got, want);
    assert_eq!(frame(&items[1]).end, Some(1_700_000_001.25));
    assert_eq!(frame(&items[1]).imu[0].accel, [0.0, 0.0, 9.8]);
    let w = ds.info.warnings.join("\n");
    assert!(
        w.contains("1 message(s) on /imu") && w.contains("message 6: message ends inside"),
        "{w}"
    );
    // Not asked for: not read.
    let mut plain = with(ImuInput::Builtin).unwrap();
    let (items, _) = drain(plain.frames.as_mut());
    assert!(items.iter().all(|i| frame(i).imu.is_empty()));
    // A topic the bag does not have.
    let e = format!("{:#}", with(ImuInput::Topic("/nope".into())).err().unwrap());
    assert!(e.contains("no topic /nope (IMU topics: /imu)"), "{e}");
}
