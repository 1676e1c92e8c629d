//! Frame folders shaped the way real recordings arrive: a frame lost in a transfer,
//! files copied from a Mac, frames of two formats, names that are times, a KITTI export without
//! its extrinsic, side files of the wrong length. Each case is built from a copy of
//! `fixtures/kitti-05-reduced` (10 real KITTI scans with calibration, times and ground truth)
//! and run end to end through `kiss-odom run`; the rule every test holds is that a frame is
//! paired with its own ground truth and time, and that anything the tool cannot pair is
//! reported (a warning naming the file, counted in `summary.json`) or refused, never silent.
//! Each test's comment says what pairing by position alone would get wrong.

use kiss_odom_io::folders::{bin, pcd, ply};
use kiss_odom_tests::{kitti_copy, run, Run};
use std::path::{Path, PathBuf};

/// Margin on the ATE of a run with one frame lost against the full run. The full run's ATE is
/// 0.019 m; pairing the frames after the gap with the next frame's ground truth gives 0.282 m.
const ATE_MARGIN_M: f64 = 0.005;

/// The clean KITTI sample, run once per test that compares against it.
fn full_run(dir: &Path) -> Run {
    let data = kitti_copy(dir, "full");
    let r = run(&data, &dir.join("out-full"), &[]);
    r.ok();
    r
}

/// A generic-layout copy (no `calib.txt`) whose frames are `ext` files (`bin`, `ply`, `pcd`).
fn generic_copy(dir: &Path, name: &str, ext: &str) -> PathBuf {
    let data = kitti_copy(dir, name);
    std::fs::remove_file(data.join("calib.txt")).unwrap();
    if ext != "bin" {
        for k in 0..10 {
            let from = frame(&data, k);
            let points = bin::parse(&std::fs::read(&from).unwrap()).unwrap();
            let to = from.with_extension(ext);
            match ext {
                "ply" => ply::write(&to, &points, None).unwrap(),
                _ => pcd::write(&to, &points, None).unwrap(),
            }
            std::fs::remove_file(from).unwrap();
        }
    }
    data
}

/// `data/velodyne/NNNNNN.bin`.
fn frame(data: &Path, k: usize) -> PathBuf {
    data.join(format!("velodyne/{k:06}.bin"))
}

fn indices(r: &Run) -> Vec<usize> {
    r.column("index")
        .iter()
        .map(|i| i.parse().unwrap())
        .collect()
}

/// Lines `0..n` of `poses_kitti.txt` of two runs are the same bytes.
fn same_first_poses(a: &Run, b: &Run, n: usize) {
    assert_eq!(
        a.lines("poses_kitti.txt")[..n],
        b.lines("poses_kitti.txt")[..n],
        "poses of frames 0..{n}"
    );
}

/// `rm velodyne/000005.bin`: the lost frame is named, and every later frame keeps its own
/// ground truth and time (pairing by position would shift them onto the next frame's: ATE
/// 0.282 m instead of 0.019 m).
#[test]
fn a_frame_lost_from_a_kitti_sequence_is_skipped_and_later_frames_keep_their_ground_truth() {
    let dir = tempfile::tempdir().unwrap();
    let full = full_run(dir.path());
    let data = kitti_copy(dir.path(), "gap");
    std::fs::remove_file(frame(&data, 5)).unwrap();
    let gap = run(&data, &dir.path().join("out-gap"), &[]);
    gap.ok().warning_with(&["velodyne/000005.bin", "missing"]);
    assert_eq!(gap.number("skipped_frames"), 1.0);
    assert_eq!(gap.number("warnings"), 1.0);
    assert_eq!(indices(&gap), (0..10).collect::<Vec<_>>());
    assert_eq!(gap.column("outcome")[5], "skipped");
    same_first_poses(&gap, &full, 5);
    // Later frames keep their own times and ground truth.
    assert_eq!(gap.tum_times(), full.tum_times());
    let (a, b) = (gap.number("metrics.ate_m"), full.number("metrics.ate_m"));
    println!("ATE with frame 5 lost {a:.4} m, full run {b:.4} m (margin {ATE_MARGIN_M} m)");
    assert!((a - b).abs() < ATE_MARGIN_M, "ATE {a} against {b}");
    assert_eq!(gap.number("metrics.frames"), 10.0);

    // Under --strict the lost frame is an error naming it.
    let strict = run(
        &data,
        &dir.path().join("out-strict"),
        &["--set", "output.strict=true"],
    );
    strict.failed_with(&["000005.bin"]);
}

/// Other shapes of a gap: a folder or a dangling symlink in place of a frame is a skipped
/// frame naming it, not a name the listing leaves out (which would shift the later frames).
#[test]
fn a_folder_or_dangling_symlink_in_place_of_a_frame_is_a_skipped_frame_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let full = full_run(dir.path());
    let data = kitti_copy(dir.path(), "holes");
    std::fs::remove_file(frame(&data, 3)).unwrap();
    std::fs::create_dir(frame(&data, 3)).unwrap();
    std::fs::remove_file(frame(&data, 7)).unwrap();
    std::os::unix::fs::symlink(dir.path().join("nowhere.bin"), frame(&data, 7)).unwrap();
    let r = run(&data, &dir.path().join("out"), &[]);
    r.ok().warning_with(&["velodyne/000003.bin", "folder"]);
    r.warning_with(&["velodyne/000007.bin", "symlink"]);
    assert_eq!(r.number("skipped_frames"), 2.0);
    assert_eq!(indices(&r), (0..10).collect::<Vec<_>>());
    same_first_poses(&r, &full, 3);
    assert_eq!(r.tum_times(), full.tum_times());
}

/// Every folder layout: generic `.bin`, `.ply` and `.pcd` folders.
#[test]
fn a_frame_lost_from_a_generic_bin_ply_or_pcd_folder_is_skipped_and_pairing_holds() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["bin", "ply", "pcd"] {
        let clean = generic_copy(dir.path(), &format!("clean-{ext}"), ext);
        let c = run(&clean, &dir.path().join(format!("out-clean-{ext}")), &[]);
        c.ok();
        let data = generic_copy(dir.path(), &format!("gap-{ext}"), ext);
        let lost = data.join(format!("velodyne/000004.{ext}"));
        std::fs::remove_file(&lost).unwrap();
        let r = run(&data, &dir.path().join(format!("out-gap-{ext}")), &[]);
        r.ok()
            .warning_with(&[&format!("velodyne/000004.{ext}"), "missing"]);
        assert_eq!(r.number("skipped_frames"), 1.0, "{ext}");
        assert_eq!(indices(&r), (0..10).collect::<Vec<_>>(), "{ext}");
        same_first_poses(&r, &c, 4);
        assert_eq!(r.tum_times(), c.tum_times(), "{ext}");
        assert_eq!(r.number("metrics.frames"), 10.0, "{ext}");
    }
}

/// macOS AppleDouble companions (`._000000.bin`, 4096 bytes) are not frames: read as frames
/// they would be garbage points and shift every index.
#[test]
fn macos_appledouble_companions_are_ignored_with_one_warning() {
    let dir = tempfile::tempdir().unwrap();
    let full = full_run(dir.path());
    let data = kitti_copy(dir.path(), "mac");
    for k in 0..10 {
        let mut header = vec![0u8, 5, 22, 7, 0, 2, 0, 0];
        header.resize(4096, 0x41);
        std::fs::write(data.join(format!("velodyne/._{k:06}.bin")), header).unwrap();
    }
    let r = run(&data, &dir.path().join("out"), &[]);
    r.ok().warning_with(&["ignored 10 file", "._000000.bin"]);
    assert_eq!(r.number("warnings"), 1.0);
    assert_eq!(r.lines("poses_kitti.txt"), full.lines("poses_kitti.txt"));
}

/// Other files that are not frames: hidden files, editor and download leftovers,
/// system files.
#[test]
fn hidden_editor_and_system_files_are_ignored_with_one_warning() {
    let dir = tempfile::tempdir().unwrap();
    let full = full_run(dir.path());
    let data = kitti_copy(dir.path(), "leftovers");
    let velodyne = data.join("velodyne");
    let scan = std::fs::read(frame(&data, 2)).unwrap();
    for name in [
        ".000004.bin",
        ".DS_Store",
        "000003.bin~",
        "#000002.bin#",
        ".000001.bin.swp",
        "000006.bin.part",
        "Thumbs.db",
        "desktop.ini",
    ] {
        std::fs::write(velodyne.join(name), &scan).unwrap();
    }
    std::fs::create_dir(velodyne.join("__MACOSX")).unwrap();
    let r = run(&data, &dir.path().join("out"), &[]);
    r.ok().warning_with(&["ignored 9 file"]);
    assert_eq!(r.number("warnings"), 1.0);
    assert_eq!(r.lines("poses_kitti.txt"), full.lines("poses_kitti.txt"));
}

/// With `.ply` and `.bin` frames mixed, no frame is silently ignored: `auto` refuses the
/// folder, an explicit format names the frames of the other one.
#[test]
fn frames_of_two_formats_are_refused_under_auto_and_the_rest_named_under_an_explicit_format() {
    let dir = tempfile::tempdir().unwrap();
    let data = generic_copy(dir.path(), "mixed", "bin");
    let points = bin::parse(&std::fs::read(frame(&data, 5)).unwrap()).unwrap();
    std::fs::remove_file(frame(&data, 5)).unwrap();
    ply::write(&data.join("velodyne/000005.ply"), &points, None).unwrap();

    let auto = run(&data, &dir.path().join("out-auto"), &[]);
    auto.failed_with(&["9 *.bin", "1 *.ply", "--format"]);

    let bin = run(&data, &dir.path().join("out-bin"), &["--format", "bin"]);
    bin.ok().warning_with(&["000005.ply", "--format bin"]);
    bin.warning_with(&["velodyne/000005.bin", "missing"]);
    assert_eq!(indices(&bin), (0..10).collect::<Vec<_>>());
    assert_eq!(bin.number("skipped_frames"), 1.0);

    let ply = run(&data, &dir.path().join("out-ply"), &["--format", "ply"]);
    ply.ok().warning_with(&["ignored 9", "--format ply"]);
    assert_eq!(indices(&ply), [5]);
}

/// Renames the frames of a generic copy to `names[k]`.
fn rename_frames(data: &Path, names: &[String]) {
    for (k, name) in names.iter().enumerate() {
        std::fs::rename(frame(data, k), data.join("velodyne").join(name)).unwrap();
    }
}

/// Frames named by time with decimals (`100.0.bin` ... `100.45.bin`) are read in time order
/// (sorting the names as text would give 0, 2, 4, 6, 8, 1, 3, 5, 7, 9).
#[test]
fn frames_named_by_decimal_seconds_are_read_in_time_order_with_their_times() {
    let dir = tempfile::tempdir().unwrap();
    let numbered = generic_copy(dir.path(), "numbered", "bin");
    std::fs::remove_file(numbered.join("times.txt")).unwrap();
    let n = run(&numbered, &dir.path().join("out-numbered"), &[]);
    n.ok();
    let data = generic_copy(dir.path(), "timed", "bin");
    std::fs::remove_file(data.join("times.txt")).unwrap();
    let times = [
        "100.0", "100.05", "100.1", "100.15", "100.2", "100.25", "100.3", "100.35", "100.4",
        "100.45",
    ];
    let names: Vec<String> = times.iter().map(|t| format!("{t}.bin")).collect();
    rename_frames(&data, &names);
    let r = run(&data, &dir.path().join("out-timed"), &[]);
    r.ok();
    assert_eq!(r.number("warnings"), 0.0, "stderr:\n{}", r.stderr);
    assert_eq!(r.lines("poses_kitti.txt"), n.lines("poses_kitti.txt"));
    let want: Vec<f64> = times.iter().map(|t| t.parse().unwrap()).collect();
    assert_eq!(r.tum_times(), want);
}

/// Other time names: integer nanoseconds and microsecond decimals give the times in seconds
/// (not frame numbers), and a long interval is reported as lost frames.
#[test]
fn frames_named_by_nanoseconds_or_microseconds_carry_their_times_and_gaps_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let base = generic_copy(dir.path(), "base", "bin");
    std::fs::remove_file(base.join("times.txt")).unwrap();
    let b = run(&base, &dir.path().join("out-base"), &[]);
    b.ok();
    let ns: Vec<String> = (0..10u64)
        .map(|k| format!("{}.bin", 1_694_000_000_950_000_000 + k * 100_000_000))
        .collect();
    let us: Vec<String> = (0..10u64)
        .map(|k| {
            let t = 1_694_000_000_950_000 + k * 100_000;
            format!("{}.{:06}.bin", t / 1_000_000, t % 1_000_000)
        })
        .collect();
    for (case, names) in [("ns", ns), ("us", us)] {
        let data = generic_copy(dir.path(), case, "bin");
        std::fs::remove_file(data.join("times.txt")).unwrap();
        rename_frames(&data, &names);
        let r = run(&data, &dir.path().join(format!("out-{case}")), &[]);
        r.ok();
        assert_eq!(
            r.lines("poses_kitti.txt"),
            b.lines("poses_kitti.txt"),
            "{case}"
        );
        let times = r.tum_times();
        for (k, t) in times.iter().enumerate() {
            let want = 1_694_000_000.95 + 0.1 * k as f64;
            assert!(
                (t - want).abs() < 1e-6,
                "{case} frame {k}: {t} s, want {want} s"
            );
        }
        // A frame lost in the middle shows as an interval twice the usual.
        std::fs::remove_file(data.join("velodyne").join(&names[4])).unwrap();
        let g = run(&data, &dir.path().join(format!("out-{case}-gap")), &[]);
        g.ok()
            .warning_with(&["may be missing", &names[3], &names[5]]);
    }
}

/// A KITTI-shaped folder whose `calib.txt` has no `Tr` is refused, or read as KITTI without
/// ground truth; read as a generic folder it would lose the KITTI correction and score
/// camera-frame ground truth as LiDAR poses (final error 7.25 m).
#[test]
fn a_kitti_folder_without_tr_is_refused_or_read_as_kitti_without_ground_truth() {
    let dir = tempfile::tempdir().unwrap();
    let full = full_run(dir.path());
    let data = kitti_copy(dir.path(), "no-tr");
    let calib = std::fs::read_to_string(data.join("calib.txt")).unwrap();
    let kept: Vec<&str> = calib.lines().filter(|l| !l.starts_with("Tr")).collect();
    std::fs::write(data.join("calib.txt"), kept.join("\n") + "\n").unwrap();

    let auto = run(&data, &dir.path().join("out-auto"), &[]);
    auto.failed_with(&["calib.txt", "Tr", "--format kitti"]);

    let kitti = run(&data, &dir.path().join("out-kitti"), &["--format", "kitti"]);
    kitti
        .ok()
        .warning_with(&["calib.txt", "ground truth not used"]);
    assert!(kitti.summary()["metrics"].is_null(), "no metrics");
    assert_eq!(kitti.summary()["input"]["kitti_correction"], true);
    assert_eq!(
        kitti.lines("poses_kitti.txt"),
        full.lines("poses_kitti.txt"),
        "the KITTI correction is applied"
    );
}

/// Writes the first `rows` lines of the sample's `name` (repeating the last one past its end).
fn side_file(data: &Path, name: &str, rows: usize) {
    let text = std::fs::read_to_string(data.join(name)).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let out: Vec<&str> = (0..rows).map(|k| lines[k.min(lines.len() - 1)]).collect();
    std::fs::write(data.join(name), out.join("\n") + "\n").unwrap();
}

/// Ground truth: a `poses.txt` shorter or longer than the frames is reported with a warning,
/// and the metrics are computed on the frames that have a row.
#[test]
fn ground_truth_shorter_or_longer_than_the_frames_is_reported_and_paired_by_frame() {
    let dir = tempfile::tempdir().unwrap();
    let full = full_run(dir.path());
    let short = kitti_copy(dir.path(), "gt-short");
    side_file(&short, "poses.txt", 8);
    let s = run(&short, &dir.path().join("out-short"), &[]);
    s.ok().warning_with(&["poses.txt", "8 rows", "000009.bin"]);
    assert_eq!(s.number("warnings"), 1.0);
    assert_eq!(
        s.number("metrics.frames"),
        8.0,
        "metrics over the frames with ground truth"
    );
    assert!(s.number("metrics.ate_m") < 0.05);

    let long = kitti_copy(dir.path(), "gt-long");
    side_file(&long, "poses.txt", 12);
    let l = run(&long, &dir.path().join("out-long"), &[]);
    l.ok().warning_with(&["poses.txt", "12 rows"]);
    assert_eq!(l.summary()["metrics"], full.summary()["metrics"]);
}

/// Times: a `times.txt` shorter or longer than the frames is reported, and `poses_tum.txt`
/// never mixes seconds with frame numbers.
#[test]
fn times_shorter_or_longer_than_the_frames_are_reported_and_never_mixed_with_frame_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let full = full_run(dir.path());
    let short = kitti_copy(dir.path(), "times-short");
    side_file(&short, "times.txt", 8);
    let s = run(&short, &dir.path().join("out-short"), &[]);
    s.ok().warning_with(&["times.txt", "8 rows"]);
    let numbers: Vec<f64> = (0..10).map(f64::from).collect();
    assert_eq!(s.tum_times(), numbers, "all frame numbers, no seconds");
    assert_eq!(s.summary()["input"]["tum_times"], "frame numbers");

    let long = kitti_copy(dir.path(), "times-long");
    side_file(&long, "times.txt", 12);
    let l = run(&long, &dir.path().join("out-long"), &[]);
    l.ok().warning_with(&["times.txt", "12 rows"]);
    assert_eq!(l.tum_times(), full.tum_times());
}

/// Two files for one frame, or numbered and unnumbered names together, cannot be paired with
/// ground truth: refused with the names (read as extra frames, they would shift the others).
#[test]
fn duplicate_frame_numbers_and_unnumbered_names_are_refused_with_the_names() {
    let dir = tempfile::tempdir().unwrap();
    let data = kitti_copy(dir.path(), "dup");
    std::fs::copy(frame(&data, 5), data.join("velodyne/5.bin")).unwrap();
    let r = run(&data, &dir.path().join("out-dup"), &[]);
    r.failed_with(&["000005.bin", "5.bin"]);

    let data = kitti_copy(dir.path(), "odd");
    std::fs::copy(frame(&data, 5), data.join("velodyne/scan.bin")).unwrap();
    let r = run(&data, &dir.path().join("out-odd"), &[]);
    r.failed_with(&["scan.bin"]);
}

/// A PLY that declares `x` twice is skipped with the reason: ply-rs keeps one property per
/// name, so its points would be read at the wrong stride.
#[test]
fn a_ply_declaring_a_property_twice_is_skipped_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let data = generic_copy(dir.path(), "ply", "ply");
    let bad = data.join("velodyne/000003.ply");
    let mut text = String::from(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float x\n\
         property float y\nproperty float z\nend_header\n",
    );
    for k in 0..3 {
        text.push_str(&format!("{k} 9 {k} 1\n"));
    }
    std::fs::write(&bad, text).unwrap();
    let r = run(&data, &dir.path().join("out"), &[]);
    r.ok()
        .warning_with(&["velodyne/000003.ply", "property x twice"]);
    assert_eq!(r.number("skipped_frames"), 1.0);
    assert_eq!(r.column("outcome")[3], "skipped");
}
