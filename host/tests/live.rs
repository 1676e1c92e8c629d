//! `kiss-odom live` fed by `kiss-odom replay`, two real processes over loopback UDP, against
//! `kiss-odom run` on the same recording (the OS-1-128 pcap in `../shared/data`): at the
//! recorded pace the poses are byte-equal; at 5x any loss is counted and the run goes on;
//! packets missing from the recording are counted per sweep; SIGINT ends `live` with its
//! outputs written; no packet at all is a clear error. The figures printed (time from a
//! sweep's last packet to its pose) are for BENCHMARKS.md, not checked.
#![cfg(target_os = "linux")]

use kiss_odom::io::pcap;
use std::net::UdpSocket;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/sensors/ouster")
}

fn recording() -> Option<(PathBuf, PathBuf)> {
    let d = data();
    let pcap = d.join("OS-1-128_v2.3.0_1024x10_lb_n3.pcap");
    if !pcap.is_file() {
        eprintln!("SKIP: ../shared/data/sensors is not beside the repository");
        return None;
    }
    Some((pcap, d.join("OS-1-128_v2.3.0_1024x10.json")))
}

/// One test's processes at a time: the byte-equality at 1x assumes the receiver is not
/// starved by the other tests' `live` processes.
fn serial() -> std::sync::MutexGuard<'static, ()> {
    static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    LOCK.lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_kiss-odom"))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A loopback address no one listens on now.
fn free_address() -> String {
    let probe = UdpSocket::bind("127.0.0.1:0").unwrap();
    probe.local_addr().unwrap().to_string()
}

/// `kiss-odom live` on `addr`, started and listening.
fn live(addr: &str, meta: &Path, out: &Path, extra: &[&str]) -> Child {
    let mut child = bin()
        .args([
            "live",
            "--udp",
            addr,
            "--meta",
            s(meta),
            "--out",
            s(out),
            "--quiet",
        ])
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    // Listening once the address cannot be taken (a hang guard, not a speed check).
    while UdpSocket::bind(addr).is_ok() {
        if let Some(status) = child.try_wait().unwrap() {
            panic!("live ended ({status}) before listening");
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "live never listened"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    child
}

fn replay(pcap: &Path, addr: &str, rate: &str) {
    let out = bin()
        .args(["replay", s(pcap), "--to", addr, "--rate", rate])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn run(pcap: &Path, meta: &Path, out: &Path) {
    let o = bin()
        .args([
            "run",
            s(pcap),
            "--meta",
            s(meta),
            "--out",
            s(out),
            "--quiet",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

fn finish(child: Child) -> Output {
    child.wait_with_output().unwrap()
}

fn read(dir: &Path, name: &str) -> String {
    std::fs::read_to_string(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&read(dir, "summary.json")).unwrap()
}

/// `run` on `pcap` into `dir/run`, then `live` into `dir/live` fed by `replay` at `rate`
/// and ended by a 2 s silence: the two folders and what `live` did.
fn run_and_live(pcap: &Path, meta: &Path, dir: &Path, rate: &str) -> (PathBuf, PathBuf, Output) {
    let (ran, lived) = (dir.join("run"), dir.join("live"));
    run(pcap, meta, &ran);
    let addr = free_address();
    let child = live(&addr, meta, &lived, &["--idle-timeout", "2"]);
    replay(pcap, &addr, rate);
    (ran, lived, finish(child))
}

fn latency(dir: &Path) -> String {
    let l = &summary(dir)["pose_latency_ms"];
    format!(
        "last packet to pose p50 {} ms, p99 {} ms, max {} ms",
        l["p50"], l["p99"], l["max"]
    )
}

#[test]
fn live_fed_by_replay_at_the_recorded_pace_gives_runs_poses_byte_for_byte() {
    let Some((pcap, meta)) = recording() else {
        return;
    };
    let _serial = serial();
    let dir = tempfile::tempdir().unwrap();
    let (ran, lived, o) = run_and_live(&pcap, &meta, dir.path(), "1");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        summary(&lived)["packets"]["lost"],
        0,
        "no loss at 1x on loopback"
    );
    for name in ["poses_kitti.txt", "poses_tum.txt"] {
        assert_eq!(read(&lived, name), read(&ran, name), "{name}");
    }
    // One TUM line on stdout per pose, as the sweeps completed.
    let stdout = String::from_utf8(o.stdout).unwrap();
    let want = read(&ran, "poses_tum.txt");
    let tum: Vec<&str> = want.lines().skip(1).collect();
    let printed: Vec<&str> = stdout.lines().take(tum.len()).collect();
    assert_eq!(printed, tum);
    println!("1x: {}", latency(&lived));
}

#[test]
fn at_five_times_the_pace_any_loss_is_counted_and_the_run_goes_on() {
    let Some((pcap, meta)) = recording() else {
        return;
    };
    let _serial = serial();
    let dir = tempfile::tempdir().unwrap();
    let (ran, lived, o) = run_and_live(&pcap, &meta, dir.path(), "5");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let lost = summary(&lived)["packets"]["lost"].as_u64().unwrap();
    let dropped = stderr.contains("dropped");
    if lost == 0 && !dropped {
        assert_eq!(
            read(&lived, "poses_kitti.txt"),
            read(&ran, "poses_kitti.txt")
        );
        println!(
            "5x: no packet lost; poses byte-equal to run; {}",
            latency(&lived)
        );
    } else {
        println!("5x: {lost} packet(s) lost, counted; {}", latency(&lived));
    }
}

#[test]
fn packets_missing_from_the_stream_are_counted_in_their_sweep() {
    let Some((pcap, meta)) = recording() else {
        return;
    };
    let _serial = serial();
    let dir = tempfile::tempdir().unwrap();
    // Five lidar packets of the second sweep (64 a sweep) left out.
    let mut datagrams: Vec<_> = pcap::open(&pcap).unwrap().map(Result::unwrap).collect();
    let lidar: Vec<usize> = (0..datagrams.len())
        .filter(|&i| datagrams[i].port == 7502)
        .collect();
    for &i in lidar[64 + 20..64 + 25].iter().rev() {
        datagrams.remove(i);
    }
    let holed = dir.path().join("holed.pcap");
    pcap::write(&holed, &datagrams, 9000).unwrap();
    let (ran, lived, o) = run_and_live(&holed, &meta, dir.path(), "1");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let lost = summary(&lived)["packets"]["lost"].as_u64().unwrap();
    assert!(lost >= 5, "{lost} lost");
    assert_eq!(
        read(&lived, "frames.csv").lines().count(),
        4,
        "three sweeps and a header"
    );
    assert_eq!(
        read(&lived, "poses_kitti.txt"),
        read(&ran, "poses_kitti.txt")
    );
}

#[test]
fn sigint_ends_live_with_its_outputs_written() {
    let Some((pcap, meta)) = recording() else {
        return;
    };
    let _serial = serial();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("live");
    let addr = free_address();
    let child = live(&addr, &meta, &out, &[]);
    replay(&pcap, &addr, "1");
    std::thread::sleep(Duration::from_millis(500));
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let o = finish(child);
    assert_eq!(
        o.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let s = summary(&out);
    assert_eq!(s["interrupted"], true);
    assert_eq!(s["frames"], 3, "{s:#}");
    assert_eq!(read(&out, "poses_kitti.txt").lines().count(), 3);
}

#[test]
fn no_packets_on_the_port_is_an_error_naming_the_address() {
    let Some((_, meta)) = recording() else { return };
    let _serial = serial();
    let dir = tempfile::tempdir().unwrap();
    let addr = free_address();
    let out = dir.path().join("live");
    let child = live(&addr, &meta, &out, &["--idle-timeout", "0.5"]);
    let o = finish(child);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains(&format!("udp://{addr}")) && stderr.contains("no packets"),
        "{stderr}"
    );
}
