//! An interrupted run on a damaged bag leaves nothing in the temporary folder: the reader reads
//! a bag without an index in place, never from a repaired copy. Alone in its file because it
//! raises the process-wide stop flag (`kiss_odom::interrupt::raise`, what a SIGINT handler does) and
//! points `TMPDIR` at a folder of its own. The signal itself, sent to a real process, is in
//! `tests/tests/signals.rs`.

mod common;

use common::*;

#[test]
fn an_interrupted_run_on_a_damaged_bag_leaves_no_temporary_copy() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path().join("tmp");
    std::fs::create_dir(&tmp).unwrap();
    // Set before anything in this process makes a temporary file.
    std::env::set_var("TMPDIR", &tmp);
    let files_in_tmp = || std::fs::read_dir(&tmp).unwrap().count();

    // A bag cut in the middle has no index: the reader reads it in place, no copy.
    let whole = std::fs::read(bag_fixture("ouster.bag")).unwrap();
    let bag = dir.path().join("cut.bag");
    std::fs::write(&bag, &whole[..ouster_payload_at(&whole, 2) + 40]).unwrap();
    let opened = kiss_odom_io::open(&bag, kiss_odom_io::Format::Auto, &Default::default());
    assert!(opened.is_ok(), "the frames before the cut are readable");
    assert_eq!(files_in_tmp(), 0, "no copy in TMPDIR");
    drop(opened);

    kiss_odom::interrupt::raise(2);
    let r = run(&bag, &dir.path().join("out"), &[]);
    assert_eq!(r.code, 130, "128 + SIGINT; stderr:\n{}", r.stderr);
    let s = r.summary();
    assert_eq!(s["interrupted"], true, "{s:#}");
    assert_eq!(s["frames"], 0, "stopped before the first frame");
    assert_eq!(files_in_tmp(), 0, "nothing left in TMPDIR");
}
