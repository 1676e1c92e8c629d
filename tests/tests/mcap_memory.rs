//! A damaged MCAP file costs memory by its size, not by what its length fields declare: the
//! fuzzer's 7 kB input whose chunk claims ~4 GB (fuzz/corpus/mcap/regress-oom-*) is read with
//! the mcap crate fed in bounded pieces, so the run's RSS stays far below the claim (fed without
//! that bound, the crate's reader allocates what the chunk declares: 4.2 GB of RSS). Its own test binary, so no other
//! test's memory counts.

use kiss_odom::memory::{peak_rss_bytes, reset_peak_rss, rss_bytes};
use kiss_odom_io::ros::mcap;
use kiss_odom_io::OpenOptions;
use kiss_odom_tests::repo;

#[test]
fn a_chunk_declaring_gigabytes_is_not_allocated() {
    let input = repo().join("fuzz/corpus/mcap/regress-oom-a416086db17ca760");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("damaged.mcap");
    std::fs::copy(&input, &path).unwrap();
    if !reset_peak_rss() {
        println!("SKIP: this kernel cannot reset the peak RSS (/proc/self/clear_refs)");
        return;
    }
    let before = rss_bytes().unwrap_or(0);
    if let Ok(mut d) = mcap::open(&path, &OpenOptions::default()) {
        for _ in 0..256 {
            match d.frames.next_item() {
                Ok(Some(_)) => {}
                Ok(None) | Err(_) => break,
            }
        }
    }
    let grew = peak_rss_bytes().unwrap_or(u64::MAX).saturating_sub(before);
    let limit = 256u64 << 20;
    println!(
        "peak RSS growth reading the damaged file: {:.1} MiB (limit {} MiB)",
        grew as f64 / f64::from(1u32 << 20),
        limit >> 20
    );
    assert!(grew < limit, "{grew} bytes");
}
