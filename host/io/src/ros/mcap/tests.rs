//! Tests of `mcap`.

use super::*;
use crate::dataset::Item;
use crate::ros::imu_msg;
use crate::ros::message::parse_cdr;
use crate::ros::pointcloud2::fixture::{assert_frame_k, drain, frame, save, xyzt};
use crate::ros::pointcloud2::Stamp;
use crate::ros::test_messages::{cdr_body, imu_cdr};
use mcap::records::MessageHeader;
use std::collections::BTreeMap;

const STRING_SCHEMA: &str = "std_msgs/msg/String";

/// Writes an MCAP file with the `mcap` crate: channels (topic, schema name), messages
/// (channel position, body), `chunk_size` None for one record per message outside chunks.
fn write_mcap(
    channels: &[(&str, &str)],
    msgs: &[(usize, Vec<u8>)],
    chunk_size: Option<u64>,
    compression: Option<mcap::Compression>,
) -> Vec<u8> {
    let mut w = mcap::WriteOptions::new()
        .compression(compression)
        .chunk_size(chunk_size)
        .use_chunks(chunk_size.is_some())
        .create(std::io::Cursor::new(Vec::new()))
        .unwrap();
    let ids: Vec<u16> = channels
        .iter()
        .map(|(topic, schema)| {
            let sid = w.add_schema(schema, "ros2msg", b"# test").unwrap();
            w.add_channel(sid, topic, CDR_ENCODING, &BTreeMap::new())
                .unwrap()
        })
        .collect();
    for (seq, (ch, body)) in msgs.iter().enumerate() {
        let header = MessageHeader {
            channel_id: ids[*ch],
            sequence: seq as u32,
            log_time: seq as u64,
            publish_time: seq as u64,
        };
        w.write_to_known_channel(&header, body).unwrap();
    }
    w.finish().unwrap();
    w.into_inner().into_inner()
}

fn cloud_msg(k: u32) -> Vec<u8> {
    cdr_body(&xyzt(k, 6), false)
}

fn string_msg() -> Vec<u8> {
    vec![0, 1, 0, 0, 3, 0, 0, 0, b'h', b'i', 0]
}

fn open_mcap(path: &Path, topic: Option<&str>) -> Result<Dataset> {
    open(
        path,
        &OpenOptions {
            topic: topic.map(String::from),
            ..OpenOptions::default()
        },
    )
}

fn mixed_messages() -> Vec<(usize, Vec<u8>)> {
    (0..5u32)
        .flat_map(|k| [(0, cloud_msg(k)), (1, string_msg())])
        .collect()
}

#[test]
fn reads_every_cloud_of_the_only_pointcloud2_topic_chunked_or_not_compressed_or_not() {
    let dir = tempfile::tempdir().unwrap();
    let channels = [("/points", POINTCLOUD2_SCHEMA), ("/chatter", STRING_SCHEMA)];
    let layouts = [
        (None, None),
        (Some(300), None),
        (Some(1 << 20), Some(mcap::Compression::Zstd)),
        (Some(500), Some(mcap::Compression::Lz4)),
    ];
    for (chunk_size, compression) in layouts {
        let bytes = write_mcap(&channels, &mixed_messages(), chunk_size, compression);
        let p = save(&dir, "a.mcap", &bytes);
        let mut ds = open_mcap(&p, None).unwrap();
        assert_eq!(ds.info.format, Some(Format::Mcap));
        assert_eq!(ds.frames.len_hint(), Some(5));
        let (items, err) = drain(ds.frames.as_mut());
        assert_eq!(err, None);
        assert_eq!(items.len(), 5, "{chunk_size:?} {compression:?}");
        for (k, item) in items.iter().enumerate() {
            let f = frame(item);
            assert_frame_k(f, k, k as u32);
            assert!(f.warnings.is_empty(), "{:?}", f.warnings);
        }
    }
}

#[test]
fn big_endian_cdr_reads_the_same_values() {
    let body = cdr_body(&xyzt(3, 6), true);
    let le = cdr_body(&xyzt(3, 6), false);
    assert_ne!(body, le);
    assert_eq!(parse_cdr(&body).unwrap(), parse_cdr(&le).unwrap());
    assert_eq!(
        parse_cdr(&body).unwrap().stamp,
        Stamp {
            sec: 1_700_000_003,
            nsec: 250_000_000
        }
    );
}

#[test]
fn file_cut_inside_a_message_yields_the_frames_before_then_an_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let channels = [("/points", POINTCLOUD2_SCHEMA), ("/chatter", STRING_SCHEMA)];
    for chunk_size in [None, Some(400), Some(1 << 20)] {
        let bytes = write_mcap(&channels, &mixed_messages(), chunk_size, None);
        // Cut halfway through the body of cloud 3: clouds 0, 1, 2 are whole.
        let body = cloud_msg(3);
        let at = bytes
            .windows(body.len())
            .position(|w| w == body.as_slice())
            .unwrap();
        let p = save(&dir, "cut.mcap", &bytes[..at + body.len() / 2]);
        let mut ds = open_mcap(&p, None).unwrap();
        assert_eq!(ds.frames.len_hint(), Some(3), "{chunk_size:?}");
        let (items, err) = drain(ds.frames.as_mut());
        assert_eq!(items.len(), 3, "{chunk_size:?}");
        for (k, item) in items.iter().enumerate() {
            assert_frame_k(frame(item), k, k as u32);
        }
        assert!(ds.info.warnings[0].contains("no summary"));
        let err = err.expect("a cut file must end with an error");
        assert!(
            err.contains(&p.display().to_string()) && err.contains("cut short"),
            "{err}"
        );
    }
}

#[test]
fn other_schema_on_the_chosen_topic_ends_the_stream_after_the_frames_before() {
    let dir = tempfile::tempdir().unwrap();
    let channels = [("/points", POINTCLOUD2_SCHEMA), ("/points", STRING_SCHEMA)];
    let msgs = vec![
        (0, cloud_msg(0)),
        (0, cloud_msg(1)),
        (1, string_msg()),
        (0, cloud_msg(2)),
    ];
    let p = save(
        &dir,
        "mixed.mcap",
        &write_mcap(&channels, &msgs, Some(1 << 20), None),
    );
    let (items, err) = drain(open_mcap(&p, None).unwrap().frames.as_mut());
    assert_eq!(items.len(), 2);
    let err = err.unwrap();
    assert!(
        err.contains(STRING_SCHEMA) && err.contains(&p.display().to_string()),
        "{err}"
    );
}

#[test]
fn inconsistent_point_step_is_a_skipped_frame_and_the_stream_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let mut bad = xyzt(1, 6);
    bad.point_step = 12;
    let msgs = vec![
        (0, cloud_msg(0)),
        (0, cdr_body(&bad, false)),
        (0, cloud_msg(2)),
    ];
    let p = save(
        &dir,
        "step.mcap",
        &write_mcap(&[("/points", POINTCLOUD2_SCHEMA)], &msgs, None, None),
    );
    let (items, err) = drain(open_mcap(&p, None).unwrap().frames.as_mut());
    assert_eq!(err, None);
    assert_eq!(items.len(), 3);
    assert_frame_k(frame(&items[0]), 0, 0);
    match &items[1] {
        Item::Skipped { index, reason, .. } => {
            assert_eq!(*index, 1);
            assert!(
                reason.contains(&p.display().to_string()) && reason.contains("point_step 12"),
                "{reason}"
            );
        }
        other => panic!("expected a skip, got {other:?}"),
    }
    assert_frame_k(frame(&items[2]), 2, 2);
}

#[test]
fn messages_out_of_log_time_order_are_reordered_with_a_chunk_index_and_flagged_without() {
    let dir = tempfile::tempdir().unwrap();
    let order = [0u32, 2, 1, 4, 3];
    for chunked in [true, false] {
        let mut w = mcap::WriteOptions::new()
            .use_chunks(chunked)
            .chunk_size(Some(400))
            .create(std::io::Cursor::new(Vec::new()))
            .unwrap();
        let sid = w
            .add_schema(POINTCLOUD2_SCHEMA, "ros2msg", b"# test")
            .unwrap();
        let ch = w
            .add_channel(sid, "/points", CDR_ENCODING, &BTreeMap::new())
            .unwrap();
        for (seq, &k) in order.iter().enumerate() {
            let header = MessageHeader {
                channel_id: ch,
                sequence: seq as u32,
                log_time: u64::from(k) * 100_000_000,
                publish_time: u64::from(k) * 100_000_000,
            };
            w.write_to_known_channel(&header, &cloud_msg(k)).unwrap();
        }
        w.finish().unwrap();
        let p = save(&dir, "late.mcap", &w.into_inner().into_inner());
        let mut ds = open_mcap(&p, None).unwrap();
        let (items, err) = drain(ds.frames.as_mut());
        assert_eq!(err, None);
        let ks: Vec<f64> = items.iter().map(|i| frame(i).points[0][0]).collect();
        if chunked {
            let w = ds.info.warnings.join("\n");
            assert!(
                w.contains("not in time order") && w.contains("message 2"),
                "{w}"
            );
            for (k, item) in items.iter().enumerate() {
                assert_frame_k(frame(item), k, k as u32);
            }
        } else {
            // No chunk index to reorder by: file order, and the late frames say so.
            assert_eq!(ks, [0.0, 2.0, 1.0, 4.0, 3.0]);
            let late: Vec<usize> = (0..5)
                .filter(|&i| {
                    frame(&items[i])
                        .warnings
                        .iter()
                        .any(|w| w.contains("out of time order"))
                })
                .collect();
            assert_eq!(late, [2, 4]);
        }
    }
}

#[test]
fn several_cloud_topics_need_a_topic_and_the_chosen_one_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let channels = [
        ("/b", POINTCLOUD2_SCHEMA),
        ("/a", POINTCLOUD2_SCHEMA),
        ("/chatter", STRING_SCHEMA),
    ];
    let msgs = vec![
        (0, cloud_msg(0)),
        (1, cloud_msg(1)),
        (2, string_msg()),
        (1, cloud_msg(2)),
    ];
    let p = save(
        &dir,
        "two.mcap",
        &write_mcap(&channels, &msgs, Some(1 << 20), None),
    );
    let err = format!("{:#}", open_mcap(&p, None).err().unwrap());
    assert!(err.contains("/a, /b") && err.contains("--topic"), "{err}");
    let err = format!("{:#}", open_mcap(&p, Some("/chatter")).err().unwrap());
    assert!(err.contains(STRING_SCHEMA), "{err}");
    let mut ds = open_mcap(&p, Some("/a")).unwrap();
    assert_eq!(ds.frames.len_hint(), Some(2));
    let (items, err) = drain(ds.frames.as_mut());
    assert_eq!(err, None);
    let xs: Vec<f64> = items.iter().map(|i| frame(i).points[0][0]).collect();
    assert_eq!(xs, vec![1.0, 2.0], "only /a's clouds (frames 1 and 2)");
}

#[test]
fn cdr_body_cut_anywhere_or_with_other_encapsulation_is_an_error_not_a_panic() {
    let body = cloud_msg(2);
    for cut in 0..body.len() {
        assert!(parse_cdr(&body[..cut]).is_err(), "cut at {cut}");
    }
    let mut padded = body.clone();
    padded.extend_from_slice(&[0, 0, 0]);
    assert!(
        parse_cdr(&padded).is_ok(),
        "up to 3 bytes of end padding are allowed"
    );
    padded.push(0);
    assert!(parse_cdr(&padded).unwrap_err().contains("4 bytes after"));
    let mut xcdr2 = body.clone();
    xcdr2[1] = 0x07;
    assert!(parse_cdr(&xcdr2).unwrap_err().contains("not plain CDR"));
}

#[test]
fn files_that_are_not_mcap_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = save(&dir, "x.mcap", b"#ROSBAG V2.0\n");
    let err = format!("{:#}", open_mcap(&p, None).err().unwrap());
    assert!(
        err.contains("not an MCAP file") && err.contains(&p.display().to_string()),
        "{err}"
    );
}

#[test]
fn an_imu_topic_gives_each_frame_the_samples_up_to_its_stamp_and_a_bad_message_is_counted() {
    let dir = tempfile::tempdir().unwrap();
    let channels = [
        ("/points", POINTCLOUD2_SCHEMA),
        ("/imu", imu_msg::ROS2_SCHEMA),
    ];
    // Samples every 0.25 s from t0 + 0.1 s, number 6 not CDR; clouds at t0 + k + 0.25 s.
    let t0 = 1_700_000_000u64 * 1_000_000_000;
    let mut timed: Vec<(u64, usize, Vec<u8>)> = Vec::new();
    for k in 0..20u32 {
        let ns = t0 + u64::from(k) * 250_000_000 + 100_000_000;
        let mut body = imu_cdr(ns, k);
        if k == 6 {
            body[1] = 7;
        }
        timed.push((ns, 1, body));
    }
    for k in 0..4u32 {
        timed.push((
            t0 + u64::from(k) * 1_000_000_000 + 250_000_000,
            0,
            cloud_msg(k),
        ));
    }
    timed.sort_by_key(|m| m.0);
    let msgs: Vec<(usize, Vec<u8>)> = timed.into_iter().map(|(_, c, b)| (c, b)).collect();
    for chunk_size in [None, Some(1024)] {
        let p = save(
            &dir,
            "imu.mcap",
            &write_mcap(&channels, &msgs, chunk_size, None),
        );
        let opts = OpenOptions {
            imu: crate::dataset::ImuInput::Auto,
            ..OpenOptions::default()
        };
        let mut ds = open(&p, &opts).unwrap();
        let (items, err) = drain(ds.frames.as_mut());
        assert_eq!(err, None);
        let got: Vec<Vec<f64>> = items
            .iter()
            .map(|i| frame(i).imu.iter().map(|s| s.gyro[0]).collect())
            .collect();
        let want: Vec<Vec<f64>> = vec![
            vec![0.0],
            vec![1.0, 2.0, 3.0, 4.0],
            vec![5.0, 7.0, 8.0],
            (9..20).map(f64::from).collect(),
        ];
        assert_eq!(got, want, "chunks {chunk_size:?}: {:?}", ds.info.warnings);
        assert_eq!(frame(&items[1]).imu[0].accel, [0.0, 0.0, 9.8]);
        let w = ds.info.warnings.join("\n");
        assert!(
            w.contains("1 message(s) on /imu") && w.contains("encapsulation 0007"),
            "{w}"
        );
    }
}

/// The guard ends the file for the linear reader before `bytes`' overrunning chunk, and the
/// stream, if the file opens at all, ends with an error.
fn stops_before_the_overrun(bytes: &[u8]) {
    let dir = tempfile::tempdir().unwrap();
    let p = save(&dir, "overrun.mcap", bytes);
    let mut input = BufReader::new(File::open(&p).unwrap());
    let sound = chunks::sound_until(&mut input, bytes.len() as u64);
    assert!(sound < bytes.len() as u64, "{sound}");
    if let Ok(mut dataset) = open_mcap(&p, None) {
        let (_, err) = drain(dataset.frames.as_mut());
        assert!(err.is_some());
    }
}

/// A fuzzer's file whose uncompressed chunk holds a record longer than the chunk: the `mcap`
/// crate's linear reader subtracts past zero there (a panic in this debug build). The reader
/// stops at that chunk as at a file cut short.
#[test]
fn a_record_that_runs_past_its_chunk_ends_the_stream_with_an_error() {
    stops_before_the_overrun(include_bytes!("fuzzed/chunk-record-overruns.mcap"));
}

/// The same overrun in a chunk that also claims more bytes than the file holds (a file cut
/// short inside its last chunk): its records are still walked, so the reader stops before it.
#[test]
fn a_record_that_runs_past_a_chunk_cut_short_ends_the_stream_with_an_error() {
    stops_before_the_overrun(include_bytes!(
        "fuzzed/chunk-past-file-end-record-overruns.mcap"
    ));
}

/// A fuzzer's file whose footer says the summary starts at an uncompressed chunk with a
/// record longer than the chunk: the `mcap` crate's summary reader runs its linear reader from
/// there and subtracts past zero (a panic in this debug build). The summary is not read; the
/// file is scanned as one without a summary, up to that chunk.
#[test]
fn a_summary_that_starts_at_an_overrunning_chunk_is_not_read() {
    let bytes = include_bytes!("fuzzed/summary-points-at-overrunning-chunk.mcap");
    let dir = tempfile::tempdir().unwrap();
    let p = save(&dir, "summary.mcap", bytes);
    let mut input = BufReader::new(File::open(&p).unwrap());
    assert!(!chunks::summary_sound(&mut input, bytes.len() as u64));
    if let Ok(mut dataset) = open_mcap(&p, None) {
        drain(dataset.frames.as_mut());
    }
    // A sound file with a summary passes.
    let sound = include_bytes!("fuzzed/uncompressed-chunk-sizes-differ.mcap");
    assert!(mcap::Summary::read(sound).unwrap().is_some());
    let p = save(&dir, "sound.mcap", sound);
    let mut input = BufReader::new(File::open(&p).unwrap());
    assert!(chunks::summary_sound(&mut input, sound.len() as u64));
}

#[test]
fn an_index_giving_an_uncompressed_chunk_two_sizes_is_not_used() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = include_bytes!("fuzzed/uncompressed-chunk-sizes-differ.mcap");
    let p = save(&dir, "sizes.mcap", bytes);
    let summary = mcap::Summary::read(bytes).unwrap().unwrap();
    assert!(summary
        .chunk_indexes
        .iter()
        .any(|c| c.compression.is_empty() && c.compressed_size != c.uncompressed_size));
    // Read in file order instead; the chunk is then cut short or read whole, never a panic.
    if let Ok(mut dataset) = open_mcap(&p, None) {
        drain(dataset.frames.as_mut());
    }
}
