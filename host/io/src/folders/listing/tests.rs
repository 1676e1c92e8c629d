//! Tests of `listing`.

use super::*;

#[test]
fn natural_order_compares_digit_runs_as_numbers() {
    let mut names = vec![
        "scan10.bin",
        "scan2.bin",
        "scan1.bin",
        "a.bin",
        "scan02.bin",
    ];
    names.sort_by(|a, b| natural_cmp(a, b));
    assert_eq!(
        names,
        [
            "a.bin",
            "scan1.bin",
            "scan2.bin",
            "scan02.bin",
            "scan10.bin"
        ]
    );
}

#[test]
fn natural_order_keeps_zero_padded_order() {
    let names: Vec<String> = (0..1200).map(|i| format!("{i:06}.bin")).collect();
    let mut sorted = names.clone();
    sorted.reverse();
    sorted.sort_by(|a, b| natural_cmp(a, b));
    assert_eq!(sorted, names);
}

fn touch(dir: &Path, names: &[&str]) {
    for n in names {
        std::fs::write(dir.join(n), [0u8; 16]).unwrap();
    }
}

fn names(listing: &Listing) -> Vec<(usize, String, Option<String>)> {
    listing
        .slots
        .iter()
        .map(|s| {
            let name = s.path.file_name().unwrap().to_string_lossy().into_owned();
            (s.index, name, s.problem.clone())
        })
        .collect()
}

#[test]
fn foreign_names_are_recognised() {
    for name in [
        "._000000.bin",
        ".DS_Store",
        ".000001.bin.swp",
        "000001.bin~",
        "#000001.bin#",
        "000001.bin.bak",
        "000001.bin.part",
        "Thumbs.db",
        "desktop.ini",
        "__MACOSX",
        "~$notes.bin",
    ] {
        assert!(is_foreign(name), "{name}");
    }
    for name in ["000001.bin", "scan_1.pcd", "1694000000.5.ply", "#1.bin"] {
        assert!(!is_foreign(name), "{name}");
    }
}

#[test]
fn numbers_and_times_are_split_from_the_name() {
    assert_eq!(split_number("000005"), Some(("", "000005", "")));
    assert_eq!(split_number("scan_12_left"), Some(("scan_", "12", "_left")));
    assert_eq!(split_number("100.05"), Some(("", "100.05", "")));
    assert_eq!(split_number("cloud.v"), None);
    assert_eq!(split_number("a.5"), Some(("a.", "5", "")));
}

#[test]
fn a_gap_in_numbered_frames_is_a_slot_with_the_missing_name() {
    let dir = tempfile::tempdir().unwrap();
    touch(
        dir.path(),
        &["000000.bin", "000001.bin", "000003.bin", "notes.txt"],
    );
    std::fs::create_dir(dir.path().join("000004.bin")).unwrap();
    touch(dir.path(), &["000005.bin"]);
    let l = list(dir.path(), None).unwrap();
    assert_eq!(l.naming, Naming::Numbered { step: 1 });
    let got = names(&l);
    assert_eq!(got.len(), 6);
    assert_eq!(got[2], (2, "000002.bin".into(), Some("missing".into())));
    assert_eq!(got[4].2.as_deref(), Some("a folder, not a frame file"));
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
}

#[test]
fn time_names_are_ordered_by_time_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let names_in: Vec<String> = (0..10)
        .map(|k| format!("{}.bin", 100.0 + 0.05 * k as f64))
        .collect();
    let refs: Vec<&str> = names_in.iter().map(String::as_str).collect();
    touch(dir.path(), &refs);
    let l = list(dir.path(), None).unwrap();
    assert_eq!(l.naming, Naming::Timed);
    let times: Vec<f64> = l.slots.iter().map(|s| s.time.unwrap()).collect();
    assert!(times.windows(2).all(|w| w[0] < w[1]), "{times:?}");
    // Nanosecond stamps that f64 cannot tell apart still sort exactly.
    let dir = tempfile::tempdir().unwrap();
    touch(
        dir.path(),
        &[
            "1694000000.123456790.pcd",
            "1694000000.123456789.pcd",
            "1694000000.12345678.pcd",
        ],
    );
    let got: Vec<String> = names(&list(dir.path(), None).unwrap())
        .into_iter()
        .map(|n| n.1)
        .collect();
    assert_eq!(
        got,
        [
            "1694000000.12345678.pcd",
            "1694000000.123456789.pcd",
            "1694000000.123456790.pcd"
        ]
    );
    // The same time written twice is refused.
    touch(dir.path(), &["1694000000.1234567800.pcd"]);
    assert!(list(dir.path(), None).is_err());
}

#[test]
fn duplicates_mixed_names_and_mixed_formats_are_refused_with_the_names() {
    let dir = tempfile::tempdir().unwrap();
    touch(dir.path(), &["5.bin", "005.bin"]);
    let e = list(dir.path(), None).unwrap_err().to_string();
    assert!(e.contains("005.bin") && e.contains("5.bin"), "{e}");

    let dir = tempfile::tempdir().unwrap();
    touch(dir.path(), &["000001.bin", "scan.bin"]);
    let e = list(dir.path(), None).unwrap_err().to_string();
    assert!(e.contains("scan.bin"), "{e}");

    let dir = tempfile::tempdir().unwrap();
    touch(
        dir.path(),
        &["000000.bin", "000001.ply", "000002.bin", "000003.bin"],
    );
    let e = list(dir.path(), None).unwrap_err().to_string();
    assert!(
        e.contains("3 *.bin, 1 *.ply") && e.contains("--format"),
        "{e}"
    );
    let l = list(dir.path(), Some(Format::Bin)).unwrap();
    assert_eq!(
        l.slots[1].problem.as_deref(),
        Some("missing (000001.ply is there, in another format)")
    );
    assert!(l.warnings[0].contains("000001.ply"), "{:?}", l.warnings);
}

#[test]
fn thinned_numbering_has_no_gaps_and_sparse_numbers_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    touch(dir.path(), &["0.bin", "100.bin", "200.bin", "400.bin"]);
    let l = list(dir.path(), None).unwrap();
    assert_eq!(l.naming, Naming::Numbered { step: 100 });
    assert_eq!(names(&l).iter().filter(|n| n.2.is_some()).count(), 1);
    let dir = tempfile::tempdir().unwrap();
    touch(dir.path(), &["1.bin", "2.bin", "99999.bin"]);
    assert!(list(dir.path(), None).is_err());
}
