//! Memory of `kiss-odom run` on hostile sensor recordings follows the configuration, not the
//! file: 100,000 IP fragments that never complete, and a Velodyne sweep whose azimuth never
//! advances (millions of returns in one sweep), each stay under 64 MB of peak RSS, as the run
//! itself measures it (`summary.json`), in a process of its own.
#![cfg(target_os = "linux")]

use crate::capture_kit;

use kiss_odom_io::capture::reassembly::MAX_BYTES;

use capture_kit::{datagrams, ethernet, ethernet_frames, simulate, velodyne, Frame, PcapOut};
use std::path::Path;
use std::process::{Command, Stdio};

const LIMIT_BYTES: u64 = 64 << 20;
/// What waiting fragments may add to a run: four times the reassembly's own bound (4 MiB of
/// datagrams), for the table and the allocator's slack.
const FRAGMENTS_LIMIT_BYTES: u64 = 4 * MAX_BYTES as u64;

/// `kiss-odom run INPUT --out OUT --quiet EXTRA...` as a child: exit status, stderr and the
/// peak RSS in bytes the run itself measured (`summary.json`'s `peak_rss_bytes`, the
/// process's `VmHWM`, which its `exec` started afresh: none of this process's pages count).
fn run_measured(input: &Path, out: &Path, extra: &[&str]) -> (i32, String, u64) {
    let output = Command::new(env!("CARGO_BIN_EXE_kiss-odom-cli"))
        .arg("run")
        .arg(input)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .args(extra)
        .stdout(Stdio::null())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let peak = summary["peak_rss_bytes"].as_u64().expect("peak_rss_bytes");
    (output.status.code().unwrap_or(-1), stderr, peak)
}

fn mib(b: u64) -> f64 {
    b as f64 / f64::from(1 << 20)
}

#[test]
fn a_hundred_thousand_fragments_that_never_complete_stay_under_64_mb() {
    let dir = tempfile::tempdir().unwrap();
    let d = datagrams(&simulate(dir.path(), "vlp16", "vlp16", 3, 0).join("packets.pcap"));
    let path = dir.path().join("fragments.pcap");
    let mut w = PcapOut::create(&path, 1);
    // First fragments of 100,000 datagrams from as many senders, each 600 bytes, never
    // followed by the rest: 444 between two of the sensor's packets.
    let mut k = 0u32;
    for (i, sensor) in ethernet_frames(&d).iter().enumerate() {
        w.push(sensor);
        while k < 100_000 && (k as usize) < (i + 1) * 100_000 / d.len() {
            let src = [10, (k >> 16) as u8, (k >> 8) as u8, k as u8];
            let mut ip =
                etherparse::Ipv4Header::new(600, 64, etherparse::IpNumber::UDP, src, [10, 0, 0, 2])
                    .unwrap();
            ip.identification = k as u16;
            ip.more_fragments = true;
            ip.header_checksum = ip.calc_header_checksum();
            let mut packet = ip.to_bytes().to_vec();
            packet.extend_from_slice(&[0x13, 0x88, 0x27, 0x0f, 0x09, 0x00, 0, 0]);
            packet.resize(20 + 600, 0);
            w.push(&Frame::whole(sensor.time_ns, ethernet(&packet)));
            k += 1;
        }
    }
    drop(w);
    let (code, stderr, peak) = run_measured(&path, &dir.path().join("out"), &[]);
    // The same recording without the fragments: what the configuration costs.
    let clean = dir.path().join("vlp16/packets.pcap");
    let (_, _, clean_peak) = run_measured(&clean, &dir.path().join("clean"), &[]);
    let added = peak.saturating_sub(clean_peak);
    println!(
        "peak RSS {:.1} MiB (limit {:.0} MiB, optimised builds), {:.1} MiB above the run \
         without the fragments (limit {:.0} MiB)",
        mib(peak),
        mib(LIMIT_BYTES),
        mib(added),
        mib(FRAGMENTS_LIMIT_BYTES)
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("100000 fragmented IP datagram(s) dropped"),
        "{stderr}"
    );
    assert!(added < FRAGMENTS_LIMIT_BYTES, "{:.1} MiB", mib(added));
    // An unoptimised binary's own pages add about 12 MiB to every run.
    if !cfg!(debug_assertions) {
        assert!(peak < LIMIT_BYTES, "{:.1} MiB", mib(peak));
    }
}

#[test]
fn a_sweep_whose_azimuth_never_advances_stays_under_64_mb() {
    let dir = tempfile::tempdir().unwrap();
    let d = datagrams(&simulate(dir.path(), "vlp16", "vlp16", 1, 0).join("packets.pcap"));
    // 10,000 packets, 3.8 M returns, all at one azimuth, each 1 us after the last: no rule
    // of the sensor's timing or azimuth ends the sweep before the recording does.
    let t0 = velodyne::timestamp(&d[0].payload);
    let path = dir.path().join("stuck.pcap");
    let mut w = PcapOut::create(&path, 1);
    for k in 0..10_000u32 {
        let mut p = d[k as usize % d.len()].clone();
        for b in 0..12 {
            velodyne::set_azimuth(&mut p.payload, b, 9000);
        }
        velodyne::set_timestamp(&mut p.payload, t0 + k);
        p.time_ns = d[0].time_ns + u64::from(k) * 1000;
        for f in ethernet_frames(&[p]) {
            w.push(&f);
        }
    }
    drop(w);
    // SMALL's 1 MiB state, so that the limit measures the sweep buffer (the default state is
    // sized from the configuration, 40 MiB); its 131,072 points bound the sweep.
    let small = ["--set", "capacities=small"];
    let (code, stderr, peak) = run_measured(&path, &dir.path().join("out"), &small);
    println!(
        "peak RSS {:.1} MiB (limit {:.0} MiB)",
        mib(peak),
        mib(LIMIT_BYTES)
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("only the first"), "{stderr}");
    assert!(peak < LIMIT_BYTES, "{:.1} MiB", mib(peak));
}
