//! Bad input in the dataset layouts, on copies of the shared simulated drive: refused naming
//! the file, or reported and the rest used.

use super::{copy_of, options, simulated, FRAMES};
use crate::common::run;
use kiss_odom_io::layouts;
use kiss_odom_io::{open, Format, Item, OpenOptions};

#[test]
fn auto_refuses_a_folder_with_the_structure_of_two_layouts() {
    let dir = tempfile::tempdir().unwrap();
    let root = copy_of(dir.path(), "boreas");
    std::fs::create_dir(root.join("Ouster")).unwrap();
    let e = format!("{:#}", kiss_odom_io::open::detect(&root).unwrap_err());
    assert!(
        e.contains("mulran") && e.contains("boreas") && e.contains("--format"),
        "{e}"
    );
    // Named, it opens.
    assert!(open(&root, Format::Boreas, &OpenOptions::default()).is_ok());
}

#[test]
fn a_mulran_folder_without_global_pose_csv_is_refused_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let root = copy_of(dir.path(), "mulran");
    std::fs::remove_file(root.join("global_pose.csv")).unwrap();
    for format in [Format::Mulran, Format::Auto] {
        let e = format!(
            "{:#}",
            open(&root, format, &OpenOptions::default()).err().unwrap()
        );
        assert!(e.contains("global_pose.csv: no such file"), "{e}");
    }
}

#[test]
fn mulran_pose_rows_missing_around_a_scan_are_reported_with_the_gap() {
    let dir = tempfile::tempdir().unwrap();
    let root = copy_of(dir.path(), "mulran");
    let csv = root.join("global_pose.csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    // Two rows a scan, 0.05 s apart: without rows 2..7 (0.2 to 0.4 s), the scan at 0.3 s is
    // 0.15 s from its nearest rows, the others 0.05 s.
    let kept: Vec<&str> = text
        .lines()
        .enumerate()
        .filter(|(i, _)| !(2..7).contains(i))
        .map(|(_, l)| l)
        .collect();
    std::fs::write(&csv, kept.join("\n")).unwrap();
    let ds = open(&root, Format::Mulran, &OpenOptions::default()).unwrap();
    let w = ds.info.warnings.join("\n");
    assert!(
        w.contains("global_pose.csv") && w.contains("1 scan(s) are more than 0.1 s"),
        "{w}"
    );
}

#[test]
fn a_ground_truth_with_a_row_missing_is_reported_and_the_rest_scored() {
    let dir = tempfile::tempdir().unwrap();
    let root = copy_of(dir.path(), "boreas");
    let csv = root.join("applanix/lidar_poses.csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    std::fs::write(&csv, lines[..lines.len() - 1].join("\n")).unwrap();
    let ds = open(&root, Format::Boreas, &OpenOptions::default()).unwrap();
    let w = ds.info.warnings.join("\n");
    let counts = format!("{} poses for {FRAMES} scans", FRAMES - 1);
    assert!(w.contains(&format!("lidar_poses.csv has {counts}")), "{w}");
    let r = run(&root, &dir.path().join("out"), &["--format", "boreas"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stderr.contains(&counts), "{}", r.stderr);
    assert!(
        r.number("metrics.ate_m").is_finite(),
        "scored on the {} frames",
        FRAMES - 1
    );
}

#[test]
fn a_csv_ground_truth_with_a_short_row_is_refused_naming_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let root = copy_of(dir.path(), "ncd");
    let csv = root.join("ground_truth/registered_poses.csv");
    let mut text = std::fs::read_to_string(&csv).unwrap();
    text.push_str("1583836592,0,1,2,3\n");
    std::fs::write(&csv, text).unwrap();
    let e = format!(
        "{:#}",
        open(&root, Format::Ncd, &OpenOptions::default())
            .err()
            .unwrap()
    );
    // A header line, a row a scan, then the short one.
    let line = format!("line {}: 5 columns", FRAMES + 2);
    assert!(
        e.contains("registered_poses.csv") && e.contains(&line),
        "{e}"
    );
}

#[test]
fn an_nclt_scan_cut_mid_point_is_skipped_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let root = copy_of(dir.path(), "nclt").join("2012-01-08");
    let scans = layouts::layout(&root, Format::Nclt, &OpenOptions::default())
        .unwrap()
        .scans;
    let cut = &scans[2].path;
    let mut bytes = std::fs::read(cut).unwrap();
    bytes.truncate(bytes.len() - 3);
    std::fs::write(cut, bytes).unwrap();
    let mut ds = open(&root, Format::Nclt, &OpenOptions::default()).unwrap();
    let mut skipped = Vec::new();
    while let Some(item) = ds.frames.next_item().unwrap() {
        if let Item::Skipped { index, reason, .. } = item {
            skipped.push((index, reason));
        }
    }
    assert_eq!(skipped.len(), 1, "{skipped:?}");
    assert_eq!(skipped[0].0, 2);
    let reason = &skipped[0].1;
    assert!(
        reason.contains(&cut.display().to_string()) && reason.contains("multiple of 8"),
        "{reason}"
    );
}

#[test]
fn scans_and_poses_that_disagree_in_count_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let root = copy_of(dir.path(), "apollo");
    std::fs::remove_file(root.join(format!("pcds/{FRAMES}.pcd"))).unwrap();
    let ds = open(&root, Format::Apollo, &OpenOptions::default()).unwrap();
    let w = ds.info.warnings.join("\n");
    let counts = format!("gt_poses.txt has {FRAMES} poses for {} scans", FRAMES - 1);
    assert!(w.contains(&counts) && w.contains("last 1"), "{w}");
    let root = copy_of(dir.path(), "helipr");
    std::fs::write(root.join("LiDAR_GT/global_Avia_gt.txt"), "").unwrap();
    let e = format!(
        "{:#}",
        open(&root, Format::Helipr, &options(Some("avia")))
            .err()
            .unwrap()
    );
    assert!(
        e.contains("global_Avia_gt.txt") && e.contains("no rows"),
        "{e}"
    );
    // The shared folder itself holds all four LiDARs too.
    let e = format!(
        "{:#}",
        open(simulated("helipr"), Format::Helipr, &OpenOptions::default())
            .err()
            .unwrap()
    );
    assert!(
        e.contains("several sensors") && e.contains("--sequence"),
        "{e}"
    );
}
