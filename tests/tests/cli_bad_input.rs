//! `kiss-odom run` on damaged input, end to end through the command line
//! (`kiss_odom::cli::main_with`, in-process, on datasets built in a temporary folder).
//!
//! The readers' own tests (`readers.rs`, `bags.rs`) show that damage becomes a skipped frame, a
//! warning or an error; these tests hold the promise the tool makes on top of that (README,
//! "Failure behaviour"): damage confined to one frame file gives a warning naming the file and
//! the reason, the frame is skipped (or its timestamps ignored) and counted in `summary.json`
//! and `frames.csv`, and the run exits 0 (1 under `--strict`, naming the file); a bag or MCAP
//! file cut in the middle or carrying the wrong message type keeps the frames before the damage
//! and exits 1 with one line naming the file; a folder without frames or a missing path exits 1
//! with the reason. No case may panic: every call goes through `catch_unwind`.
//!
//! Good frames are real scans: the KITTI sample in `fixtures/kitti-05-reduced/velodyne` (about
//! 20k points each), copied byte for byte or rewritten as PLY/PCD, or carried as the payload of
//! a PointCloud2 message.

use crate::common;

use common::*;
use kiss_odom_io::folders::{pcd, ply};
use std::ffi::OsString;

// ------------------------------------------------------------------------------------------
// Damage confined to one frame file: warning, skip, count; --strict fails naming the file

#[test]
fn truncated_and_empty_bin_frames_are_skipped_warned_about_and_counted() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let frames = bin_folder(&data, 7);
    let truncated = frames.join("000002.bin");
    let empty = frames.join("000004.bin");
    let mut bytes = kitti_bytes(2);
    bytes.truncate(bytes.len() / 2 + 7); // a write cut short, mid-point
    std::fs::write(&truncated, &bytes).unwrap();
    std::fs::write(&empty, []).unwrap();

    let r = run(&data, &dir.path().join("out"), &[]);
    r.succeeded_with_frames(7);
    let w = warning_for(&r, &truncated);
    assert!(
        w.contains(&format!("length {} is not a multiple of 16", bytes.len())),
        "{w}"
    );
    let w = warning_for(&r, &empty);
    assert!(w.contains("empty"), "{w}");
    assert_eq!(r.warnings().len(), 2, "stderr:\n{}", r.stderr);
    assert_eq!(r.count("skipped_frames"), 2);
    assert_eq!(r.count("empty_frames"), 0);
    assert_eq!(r.count("warnings"), 2);
    for row in r.rows() {
        let want_skipped = row.index == 2 || row.index == 4;
        assert_eq!(row.outcome == "skipped", want_skipped, "{row:?}");
    }
    skipped_poses_are_predictions(&r, &[2, 4]);

    // Tracking goes on after the gaps: the last pose is where the undamaged run puts it.
    let clean = dir.path().join("clean");
    bin_folder(&clean, 7);
    let c = run(&clean, &dir.path().join("out-clean"), &[]);
    c.succeeded_with_frames(7);
    assert_eq!(c.count("skipped_frames"), 0);
    let gap = distance(&c.poses()[6], &r.poses()[6]);
    println!("frame 6 with frames 2 and 4 skipped: {gap:.4} m from the undamaged run");
    assert!(gap < 0.1, "frame 6 is {gap:.3} m off the undamaged run");

    // --strict: the first damaged file ends the run, exit 1 naming it; frames 0-1 are written.
    let s = run(
        &data,
        &dir.path().join("out-strict"),
        &["--set", "output.strict=true"],
    );
    let line = s.failed_naming(&truncated);
    assert!(line.contains("not a multiple of 16"), "{line}");
    assert_eq!(s.poses().len(), 2, "the frames before the damaged one");
}

#[test]
fn garbage_ply_and_pcd_headers_are_skipped_warned_about_and_counted() {
    // Per format: a header with the right magic but nonsense inside, and bytes that are no
    // header at all.
    let garbage: [(&str, &[u8], &[u8]); 2] = [
        (
            "ply",
            b"ply\nformat ascii 1.0\nelement vertex 20000\nproperty float x\nproperty flaot y\n\
              property float z\nend_header\n1 2 3\n",
            b"\x00\x01binary junk \xff\xfe\n\n\nend_header\n",
        ),
        (
            "pcd",
            b"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n\
              WIDTH banana\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n1 2 3\n",
            b"\x00\x01binary junk \xff\xfe\n\n\nDATA binary\n",
        ),
    ];
    for (ext, bad_header, junk) in garbage {
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("data");
        let frames = velodyne(&data);
        let name = |k: usize| frames.join(format!("{k:06}.{ext}"));
        for k in [0, 1, 3, 5] {
            let points = kitti_points(k);
            match ext {
                "ply" => ply::write(&name(k), &points, None).unwrap(),
                _ => pcd::write(&name(k), &points, None).unwrap(),
            }
        }
        std::fs::write(name(2), bad_header).unwrap();
        std::fs::write(name(4), junk).unwrap();

        let r = run(&data, &dir.path().join("out"), &[]);
        r.succeeded_with_frames(6);
        for k in [2, 4] {
            println!("{ext}: {}", warning_for(&r, &name(k)));
        }
        assert_eq!(r.warnings().len(), 2, "{ext}: stderr:\n{}", r.stderr);
        assert_eq!(r.count("skipped_frames"), 2, "{ext}");
        assert_eq!(r.count("warnings"), 2, "{ext}");
        for row in r.rows() {
            let want_skipped = row.index == 2 || row.index == 4;
            assert_eq!(row.outcome == "skipped", want_skipped, "{ext}: {row:?}");
        }
        skipped_poses_are_predictions(&r, &[2, 4]);
        assert_eq!(r.summary()["input"]["format"], ext, "read as {ext}");

        let s = run(
            &data,
            &dir.path().join("out-strict"),
            &["--set", "output.strict=true"],
        );
        s.failed_naming(&name(2));
        assert_eq!(
            s.poses().len(),
            2,
            "{ext}: the frames before the damaged one"
        );
    }
}

#[test]
fn timestamps_files_of_the_wrong_length_are_ignored_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    bin_folder(&data, 5);
    let stamps_dir = data.join("timestamps");
    std::fs::create_dir(&stamps_dir).unwrap();
    let side = |k: usize| stamps_dir.join(format!("{k:06}.bin"));
    for k in 0..5 {
        let mut stamps = sweep_stamps(&kitti_points(k));
        if k == 1 {
            stamps.pop(); // one stamp short
        }
        let mut bytes = stamp_bytes(&stamps);
        if k == 3 {
            bytes.truncate(bytes.len() - 3); // no whole number of f64
        }
        std::fs::write(side(k), bytes).unwrap();
    }
    let points1 = kitti_points(1).len();

    let r = run(&data, &dir.path().join("out"), &[]);
    r.succeeded_with_frames(5);
    let w = warning_for(&r, &side(1));
    assert!(
        w.contains(&format!("{} timestamps for {points1} points", points1 - 1))
            && w.contains("ignored"),
        "{w}"
    );
    let w = warning_for(&r, &side(3));
    assert!(w.contains("not a multiple of 8"), "{w}");
    assert_eq!(r.warnings().len(), 2, "stderr:\n{}", r.stderr);
    assert_eq!(r.count("warnings"), 2);
    assert_eq!(
        r.count("skipped_frames"),
        0,
        "the frames themselves are used"
    );
    for row in r.rows() {
        let ignored = row.index == 1 || row.index == 3;
        assert_eq!(row.deskewed, !ignored, "{row:?}");
        assert_eq!(row.outcome, "registered", "{row:?}");
    }

    let s = run(
        &data,
        &dir.path().join("out-strict"),
        &["--set", "output.strict=true"],
    );
    s.failed_naming(&side(1));
    assert_eq!(s.poses().len(), 1, "the frame before the bad timestamps");
}

#[test]
fn timestamps_all_equal_or_not_finite_are_flagged_in_frames_csv() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    bin_folder(&data, 6);
    let stamps_dir = data.join("timestamps");
    std::fs::create_dir(&stamps_dir).unwrap();
    // 1: all equal; 3: one NaN; 5: one +inf. The others are a proper sweep.
    let bad = [1, 3, 5];
    for k in 0..6 {
        let mut stamps = sweep_stamps(&kitti_points(k));
        let mid = stamps.len() / 2;
        match k {
            1 => stamps.iter_mut().for_each(|t| *t = 1.7e9),
            3 => stamps[mid] = f64::NAN,
            5 => stamps[mid] = f64::INFINITY,
            _ => {}
        }
        std::fs::write(stamps_dir.join(format!("{k:06}.bin")), stamp_bytes(&stamps)).unwrap();
    }

    let r = run(&data, &dir.path().join("out"), &[]);
    r.succeeded_with_frames(6);
    assert_eq!(r.count("skipped_frames"), 0);
    for row in r.rows() {
        let unusable = bad.contains(&row.index);
        let flagged = row.flags.iter().any(|f| f == "timestamps_ignored");
        assert_eq!(flagged, unusable, "{row:?}");
        assert_eq!(row.deskewed, !unusable, "{row:?}");
    }
    let summary = r.summary();
    assert_eq!(
        summary["degraded_frames"]["timestamps_ignored"],
        bad.len(),
        "{summary:#}"
    );

    // Under --strict the first unusable stamps stop the run, naming the frame's file.
    let s = run(
        &data,
        &dir.path().join("out-strict"),
        &["--set", "output.strict=true"],
    );
    s.failed_naming(&data.join("velodyne").join("000001.bin"));
    assert_eq!(s.poses().len(), 1, "the frame before the unusable stamps");
}

// ------------------------------------------------------------------------------------------
// Containers: bags and MCAP files

#[test]
fn bag_and_mcap_cut_in_the_middle_keep_the_frames_before_then_fail_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["bag", "mcap"] {
        // ouster.* holds 4 clouds (and 2 IMU messages); the copy stops inside frame 2's points.
        let whole = std::fs::read(bag_fixture(&format!("ouster.{ext}"))).unwrap();
        let cut = ouster_payload_at(&whole, 2) + 40;
        let path = dir.path().join(format!("cut.{ext}"));
        std::fs::write(&path, &whole[..cut]).unwrap();

        let r = run(&path, &dir.path().join(format!("out-{ext}")), &[]);
        let line = r.failed_naming(&path);
        assert!(line.contains("cut short"), "{ext}: {line}");
        let poses = r.poses();
        assert_eq!(poses.len(), 2, "{ext}: frames 0 and 1 were processed");
        assert!(poses.iter().flatten().all(|v| v.is_finite()), "{ext}");
        assert_eq!(r.rows().len(), 2, "{ext}: frames.csv");
        assert_eq!(r.count("frames"), 2, "{ext}: summary.json");

        // The undamaged file gives all four.
        let whole_run = run(
            &bag_fixture(&format!("ouster.{ext}")),
            &dir.path().join(format!("out-whole-{ext}")),
            &[],
        );
        whole_run.succeeded_with_frames(4);
    }
}

/// ROS 1 and CDR serializations of a `sensor_msgs/PointCloud2` holding a KITTI scan: one row,
/// fields x, y, z, intensity (FLOAT32 at 0, 4, 8, 12), the scan's bytes as data.
fn cloud_fields() -> [(&'static str, u32); 4] {
    [("x", 0), ("y", 4), ("z", 8), ("intensity", 12)]
}

const FLOAT32: u8 = 7;

fn ros1_cloud(seq: u32, (sec, nsec): (u32, u32), scan: &[u8]) -> Vec<u8> {
    let mut b = Vec::new();
    let u32_ = |b: &mut Vec<u8>, v: u32| b.extend_from_slice(&v.to_le_bytes());
    let str_ = |b: &mut Vec<u8>, s: &str| {
        b.extend_from_slice(&(s.len() as u32).to_le_bytes());
        b.extend_from_slice(s.as_bytes());
    };
    u32_(&mut b, seq);
    u32_(&mut b, sec);
    u32_(&mut b, nsec);
    str_(&mut b, "velodyne");
    u32_(&mut b, 1); // height
    u32_(&mut b, (scan.len() / 16) as u32); // width
    u32_(&mut b, 4);
    for (name, offset) in cloud_fields() {
        str_(&mut b, name);
        u32_(&mut b, offset);
        b.push(FLOAT32);
        u32_(&mut b, 1);
    }
    b.push(0); // is_bigendian
    u32_(&mut b, 16); // point_step
    u32_(&mut b, scan.len() as u32); // row_step
    u32_(&mut b, scan.len() as u32);
    b.extend_from_slice(scan);
    b.push(1); // is_dense
    b
}

/// Little-endian plain CDR (XCDR1): alignment counts from the end of the 4-byte header.
struct Cdr(Vec<u8>);

impl Cdr {
    fn new() -> Self {
        Cdr(vec![0, 1, 0, 0])
    }
    fn align(&mut self, n: usize) {
        while !(self.0.len() - 4).is_multiple_of(n) {
            self.0.push(0);
        }
    }
    fn u32(&mut self, v: u32) {
        self.align(4);
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.0.extend_from_slice(s.as_bytes());
        self.0.push(0);
    }
}

fn cdr_cloud((sec, nsec): (u32, u32), scan: &[u8]) -> Vec<u8> {
    let mut c = Cdr::new();
    c.u32(sec);
    c.u32(nsec);
    c.string("velodyne");
    c.u32(1);
    c.u32((scan.len() / 16) as u32);
    c.u32(4);
    for (name, offset) in cloud_fields() {
        c.string(name);
        c.u32(offset);
        c.u8(FLOAT32);
        c.u32(1);
    }
    c.u8(0);
    c.u32(16);
    c.u32(scan.len() as u32);
    c.u32(scan.len() as u32);
    c.0.extend_from_slice(scan);
    c.u8(1);
    c.0
}

fn ros1_string(s: &str) -> Vec<u8> {
    let mut b = (s.len() as u32).to_le_bytes().to_vec();
    b.extend_from_slice(s.as_bytes());
    b
}

fn cdr_string(s: &str) -> Vec<u8> {
    let mut c = Cdr::new();
    c.string(s);
    c.0
}

/// One message of a hand-made recording: which connection/channel, and its body.
struct Msg {
    conn: usize,
    time_ns: u64,
    body: Vec<u8>,
}

/// A ROS 1 bag (format 2.0, http://wiki.ros.org/Bags/Format/2.0) with one uncompressed chunk
/// per message and a full index. `conns` are (topic, type, md5sum).
fn write_bag(conns: &[(&str, &str, &str)], msgs: &[Msg]) -> Vec<u8> {
    fn fields(out: &mut Vec<u8>, fields: &[(&str, &[u8])]) {
        for (name, value) in fields {
            let len = (name.len() + 1 + value.len()) as u32;
            out.extend_from_slice(&len.to_le_bytes());
            out.extend_from_slice(name.as_bytes());
            out.push(b'=');
            out.extend_from_slice(value);
        }
    }
    fn record(out: &mut Vec<u8>, header: &[(&str, &[u8])], data: &[u8]) {
        let mut h = Vec::new();
        fields(&mut h, header);
        out.extend_from_slice(&(h.len() as u32).to_le_bytes());
        out.extend_from_slice(&h);
        out.extend_from_slice(&(data.len() as u32).to_le_bytes());
        out.extend_from_slice(data);
    }
    fn time(ns: u64) -> [u8; 8] {
        let mut t = [0u8; 8];
        t[..4].copy_from_slice(&((ns / 1_000_000_000) as u32).to_le_bytes());
        t[4..].copy_from_slice(&((ns % 1_000_000_000) as u32).to_le_bytes());
        t
    }
    let conn_record = |out: &mut Vec<u8>, id: u32| {
        let (topic, tp, md5) = conns[id as usize];
        let mut data = Vec::new();
        fields(
            &mut data,
            &[
                ("topic", topic.as_bytes()),
                ("type", tp.as_bytes()),
                ("md5sum", md5.as_bytes()),
                ("message_definition", b"# kiss-odom test"),
            ],
        );
        record(
            out,
            &[
                ("op", &[7]),
                ("conn", &id.to_le_bytes()),
                ("topic", topic.as_bytes()),
            ],
            &data,
        );
    };
    let header = |index_pos: u64, chunks: u32| {
        let mut h = Vec::new();
        record(
            &mut h,
            &[
                ("op", &[3]),
                ("index_pos", &index_pos.to_le_bytes()),
                ("conn_count", &(conns.len() as u32).to_le_bytes()),
                ("chunk_count", &chunks.to_le_bytes()),
            ],
            &[b' '; 64],
        );
        h
    };
    const MAGIC: &[u8] = b"#ROSBAG V2.0\n";
    let base = (MAGIC.len() + header(0, 0).len()) as u64;
    let mut section = Vec::new();
    let mut infos = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    for m in msgs {
        let c = m.conn as u32;
        let mut data = Vec::new();
        if seen.insert(c) {
            conn_record(&mut data, c);
        }
        let offset = data.len() as u32;
        record(
            &mut data,
            &[
                ("op", &[2]),
                ("conn", &c.to_le_bytes()),
                ("time", &time(m.time_ns)),
            ],
            &m.body,
        );
        let pos = base + section.len() as u64;
        record(
            &mut section,
            &[
                ("op", &[5]),
                ("compression", b"none"),
                ("size", &(data.len() as u32).to_le_bytes()),
            ],
            &data,
        );
        let mut entry = time(m.time_ns).to_vec();
        entry.extend_from_slice(&offset.to_le_bytes());
        record(
            &mut section,
            &[
                ("op", &[4]),
                ("ver", &1u32.to_le_bytes()),
                ("conn", &c.to_le_bytes()),
                ("count", &1u32.to_le_bytes()),
            ],
            &entry,
        );
        infos.push((pos, m.time_ns, c));
    }
    let mut out = MAGIC.to_vec();
    out.extend(header(base + section.len() as u64, infos.len() as u32));
    out.extend(section);
    for id in 0..conns.len() as u32 {
        conn_record(&mut out, id);
    }
    for (pos, t, c) in infos {
        let mut counts = c.to_le_bytes().to_vec();
        counts.extend_from_slice(&1u32.to_le_bytes());
        record(
            &mut out,
            &[
                ("op", &[6]),
                ("ver", &1u32.to_le_bytes()),
                ("chunk_pos", &pos.to_le_bytes()),
                ("start_time", &time(t)),
                ("end_time", &time(t)),
                ("count", &1u32.to_le_bytes()),
            ],
            &counts,
        );
    }
    out
}

/// An MCAP file (https://mcap.dev/spec) with messages outside chunks and no summary section.
/// `channels` are (topic, schema name); every channel has its own schema, `cdr` encoding.
fn write_mcap(channels: &[(&str, &str)], msgs: &[Msg]) -> Vec<u8> {
    const MAGIC: &[u8] = b"\x89MCAP0\r\n";
    fn record(out: &mut Vec<u8>, opcode: u8, content: &[u8]) {
        out.push(opcode);
        out.extend_from_slice(&(content.len() as u64).to_le_bytes());
        out.extend_from_slice(content);
    }
    fn string(out: &mut Vec<u8>, s: &str) {
        out.extend_from_slice(&(s.len() as u32).to_le_bytes());
        out.extend_from_slice(s.as_bytes());
    }
    let mut out = MAGIC.to_vec();
    let mut header = Vec::new();
    string(&mut header, "ros2");
    string(&mut header, "kiss-odom tests");
    record(&mut out, 0x01, &header);
    for (i, (topic, schema)) in channels.iter().enumerate() {
        let id = (i + 1) as u16;
        let mut s = id.to_le_bytes().to_vec();
        string(&mut s, schema);
        string(&mut s, "ros2msg");
        string(&mut s, "# kiss-odom test");
        record(&mut out, 0x03, &s);
        let mut c = id.to_le_bytes().to_vec();
        c.extend_from_slice(&id.to_le_bytes()); // schema id
        string(&mut c, topic);
        string(&mut c, "cdr");
        c.extend_from_slice(&0u32.to_le_bytes()); // no metadata
        record(&mut out, 0x04, &c);
    }
    for (seq, m) in msgs.iter().enumerate() {
        let mut c = ((m.conn + 1) as u16).to_le_bytes().to_vec();
        c.extend_from_slice(&(seq as u32).to_le_bytes());
        c.extend_from_slice(&m.time_ns.to_le_bytes()); // log time
        c.extend_from_slice(&m.time_ns.to_le_bytes()); // publish time
        c.extend_from_slice(&m.body);
        record(&mut out, 0x05, &c);
    }
    record(&mut out, 0x0F, &0u32.to_le_bytes()); // data end, no CRC
    let mut footer = 0u64.to_le_bytes().to_vec(); // no summary
    footer.extend_from_slice(&0u64.to_le_bytes());
    footer.extend_from_slice(&0u32.to_le_bytes());
    record(&mut out, 0x02, &footer);
    out.extend_from_slice(MAGIC);
    out
}

#[test]
fn a_wrong_message_type_on_the_topic_keeps_the_frames_before_then_fails_naming_the_file() {
    // /points carries three KITTI scans as PointCloud2, then a String (a second publisher on
    // the same topic), then a fourth scan.
    let dir = tempfile::tempdir().unwrap();
    let scans: Vec<Vec<u8>> = (0..4).map(kitti_bytes).collect();
    let stamp = |k: usize| (1_700_000_000 + k as u32 / 10, (k as u32 % 10) * 100_000_000);
    let time_ns = |k: usize| {
        let (s, n) = stamp(k);
        u64::from(s) * 1_000_000_000 + u64::from(n)
    };
    let order = [(0, 0), (0, 1), (0, 2), (1, 3), (0, 3)]; // (connection, scan or slot)
    let msgs = |cloud: &dyn Fn(usize) -> Vec<u8>, text: &dyn Fn() -> Vec<u8>| -> Vec<Msg> {
        order
            .iter()
            .enumerate()
            .map(|(i, &(conn, k))| Msg {
                conn,
                time_ns: time_ns(i),
                body: if conn == 0 { cloud(k) } else { text() },
            })
            .collect()
    };
    let bag = write_bag(
        &[
            (
                "/points",
                "sensor_msgs/PointCloud2",
                "1158d486dd51d683ce2f1be655c3c181",
            ),
            (
                "/points",
                "std_msgs/String",
                "992ce8a1687cec8c8bd883ec73ca41d1",
            ),
        ],
        &msgs(&|k| ros1_cloud(k as u32, stamp(k), &scans[k]), &|| {
            ros1_string("not a cloud")
        }),
    );
    let mcap = write_mcap(
        &[
            ("/points", "sensor_msgs/msg/PointCloud2"),
            ("/points", "std_msgs/msg/String"),
        ],
        &msgs(&|k| cdr_cloud(stamp(k), &scans[k]), &|| {
            cdr_string("not a cloud")
        }),
    );
    for (ext, bytes, wrong) in [
        ("bag", bag, "std_msgs/String"),
        ("mcap", mcap, "std_msgs/msg/String"),
    ] {
        let path = dir.path().join(format!("mixed.{ext}"));
        std::fs::write(&path, bytes).unwrap();
        let r = run(&path, &dir.path().join(format!("out-{ext}")), &[]);
        let line = r.failed_naming(&path);
        assert!(line.contains(wrong) && line.contains("/points"), "{line}");
        let poses = r.poses();
        assert_eq!(poses.len(), 3, "{ext}: the three clouds before the String");
        assert!(poses.iter().flatten().all(|v| v.is_finite()), "{ext}");
        let rows = r.rows();
        assert!(
            rows.iter().all(|row| row.outcome == "registered"),
            "{ext}: {rows:?}"
        );
        // The clouds really were read and registered: the car moves about 1 m a frame in the
        // KITTI sample.
        let moved = distance(&poses[0], &poses[2]);
        assert!((0.5..5.0).contains(&moved), "{ext}: moved {moved:.3} m");
    }
}

// ------------------------------------------------------------------------------------------
// Nothing to read

#[test]
fn no_frames_or_no_such_path_exit_1_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();

    // A folder with files but no frames, and one whose velodyne/ folder is empty.
    let notes = dir.path().join("notes");
    std::fs::create_dir(&notes).unwrap();
    std::fs::write(notes.join("README.txt"), "no scans here").unwrap();
    let hollow = dir.path().join("hollow");
    velodyne(&hollow);
    for folder in [&notes, &hollow] {
        let r = run(folder, &dir.path().join("out-none"), &[]);
        let line = r.failed_naming(folder);
        assert!(line.contains("no frames"), "{line}");
    }

    // A path that does not exist: refused before the output folder is made.
    let missing = dir.path().join("does-not-exist");
    let out = dir.path().join("out-missing");
    let r = run(&missing, &out, &[]);
    let line = r.failed_naming(&missing);
    assert!(line.contains("no such file"), "{line}");
    assert!(!out.exists(), "nothing written for a missing input");

    // A file that is not a dataset, and a frame range past the end.
    let stray = dir.path().join("scan.txt");
    std::fs::write(&stray, "1 2 3\n").unwrap();
    let r = run(&stray, &dir.path().join("out-stray"), &[]);
    r.failed_naming(&stray);

    let data = dir.path().join("data");
    bin_folder(&data, 2);
    let r = run(&data, &dir.path().join("out-range"), &["--frames", "5.."]);
    let line = r.failed_naming(&data);
    assert!(line.contains("no frames"), "{line}");
}

/// Robust mode's settings given to a run in reference mode are not used: a warning names
/// each (and `--strict` stops the run on it); in robust mode they are used, without a word.
#[test]
fn robust_only_options_in_reference_mode_are_said_unused() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    bin_folder(&data, 2);
    let opts = [
        "--set",
        "registration.lateral_prior=1",
        "--set",
        "registration.cycle_stop=true",
    ];
    let r = run(&data, &dir.path().join("out-ref"), &opts);
    r.ok();
    assert_eq!(r.warnings().len(), 2, "{}", r.stderr);
    r.warning_with(&[
        "registration.lateral_prior = 1.0 not used",
        "robust mode only",
    ]);
    r.warning_with(&["registration.cycle_stop = true not used"]);
    let strict = [&opts[..], &["--set", "output.strict=true"]].concat();
    let s = run(&data, &dir.path().join("out-strict"), &strict);
    assert!(s.stderr.contains("output.strict"), "{}", s.stderr);
    assert_ne!(s.code, 0);
    let robust = [&opts[..], &["--set", "registration.degeneracy=robust"]].concat();
    let r = run(&data, &dir.path().join("out-robust"), &robust);
    r.ok();
    assert!(r.warnings().is_empty(), "{}", r.stderr);
}

/// `kiss-odom eval` on finite poses far enough apart for the error sums to overflow fails
/// naming the metric, rather than writing the ATE as `null` (JSON has no inf) with exit 0.
#[test]
fn eval_with_an_infinite_ate_fails_naming_the_metric() {
    let dir = tempfile::tempdir().unwrap();
    let est = dir.path().join("est.txt");
    let gt = dir.path().join("gt.txt");
    let line = |x: f64| format!("1 0 0 {x:e} 0 1 0 0 0 0 1 0\n");
    std::fs::write(&est, [0.0, 1e200, -1e200].map(line).concat()).unwrap();
    std::fs::write(&gt, [0.0, 1.0, 2.0].map(line).concat()).unwrap();
    let args: Vec<OsString> = vec![
        "eval".into(),
        est.clone().into(),
        gt.into(),
        "--json".into(),
    ];
    let r = kiss_odom_tests::kiss_odom(&args, dir.path());
    let line = r.failed_with(&["est.txt", "ate_m is inf"]);
    println!("{line}");
}
