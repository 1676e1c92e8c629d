//! The file readers of the host against files built here and against real KITTI data.
//!
//! Round trips write small generated frames with the crate's writers and read them back through
//! `kiss_odom_io::open`, the path `kiss-odom run` takes. Readers are also fed files built by
//! hand in these tests (headers as text, payloads as bytes), so that a reader and a writer
//! sharing one mistake cannot pass. Damaged files must become skipped frames or warnings that
//! name the file, never a panic or a silently wrong frame.
//!
//! KITTI checks use `../shared/data/kitti-mini` and two goldens produced by the reference
//! kiss-icp 1.3.0 (`tests/reference/gen_kitti_correction.py`): the corrected first scan of
//! sequence 01 and its ground truth in the LiDAR frame.

use kiss_odom_io::folders::{bin, generic, kitti, pcd, ply};
use kiss_odom_io::{self as io, poses, Dataset, Format, Item};
use nalgebra::{Isometry3, Matrix4, Vector3};
use std::path::{Path, PathBuf};

// ------------------------------------------------------------------------------------------
// Helpers

fn kitti_mini() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/kitti-mini")
}

fn seq01() -> PathBuf {
    kitti_mini().join("sequences/01")
}

fn golden(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures/golden")
        .join(name)
}

fn open(path: &Path, format: Format) -> Dataset {
    io::open(path, format, &Default::default())
        .unwrap_or_else(|e| panic!("{}: {e:#}", path.display()))
}

fn all_items(dataset: &mut Dataset) -> Vec<Item> {
    let mut items = Vec::new();
    while let Some(item) = dataset.frames.next_item().expect("no container damage") {
        items.push(item);
    }
    items
}

fn frame(item: &Item) -> &io::Frame {
    match item {
        Item::Frame(f) => f,
        Item::Skipped { reason, .. } => panic!("unexpected skip: {reason}"),
    }
}

fn skip_reason(item: &Item) -> &str {
    match item {
        Item::Skipped { reason, .. } => reason,
        Item::Frame(f) => panic!("{} was read but should have been skipped", f.name),
    }
}

/// A small deterministic cloud whose coordinates are exact in `f32` (so `.bin` round trips are
/// exact too), different for each `seed`.
fn cloud(seed: usize, n: usize) -> Vec<[f64; 3]> {
    (0..n)
        .map(|i| {
            let a = (seed * 31 + i) as f64;
            [
                a * 0.25 - 7.5,
                (a * 1.75).sin() * 40.0,
                -1.5 + (i % 7) as f64 * 0.125,
            ]
            .map(|v| v as f32 as f64)
        })
        .collect()
}

fn stamps(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| 1.7e9 + i as f64 / (n as f64 * 10.0))
        .collect()
}

fn velodyne(root: &Path) -> PathBuf {
    let dir = root.join("velodyne");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn le_bytes<const N: usize>(values: impl IntoIterator<Item = [u8; N]>) -> Vec<u8> {
    values.into_iter().flatten().collect()
}

// ------------------------------------------------------------------------------------------
// Round trips through the generic layout

#[test]
fn bin_frames_are_numbered_by_their_name_and_gaps_are_skipped_frames() {
    let dir = tempfile::tempdir().unwrap();
    let frames = velodyne(dir.path());
    // The number in the name is the frame: 2 before 10, whatever the directory listing says,
    // and 3..9 are missing.
    let names = [(1, "frame_1.bin"), (2, "frame_2.bin"), (10, "frame_10.bin")];
    for (seed, name) in names {
        bin::write(&frames.join(name), &cloud(seed, 50 + seed)).unwrap();
    }
    let mut ds = open(dir.path(), Format::Auto);
    assert_eq!(ds.info.format, Some(Format::Bin));
    assert!(!ds.info.kitti_correction);
    assert_eq!(ds.frames.len_hint(), Some(10));
    let items = all_items(&mut ds);
    assert_eq!(items.len(), 10);
    let indices: Vec<usize> = items.iter().map(Item::index).collect();
    assert_eq!(indices, (1..=10).collect::<Vec<_>>());
    for (seed, name) in names {
        let f = frame(&items[seed - 1]);
        assert!(f.name.ends_with(name), "{} is not {name}", f.name);
        assert_eq!(f.points, cloud(seed, 50 + seed));
        assert_eq!(f.stamps, None);
        assert!(f.warnings.is_empty());
    }
    for k in 3..10 {
        let reason = skip_reason(&items[k - 1]);
        assert!(
            reason.ends_with(&format!("velodyne/frame_{k}.bin: missing")),
            "{reason}"
        );
    }
}

#[test]
fn bin_writer_writes_f32_xyz_and_zero_intensity() {
    let bytes = bin::encode(&[[1.0, -2.0, 0.5]]);
    let expected = le_bytes([1.0f32, -2.0, 0.5, 0.0].map(f32::to_le_bytes));
    assert_eq!(bytes, expected);
}

#[test]
fn ply_and_pcd_frames_round_trip_exactly_in_binary_and_ascii() {
    let cases = [
        (Format::Ply, "ply", false),
        (Format::Ply, "ply", true),
        (Format::Pcd, "pcd", false),
        (Format::Pcd, "pcd", true),
    ];
    for (case, (format, ext, ascii)) in cases.into_iter().enumerate() {
        let write = |path: &Path, points: &[[f64; 3]], stamps: Option<&[f64]>| {
            match (format, ascii) {
                (Format::Ply, false) => ply::write(path, points, stamps),
                (Format::Ply, true) => ply::write_ascii(path, points, stamps),
                (_, false) => pcd::write(path, points, stamps),
                (_, true) => pcd::write_ascii(path, points, stamps),
            }
            .unwrap()
        };
        let dir = tempfile::tempdir().unwrap();
        // Frames directly in the folder (no velodyne/): the generic layout allows both.
        // Values that are not exact in f32, so a narrowing anywhere would show.
        let points: Vec<[f64; 3]> = cloud(case, 40)
            .iter()
            .map(|p| p.map(|v| v + 1e-9 / 3.0))
            .collect();
        let t = stamps(points.len());
        write(&dir.path().join(format!("0001.{ext}")), &points, Some(&t));
        write(&dir.path().join(format!("0002.{ext}")), &points[..10], None);

        let mut ds = open(dir.path(), Format::Auto);
        assert_eq!(ds.info.format, Some(format), "case {case}");
        let items = all_items(&mut ds);
        assert_eq!(items.len(), 2, "case {case}");
        assert_eq!(frame(&items[0]).points, points, "case {case}");
        assert_eq!(
            frame(&items[0]).stamps.as_deref(),
            Some(&t[..]),
            "case {case}"
        );
        assert_eq!(frame(&items[1]).points, points[..10], "case {case}");
        assert_eq!(frame(&items[1]).stamps, None, "case {case}");
    }
}

// ------------------------------------------------------------------------------------------
// Time fields in files built by hand

#[test]
fn ply_time_fields_are_read_from_ascii_and_binary() {
    let dir = tempfile::tempdir().unwrap();
    let ascii = "ply\nformat ascii 1.0\ncomment hand-made\nelement vertex 3\n\
                 property float x\nproperty float y\nproperty float z\nproperty uchar intensity\n\
                 property double timestamp\nend_header\n\
                 1 2 3 7 0.25\n-1 0.5 4 8 0.5\n10 20 30 9 0.75\n";
    std::fs::write(dir.path().join("a.ply"), ascii).unwrap();

    // Binary little-endian: double x y z, uint t (nanoseconds, as Ouster drivers write).
    let mut binary = b"ply\nformat binary_little_endian 1.0\nelement vertex 2\n\
                       property double x\nproperty double y\nproperty double z\n\
                       property uint t\nend_header\n"
        .to_vec();
    for (p, t) in [([0.1, 0.2, 0.3], 0u32), ([-5.0, 6.5, 1e-3], 99_999_999)] {
        binary.extend(le_bytes(p.map(f64::to_le_bytes)));
        binary.extend(t.to_le_bytes());
    }
    std::fs::write(dir.path().join("b.ply"), binary).unwrap();

    let mut ds = open(dir.path(), Format::Ply);
    let items = all_items(&mut ds);
    let a = frame(&items[0]);
    assert_eq!(
        a.points,
        vec![[1.0, 2.0, 3.0], [-1.0, 0.5, 4.0], [10.0, 20.0, 30.0]]
    );
    assert_eq!(a.stamps, Some(vec![0.25, 0.5, 0.75]));
    let b = frame(&items[1]);
    assert_eq!(b.points, vec![[0.1, 0.2, 0.3], [-5.0, 6.5, 1e-3]]);
    assert_eq!(b.stamps, Some(vec![0.0, 99_999_999.0]));
}

#[test]
fn pcd_time_fields_are_read_from_ascii_and_binary() {
    let dir = tempfile::tempdir().unwrap();
    let ascii = "# .PCD v0.7 - hand-made\nVERSION 0.7\nFIELDS x y z intensity time\n\
                 SIZE 4 4 4 4 4\nTYPE F F F F F\nCOUNT 1 1 1 1 1\nWIDTH 2\nHEIGHT 1\n\
                 VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n\
                 1.5 2.5 -3.5 100 -0.05\n4 5 6 0 0.049\n";
    std::fs::write(dir.path().join("a.pcd"), ascii).unwrap();

    // Binary: float x y z, uint32 t, as an Ouster-style cloud.
    let mut binary = b"VERSION 0.7\nFIELDS x y z t\nSIZE 4 4 4 4\nTYPE F F F U\n\
                       COUNT 1 1 1 1\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n\
                       POINTS 3\nDATA binary\n"
        .to_vec();
    let rows = [
        ([0.5f32, 1.0, 1.5], 0u32),
        ([2.0, -2.0, 0.25], 50_000),
        ([8.0, 9.0, -10.0], 4_000_000_000),
    ];
    for (p, t) in rows {
        binary.extend(le_bytes(p.map(f32::to_le_bytes)));
        binary.extend(t.to_le_bytes());
    }
    std::fs::write(dir.path().join("b.pcd"), binary).unwrap();

    let mut ds = open(dir.path(), Format::Auto);
    assert_eq!(ds.info.format, Some(Format::Pcd));
    let items = all_items(&mut ds);
    let a = frame(&items[0]);
    assert_eq!(a.points, vec![[1.5, 2.5, -3.5], [4.0, 5.0, 6.0]]);
    assert_eq!(a.stamps, Some(vec![-0.05f32 as f64, 0.049f32 as f64]));
    let b = frame(&items[1]);
    assert_eq!(
        b.points,
        rows.iter()
            .map(|(p, _)| p.map(f64::from))
            .collect::<Vec<_>>()
    );
    assert_eq!(b.stamps, Some(vec![0.0, 50_000.0, 4_000_000_000.0]));
}

// ------------------------------------------------------------------------------------------
// Damage confined to one frame

#[test]
fn truncated_and_empty_bins_are_skipped_with_a_reason_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let frames = velodyne(dir.path());
    bin::write(&frames.join("000000.bin"), &cloud(0, 10)).unwrap();
    std::fs::write(frames.join("000001.bin"), []).unwrap();
    bin::write(&frames.join("000002.bin"), &cloud(2, 10)).unwrap();
    std::fs::write(frames.join("000003.bin"), vec![0u8; 1000]).unwrap();
    bin::write(&frames.join("000004.bin"), &cloud(4, 10)).unwrap();

    let mut ds = open(dir.path(), Format::Auto);
    let items = all_items(&mut ds);
    assert_eq!(items.len(), 5, "skips keep their place in the sequence");
    assert_eq!(frame(&items[2]).index, 2);
    assert_eq!(frame(&items[4]).points, cloud(4, 10));

    assert!(matches!(items[1], Item::Skipped { index: 1, .. }));
    let empty = skip_reason(&items[1]);
    assert!(empty.contains("velodyne/000001.bin"), "{empty}");
    assert!(empty.contains("empty"), "{empty}");

    let truncated = skip_reason(&items[3]);
    assert!(
        truncated.ends_with("velodyne/000003.bin: length 1000 is not a multiple of 16 bytes"),
        "{truncated}"
    );
    assert!(!truncated.contains('\n'));
}

#[test]
fn garbage_ply_and_pcd_headers_are_skipped_with_a_reason_naming_the_file() {
    let garbage: [(&str, &[u8]); 4] = [
        ("000001", b"this is not a header\n\x00\x01\x02"),
        (
            "000002",
            b"ply\nformat ascii 1.0\nelement vertex 2\nproperty flaot x\nend_header\n",
        ),
        ("000003", b""),
        ("000004", &[0xff; 64]),
    ];
    for (format, ext) in [(Format::Ply, "ply"), (Format::Pcd, "pcd")] {
        let dir = tempfile::tempdir().unwrap();
        let frames = velodyne(dir.path());
        let good = cloud(0, 5);
        let name = |stem: &str| frames.join(format!("{stem}.{ext}"));
        match format {
            Format::Ply => ply::write(&name("000000"), &good, None).unwrap(),
            _ => pcd::write(&name("000000"), &good, None).unwrap(),
        }
        for (stem, bytes) in garbage {
            std::fs::write(name(stem), bytes).unwrap();
        }
        let mut ds = open(dir.path(), Format::Auto);
        assert_eq!(ds.info.format, Some(format));
        let items = all_items(&mut ds);
        assert_eq!(items.len(), 5);
        assert_eq!(frame(&items[0]).points, good);
        for (item, (stem, _)) in items[1..].iter().zip(garbage) {
            let reason = skip_reason(item);
            println!("{reason}");
            assert!(
                reason.contains(&format!("velodyne/{stem}.{ext}: ")),
                "{reason}"
            );
            assert!(!reason.contains('\n'), "{reason:?}");
        }
    }
}

#[test]
fn ply_with_fewer_vertices_than_declared_is_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("000000.ply");
    ply::write(&path, &cloud(0, 20), None).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() - 12]).unwrap();
    let mut ds = open(dir.path(), Format::Auto);
    let reason = skip_reason(&all_items(&mut ds)[0]).to_string();
    assert!(reason.contains("000000.ply: "), "{reason}");
}

#[test]
fn timestamps_side_files_are_used_and_wrong_lengths_become_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let frames = velodyne(dir.path());
    let stamps_dir = dir.path().join("timestamps");
    std::fs::create_dir(&stamps_dir).unwrap();
    for i in 0..4 {
        bin::write(&frames.join(format!("{i:06}.bin")), &cloud(i, 8)).unwrap();
    }
    let good = stamps(8);
    std::fs::write(
        stamps_dir.join("000000.bin"),
        le_bytes(good.iter().map(|t| t.to_le_bytes())),
    )
    .unwrap();
    // One stamp short, a length that is no whole number of f64, and no file at all (000003).
    std::fs::write(
        stamps_dir.join("000001.bin"),
        le_bytes(good[..7].iter().map(|t| t.to_le_bytes())),
    )
    .unwrap();
    std::fs::write(stamps_dir.join("000002.bin"), [0u8; 60]).unwrap();

    let mut ds = open(dir.path(), Format::Auto);
    let items = all_items(&mut ds);
    let f0 = frame(&items[0]);
    assert_eq!(f0.stamps.as_deref(), Some(&good[..]));
    assert!(f0.warnings.is_empty(), "{:?}", f0.warnings);
    for (i, what) in [(1, "7 timestamps for 8 points"), (2, "length 60"), (3, "")] {
        let f = frame(&items[i]);
        assert_eq!(f.points, cloud(i, 8), "frame {i} is kept");
        assert_eq!(f.stamps, None, "frame {i}");
        assert_eq!(f.warnings.len(), 1, "frame {i}: {:?}", f.warnings);
        let w = &f.warnings[0];
        assert!(w.contains(&format!("timestamps/{i:06}.bin: ")), "{w}");
        assert!(w.contains(what), "{w}");
    }
}

#[test]
fn side_files_give_frame_times_and_ground_truth() {
    let dir = tempfile::tempdir().unwrap();
    let frames = velodyne(dir.path());
    let truth: Vec<Isometry3<f64>> = (0..3)
        .map(|i| {
            let f = i as f64;
            Isometry3::new(
                Vector3::new(f, 0.5 * f, 0.0),
                Vector3::new(0.0, 0.0, 0.1 * f),
            )
        })
        .collect();
    for i in 0..3 {
        bin::write(&frames.join(format!("{i:06}.bin")), &cloud(i, 4)).unwrap();
    }
    poses::write_kitti(&dir.path().join("poses.txt"), &truth).unwrap();
    std::fs::write(dir.path().join("times.txt"), "0.0\n0.1\n0.2\n").unwrap();

    let mut ds = open(dir.path(), Format::Bin);
    assert_eq!(ds.info.frame_times, Some(vec![0.0, 0.1, 0.2]));
    assert_eq!(
        ds.info.ground_truth_path.as_deref(),
        Some(dir.path().join("poses.txt").as_path())
    );
    let gt = ds.info.ground_truth.clone().expect("poses.txt read");
    assert_eq!(gt.len(), 3);
    for (a, b) in gt.iter().zip(&truth) {
        assert!((a.to_homogeneous() - b.to_homogeneous()).amax() < 1e-15);
    }
    let items = all_items(&mut ds);
    assert_eq!(frame(&items[2]).time, Some(0.2));
}

#[test]
fn a_folder_without_frames_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("notes.txt"), "no scans here").unwrap();
    for format in [Format::Auto, Format::Bin, Format::Ply, Format::Pcd] {
        let Err(e) = io::open(dir.path(), format, &Default::default()) else {
            panic!("{format:?} opened a folder without frames");
        };
        let e = format!("{e:#}");
        assert!(e.contains(&dir.path().display().to_string()), "{e}");
    }
    let missing = dir.path().join("nope");
    let Err(e) = io::open(&missing, Format::Auto, &Default::default()) else {
        panic!("opened a missing path");
    };
    assert!(format!("{e:#}").contains("nope"));
}

#[test]
fn seek_positions_the_next_item() {
    let dir = tempfile::tempdir().unwrap();
    let frames = velodyne(dir.path());
    for i in 0..4 {
        bin::write(&frames.join(format!("{i}.bin")), &cloud(i, 3)).unwrap();
    }
    let mut ds = open(dir.path(), Format::Auto);
    assert!(ds.frames.seek(2));
    let item = ds.frames.next_item().unwrap().unwrap();
    assert_eq!(frame(&item).index, 2);
    assert_eq!(frame(&item).points, cloud(2, 3));
    assert!(ds.frames.seek(0));
    assert_eq!(frame(&ds.frames.next_item().unwrap().unwrap()).index, 0);
    assert!(ds.frames.seek(4), "seeking to the end is allowed");
    assert!(ds.frames.next_item().unwrap().is_none());
    assert!(!ds.frames.seek(5));
}

#[test]
fn an_explicit_format_wins_over_detection() {
    let dir = tempfile::tempdir().unwrap();
    bin::write(&dir.path().join("0.bin"), &cloud(0, 3)).unwrap();
    ply::write(&dir.path().join("1.ply"), &cloud(1, 4), None).unwrap();
    // Two formats: `auto` refuses with the counts and the way out.
    let Err(e) = io::open(dir.path(), Format::Auto, &Default::default()) else {
        panic!("auto opened a folder of .bin and .ply frames");
    };
    let e = format!("{e:#}");
    assert!(
        e.contains("1 *.bin, 1 *.ply") && e.contains("--format"),
        "{e}"
    );
    let mut ds = open(dir.path(), Format::Ply);
    assert!(
        ds.info.warnings[0].contains("0.bin"),
        "{:?}",
        ds.info.warnings
    );
    let items = all_items(&mut ds);
    assert_eq!(items.len(), 1);
    assert_eq!(frame(&items[0]).index, 1);
    assert_eq!(frame(&items[0]).points, cloud(1, 4));

    // The KITTI sequence read as plain .bin frames: no correction, no ground-truth conversion.
    let mut ds = open(&seq01(), Format::Bin);
    assert_eq!(ds.info.format, Some(Format::Bin));
    assert!(!ds.info.kitti_correction);
    let raw = bin::read(&seq01().join("velodyne/000000.bin")).unwrap();
    assert_eq!(frame(&ds.frames.next_item().unwrap().unwrap()).points, raw);
}

// ------------------------------------------------------------------------------------------
// KITTI

#[test]
fn kitti_sequence_is_detected_and_every_scan_has_size_over_16_points() {
    let mut ds = open(&seq01(), Format::Auto);
    assert_eq!(ds.info.format, Some(Format::Kitti));
    assert!(ds.info.kitti_correction);
    assert_eq!(ds.frames.len_hint(), Some(10));
    let times = generic::read_times(&seq01().join("times.txt")).unwrap();
    assert_eq!(ds.info.frame_times.as_deref(), Some(&times[..]));
    let items = all_items(&mut ds);
    assert_eq!(items.len(), 10);
    for (i, item) in items.iter().enumerate() {
        let f = frame(item);
        let file = seq01().join(format!("velodyne/{i:06}.bin"));
        let size = std::fs::metadata(&file).unwrap().len() as usize;
        assert_eq!(f.points.len(), size / 16, "{}", file.display());
        assert_eq!(f.stamps, None, "KITTI scans carry no per-point times");
        assert_eq!(f.time, Some(times[i]));
    }
}

#[test]
fn kitti_correction_lifts_every_point_by_0_205_degrees_keeping_its_range() {
    let raw = bin::read(&seq01().join("velodyne/000000.bin")).unwrap();
    let mut ds = open(&seq01(), Format::Kitti);
    let corrected = frame(&ds.frames.next_item().unwrap().unwrap())
        .points
        .clone();
    assert_eq!(corrected.len(), raw.len());

    let offset = 0.205f64.to_radians();
    let (mut worst_angle, mut worst_range, mut worst_elevation) = (0.0f64, 0.0f64, 0.0f64);
    for (p, q) in raw.iter().zip(&corrected) {
        let (p, q) = (Vector3::from(*p), Vector3::from(*q));
        if p.xy().norm() < 1e-3 {
            continue; // no defined elevation
        }
        // atan2(|p x q|, p.q) is accurate for small angles, unlike acos.
        let angle = p.cross(&q).norm().atan2(p.dot(&q));
        let elevation = |v: &Vector3<f64>| v.z.atan2(v.xy().norm());
        worst_angle = worst_angle.max((angle - offset).abs());
        worst_range = worst_range.max((q.norm() - p.norm()).abs());
        worst_elevation = worst_elevation.max((elevation(&q) - elevation(&p) - offset).abs());
    }
    println!(
        "angle error {worst_angle:.2e} rad (tol 1e-12), range change {worst_range:.2e} m \
         (tol 1e-12), elevation error {worst_elevation:.2e} rad (tol 1e-12)"
    );
    assert!(worst_angle < 1e-12);
    assert!(worst_range < 1e-12);
    // Rotation about p x z moves p towards +z by exactly the offset, azimuth unchanged.
    assert!(worst_elevation < 1e-12);
}

/// Rows of a golden text file: numbers per line, `#` lines skipped.
fn golden_rows(name: &str) -> Vec<Vec<f64>> {
    let path = golden(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| l.split_whitespace().map(|t| t.parse().unwrap()).collect())
        .collect()
}

#[test]
fn kitti_correction_matches_the_reference_to_1e_12_m() {
    let rows = golden_rows("kitti_correction_01_000000.txt");
    assert!(rows.len() >= 300, "golden has {} points", rows.len());
    let raw = bin::read(&seq01().join("velodyne/000000.bin")).unwrap();
    let mut ds = open(&seq01(), Format::Auto);
    let ours = frame(&ds.frames.next_item().unwrap().unwrap())
        .points
        .clone();

    let mut worst = 0.0f64;
    for row in &rows {
        let i = row[0] as usize;
        assert_eq!(
            raw[i],
            [row[1], row[2], row[3]],
            "input point {i} as the reference read it"
        );
        let expected = Vector3::new(row[4], row[5], row[6]);
        worst = worst.max((Vector3::from(ours[i]) - expected).norm());
    }
    println!(
        "KITTI correction vs reference: worst {worst:.3e} m over {} points (tol 1e-12 m)",
        rows.len()
    );
    assert!(worst <= 1e-12);
}

fn golden_gt() -> Vec<Matrix4<f64>> {
    golden_rows("kitti_gt_lidar_01.txt")
        .iter()
        .map(|r| Matrix4::from_row_slice(r))
        .collect()
}

#[test]
fn kitti_ground_truth_in_the_lidar_frame_matches_the_reference() {
    let expected = golden_gt();
    let (path, ours) = kitti::ground_truth_matrices(&seq01()).unwrap().unwrap();
    assert!(
        path.ends_with("poses/01.txt"),
        "benchmark file first: {}",
        path.display()
    );
    assert_eq!(ours.len(), expected.len());
    let worst = ours
        .iter()
        .zip(&expected)
        .map(|(a, b)| (a - b).amax())
        .fold(0.0, f64::max);
    println!("LiDAR-frame ground truth vs reference: worst entry {worst:.3e} (tol 1e-12)");
    assert!(worst <= 1e-12);

    // What the dataset hands out: a rigid transform per frame, frame 9 checked on its own.
    let ds = open(&seq01(), Format::Auto);
    let gt = ds.info.ground_truth.expect("sequence 01 has ground truth");
    assert_eq!(gt.len(), 10);
    let nine = gt[9].to_homogeneous();
    let translation = (nine.fixed_view::<3, 1>(0, 3) - expected[9].fixed_view::<3, 1>(0, 3)).amax();
    let rotation = (nine.fixed_view::<3, 3>(0, 0) - expected[9].fixed_view::<3, 3>(0, 0)).amax();
    println!(
        "frame 9: translation {translation:.3e} m (tol 1e-12), rotation entries {rotation:.3e} \
         (tol 1e-6: projection onto SO(3))"
    );
    assert!(translation <= 1e-12);
    assert!(rotation <= 1e-6);
}

#[test]
fn kitti_ground_truth_needs_the_float32_calibration_to_match() {
    // Recompute with Tr parsed as f64 straight from calib.txt, independent of the reader: if the
    // reader did this, the reference would disagree far beyond the 1e-12 tolerance above.
    let calib = std::fs::read_to_string(seq01().join("calib.txt")).unwrap();
    let tr_line = calib.lines().find(|l| l.starts_with("Tr:")).unwrap();
    let v: Vec<f64> = tr_line[3..]
        .split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect();
    let mut tr = Matrix4::identity();
    tr.fixed_view_mut::<3, 4>(0, 0)
        .copy_from(&nalgebra::Matrix3x4::from_row_slice(&v));
    let cam = poses::read_kitti_matrices(&kitti_mini().join("poses/01.txt")).unwrap();
    let tr_inv = tr.try_inverse().unwrap();
    let expected = golden_gt();
    let worst = cam
        .iter()
        .zip(&expected)
        .map(|(c, e)| (tr_inv * c * tr - e).amax())
        .fold(0.0, f64::max);
    println!("float64 calibration vs reference: worst entry {worst:.3e} (must exceed 1e-10)");
    assert!(worst > 1e-10);
}
