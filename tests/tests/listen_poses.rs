//! `kiss-odom listen-poses` as a real process fed by a test socket over loopback: pose
//! datagrams out of order, a lost one, a duplicate and bytes that are no datagram end up as
//! `run`'s outputs with every pose's bits intact and each anomaly counted; `--sweeps` stops
//! it, and so does SIGINT with the outputs written; no sender at all is an error after
//! `--idle`.
#![cfg(target_os = "linux")]

use crate::common;
use kiss_odom_sensors::pose_datagram::{Counters, Link, PoseDatagram};
use kiss_odom_tests::{send_in_order, signal, wait_read, wait_until, HANG};
use nalgebra::{Isometry3, Vector3};
use std::net::UdpSocket;
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// A loopback address no one listens on now.
fn free_address() -> String {
    let probe = UdpSocket::bind("127.0.0.1:0").unwrap();
    probe.local_addr().unwrap().to_string()
}

/// `kiss-odom listen-poses` on `addr` into `out`, started and listening.
fn listen(addr: &str, out: &Path, extra: &[&str]) -> Child {
    let mut child = Command::new(env!("CARGO_BIN_EXE_kiss-odom-cli"))
        .args(["listen-poses", "--bind", addr, "--out"])
        .arg(out)
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    common::wait_listening(&mut child, addr, "listen-poses");
    child
}

/// The child's output, killing it if it has not ended after [`HANG`].
fn finish(mut child: Child) -> Output {
    if !wait_until(HANG, || child.try_wait().unwrap().is_some()) {
        let _ = child.kill();
        panic!("listen-poses did not end: {:?}", child.wait_with_output());
    }
    child.wait_with_output().unwrap()
}

/// A rigid pose, sweep 0's.
fn rigid() -> Isometry3<f64> {
    Isometry3::new(Vector3::new(1.25, -0.1, 3.0), Vector3::new(0.1, -0.2, 0.3))
}

/// Sweep `k`'s datagram: sweep 0 a rigid pose's rows (as `run` writes them), the others numbers
/// whose shortest forms are long, tiny, huge, signed zero and subnormal.
fn datagram(k: u32) -> PoseDatagram {
    let pose = if k == 0 {
        kiss_odom_io::poses::rows_from_isometry(&rigid())
    } else {
        let odd = [
            0.1 + 0.2,
            1.0 / 3.0,
            -0.0,
            1e-300,
            5e-324,
            1.7976931348623157e308,
        ];
        core::array::from_fn(|i| odd[i % odd.len()] * f64::from(k) - i as f64 / 7.0)
    };
    PoseDatagram {
        link: if k == 3 { Link::Gap as u16 } else { 0 },
        sweep: k,
        points: 28_000 + k,
        start_ns: 1_000_000_000 * u64::from(k) + 7,
        pose,
        status: if k == 3 { 1 << 4 | 1 << 7 } else { 0 },
        iterations: 10 + k as u16,
        sweep_lost: if k == 3 { 2 } else { 0 },
        counters: Counters {
            packets: 100 * k,
            lost: if k >= 3 { 2 } else { 0 },
            ..Counters::default()
        },
    }
}

fn read(dir: &Path, name: &str) -> String {
    std::fs::read_to_string(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn poses_come_back_bit_exact_in_sweep_order_with_losses_duplicates_and_junk_counted() {
    let dir = tempfile::tempdir().unwrap();
    let addr = free_address();
    // An idle time longer than the hang guard: only `--sweeps 3` can end it in time.
    let child = listen(&addr, dir.path(), &["--sweeps", "3", "--idle", "3600"]);
    let tx = UdpSocket::bind("127.0.0.1:0").unwrap();
    let mut later_one = datagram(1);
    later_one.pose[0] = 99.0;
    let sent: Vec<Vec<u8>> = vec![
        datagram(3).encode().to_vec(),
        b"not a pose datagram".to_vec(),
        datagram(1).encode().to_vec(),
        later_one.encode().to_vec(),
        datagram(0).encode().to_vec(), // the third sweep: --sweeps 3 ends it here
    ];
    let sent: Vec<&[u8]> = sent.iter().map(Vec::as_slice).collect();
    send_in_order(&child, &tx, &addr, &sent);
    let out = finish(child);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert_eq!(
        stderr.trim(),
        "warning: 1 pose datagram(s) lost on the way (missing_sweeps in summary.json)\n\
         warning: 1 datagram(s) that are not pose datagrams, skipped\n\
         warning: the receiver counted lost=2: packets missing in the sensor's sequence\n\
         listen-poses: 3 sweeps, 1 missing, 1 duplicate, 1 undecodable, counters: packets=300 \
         lost=2 bad=0 foreign=0 wrong_size=0 overflow=0 unsent=0 frame_errors=0"
    );

    let d = dir.path();
    let kitti = read(d, "poses_kitti.txt");
    let lines: Vec<&str> = kitti.lines().collect();
    assert_eq!(lines.len(), 3, "{kitti}");
    for (line, k) in lines.iter().zip([0, 1, 3]) {
        let back: Vec<u64> = line
            .split(' ')
            .map(|v| v.parse::<f64>().unwrap().to_bits())
            .collect();
        let want: Vec<u64> = datagram(k).pose.iter().map(|v| v.to_bits()).collect();
        assert_eq!(back, want, "sweep {k}: {line}");
    }
    // `run`'s writer, byte for byte, for the pose that is an isometry.
    let run_line = kiss_odom_io::poses::format_kitti(&[rigid()]);
    assert_eq!(format!("{}\n", lines[0]), run_line);

    assert_eq!(
        read(d, "frames.csv"),
        "sweep,start_ns,points,status,iterations,sweep_lost,link,packets,lost,bad,foreign,\
         wrong_size,overflow,unsent,frame_errors\n\
         0,7,28000,ok,10,0,ok,0,0,0,0,0,0,0,0\n\
         1,1000000007,28001,ok,11,0,ok,100,0,0,0,0,0,0,0\n\
         3,3000000007,28003,degenerate|capacity,13,2,gap,300,2,0,0,0,0,0,0\n"
    );

    let s: serde_json::Value = serde_json::from_str(&read(d, "summary.json")).unwrap();
    assert_eq!(s["sweeps"], 3);
    assert_eq!(s["missing"], 1);
    assert_eq!(s["missing_sweeps"], serde_json::json!([2]));
    assert_eq!(s["duplicates"], 1);
    assert_eq!(s["out_of_order"], 2);
    assert_eq!(s["datagrams"], 5);
    assert_eq!(
        s["undecodable"],
        serde_json::json!({"length": 1, "magic": 0, "version": 0})
    );
    assert_eq!(s["counters"]["packets"], 300);
    assert_eq!(s["counters"]["lost"], 2);
    let from = tx.local_addr().unwrap().to_string();
    assert_eq!(
        s["senders"],
        serde_json::json!([{"address": from, "datagrams": 5}])
    );
    assert_eq!(s["interrupted"], false);
    assert_eq!(s["warnings"], 3, "one per kind of loss printed");
}

#[test]
fn without_a_sender_it_fails_after_the_idle_time_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let addr = free_address();
    let start = Instant::now();
    let out = finish(listen(&addr, dir.path(), &["--idle", "1"]));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("no datagram in 1 s"), "{stderr}");
    assert!(start.elapsed() >= Duration::from_secs(1));
    let s: serde_json::Value = serde_json::from_str(&read(dir.path(), "summary.json")).unwrap();
    assert_eq!(s["datagrams"], 0);
    assert!(!dir.path().join("poses_kitti.txt").exists());
}

#[test]
fn sigint_ends_it_with_the_sweeps_so_far_written() {
    let dir = tempfile::tempdir().unwrap();
    let addr = free_address();
    let child = listen(&addr, dir.path(), &["--idle", "3600", "--quiet"]);
    let tx = UdpSocket::bind("127.0.0.1:0").unwrap();
    let (zero, one) = (datagram(0).encode(), datagram(1).encode());
    send_in_order(&child, &tx, &addr, &[&zero[..], &one[..]]);
    // Both read from the socket (and so taken) before the signal.
    wait_read(&addr);
    signal(&child, "INT");
    let out = finish(child);
    assert_eq!(
        out.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(read(dir.path(), "poses_kitti.txt").lines().count(), 2);
    let s: serde_json::Value = serde_json::from_str(&read(dir.path(), "summary.json")).unwrap();
    assert_eq!(s["interrupted"], true);
    assert_eq!(s["sweeps"], 2);
}
