//! What a capture file can hold around the sensor's packets, read as the packets say and never
//! silently: link layers (SLL2 as `tcpdump -i any` writes it, raw IP), a link type not read,
//! a snap length shorter than the packets, a UDP length field longer than its datagram,
//! pcapng interfaces with their own timestamp resolution, and IP fragments that are lost or
//! whose IP ID is reused. Every capture is built here from a simulated recording.

use crate::capture_kit;
use crate::common;

use capture_kit::{datagrams, ethernet, ethernet_frames, ipv4, simulate, write_pcap, Frame};
use common::run;
use kiss_odom_io::capture::pcap::Datagram;
use kiss_odom_io::capture::sweeps::{self, Sweep};
use kiss_odom_io::SensorOptions;
use std::path::{Path, PathBuf};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A 3-sweep VLP-16 recording's datagrams (port 2368, 75 packets a sweep).
fn vlp16(dir: &Path) -> Vec<Datagram> {
    datagrams(&simulate(dir, "vlp16", "vlp16", 3, 0).join("packets.pcap"))
}

/// `frames` as a pcap of link type `link` in `dir/name`.
fn capture(dir: &Path, name: &str, link: u32, frames: &[Frame]) -> PathBuf {
    let path = dir.join(name);
    write_pcap(&path, link, frames);
    path
}

#[test]
fn sll2_and_raw_ip_captures_read_like_ethernet() {
    let dir = tempfile::tempdir().unwrap();
    let d = vlp16(dir.path());
    let reference = capture(dir.path(), "eth.pcap", 1, &ethernet_frames(&d));
    let expected = run(&reference, &dir.path().join("eth"), &[]);
    expected.ok();
    let sll2 = |ip: &[u8]| {
        // Protocol, reserved, interface index, ARPHRD_ETHER, packet type, address length,
        // address: the 20 bytes of a Linux cooked v2 header.
        let mut f = vec![0x08, 0x00, 0, 0, 0, 0, 0, 2, 0, 1, 0, 6];
        f.extend_from_slice(&[2, 0, 0, 0, 0, 1, 0, 0]);
        f.extend_from_slice(ip);
        f
    };
    let raw = |ip: &[u8]| ip.to_vec();
    type Wrap<'a> = &'a dyn Fn(&[u8]) -> Vec<u8>;
    let links: [(u32, Wrap); 4] = [(276, &sll2), (12, &raw), (101, &raw), (228, &raw)];
    for (link, wrap) in links {
        let frames: Vec<Frame> = d
            .iter()
            .enumerate()
            .map(|(k, d)| Frame::whole(d.time_ns, wrap(&ipv4(d, k as u16, 65_000)[0])))
            .collect();
        let path = capture(dir.path(), &format!("link{link}.pcap"), link, &frames);
        let r = run(&path, &dir.path().join(format!("out{link}")), &[]);
        r.ok();
        assert_eq!(
            r.lines("poses_kitti.txt"),
            expected.lines("poses_kitti.txt"),
            "link type {link}"
        );
    }
}

#[test]
fn a_link_type_not_read_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = vlp16(dir.path());
    // IEEE 802.11 (105): not a link layer read here.
    let path = capture(dir.path(), "wifi.pcap", 105, &ethernet_frames(&d));
    let r = run(&path, &dir.path().join("out"), &[]);
    let e = r.failed_with(&["wifi.pcap", "link type"]);
    assert!(e.contains("IEEE802_11 (105)"), "{e}");
}

#[test]
fn a_snap_length_shorter_than_the_packets_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let d = vlp16(dir.path());
    let cut = |every: usize| -> Vec<Frame> {
        ethernet_frames(&d)
            .into_iter()
            .enumerate()
            .map(|(k, mut f)| {
                if k % every == 0 {
                    f.data.truncate(96);
                }
                f
            })
            .collect()
    };
    // Every frame cut: nothing decodes, and the error says why.
    let all = capture(dir.path(), "snap96.pcap", 1, &cut(1));
    let r = run(&all, &dir.path().join("all"), &[]);
    r.failed_with(&["snap96.pcap", "snap length"]);
    // One frame in ten: a warning naming the snap length, the packets counted as bad.
    let some = capture(dir.path(), "some.pcap", 1, &cut(10));
    let r = run(&some, &dir.path().join("some"), &[]);
    r.ok();
    r.warning_with(&["some.pcap", "snap length", "23 packet(s)"]);
    assert_eq!(r.number("packets.bad"), 23.0, "{}", r.stderr);
}

#[test]
fn a_udp_length_field_longer_than_the_datagram_is_named_and_counted() {
    let dir = tempfile::tempdir().unwrap();
    let d = vlp16(dir.path());
    let mut frames = ethernet_frames(&d);
    for f in frames.iter_mut().skip(30).step_by(40).take(5) {
        // Ethernet 14 + IPv4 20 bytes, then the UDP length field at 4..6.
        let at = 14 + 20 + 4;
        let len = u16::from_be_bytes([f.data[at], f.data[at + 1]]) + 100;
        f.data[at..at + 2].copy_from_slice(&len.to_be_bytes());
    }
    let path = capture(dir.path(), "udplen.pcap", 1, &frames);
    let r = run(&path, &dir.path().join("out"), &[]);
    r.ok();
    r.warning_with(&["udplen.pcap", "5 packet(s)", "UDP length field"]);
    assert_eq!(r.number("packets.bad"), 5.0, "{}", r.stderr);
}

/// The times of `times.txt` that `convert` writes for a recording.
fn converted_times(dir: &Path, input: &Path) -> Vec<f64> {
    let out = dir.join(format!(
        "conv-{}",
        input.file_name().unwrap().to_str().unwrap()
    ));
    let (code, stderr) = common::kiss_odom(
        ["convert", s(input), "--out", s(&out), "--quiet"]
            .map(Into::into)
            .to_vec(),
    );
    assert_eq!(code, 0, "{stderr}");
    std::fs::read_to_string(out.join("times.txt"))
        .unwrap()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect()
}

#[test]
fn pcapng_times_follow_each_interfaces_resolution_and_offset() {
    use pcap_file::pcapng::blocks::enhanced_packet::EnhancedPacketBlock;
    use pcap_file::pcapng::blocks::interface_description::{
        InterfaceDescriptionBlock, InterfaceDescriptionOption as Opt,
    };
    use pcap_file::pcapng::PcapNgWriter;
    use pcap_file::DataLink;
    let dir = tempfile::tempdir().unwrap();
    let mut d = vlp16(dir.path());
    // Times of a real clock (2023), where 1000x errors cannot hide near zero.
    for p in &mut d {
        p.time_ns += 1_700_000_000_000_000_000;
    }
    let pcap = capture(dir.path(), "us.pcap", 1, &ethernet_frames(&d));
    // Interface 0: the default resolution (microseconds); 1: nanoseconds and an offset of
    // 100 s; 2: 2^-30 s.
    type Raw = fn(u64) -> u64;
    let interfaces: [(Vec<Opt<'static>>, Raw); 3] = [
        (vec![], |ns| ns / 1000),
        (vec![Opt::IfTsResol(9), Opt::IfTsOffset(100)], |ns| {
            ns - 100_000_000_000
        }),
        (vec![Opt::IfTsResol(0x80 | 30)], |ns| {
            ((u128::from(ns) << 30) / 1_000_000_000) as u64 + 1
        }),
    ];
    let path = dir.path().join("three.pcapng");
    let mut w = PcapNgWriter::new(std::fs::File::create(&path).unwrap()).unwrap();
    for (options, _) in &interfaces {
        w.write_pcapng_block(InterfaceDescriptionBlock {
            linktype: DataLink::ETHERNET,
            snaplen: 65535,
            options: options.clone(),
        })
        .unwrap();
    }
    for (k, f) in ethernet_frames(&d).into_iter().enumerate() {
        let i = k % 3;
        w.write_pcapng_block(EnhancedPacketBlock {
            interface_id: i as u32,
            timestamp: std::time::Duration::from_nanos(interfaces[i].1(f.time_ns)),
            original_len: f.data.len() as u32,
            data: f.data.into(),
            options: vec![],
        })
        .unwrap();
    }
    drop(w);
    let want = converted_times(dir.path(), &pcap);
    let got = converted_times(dir.path(), &path);
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(&want) {
        assert!((g - w).abs() < 2e-6, "pcapng {g} s, pcap {w} s");
    }
}

/// Ethernet frames of an OS1-64 recording's datagrams as 1500-byte IPv4 fragments, datagram
/// `k` with IP ID `ids(k)` and `keep(k, fragment)` deciding which fragments are written.
fn fragmented(
    d: &[Datagram],
    ids: impl Fn(usize) -> u16,
    keep: impl Fn(usize, usize, usize) -> bool,
) -> Vec<Frame> {
    let mut frames = Vec::new();
    for (k, d) in d.iter().enumerate() {
        let pieces = ipv4(d, ids(k), 1500);
        let n = pieces.len();
        for (i, ip) in pieces.into_iter().enumerate() {
            if keep(k, i, n) {
                frames.push(Frame::whole(d.time_ns, ethernet(&ip)));
            }
        }
    }
    frames
}

fn os1_64(dir: &Path) -> (Vec<Datagram>, SensorOptions) {
    let sim = simulate(dir, "os1", "os1-64", 3, 0);
    let opts = SensorOptions {
        meta: Some(sim.join("packets.json")),
        ..SensorOptions::default()
    };
    (datagrams(&sim.join("packets.pcap")), opts)
}

fn sweeps(path: &Path, opts: &SensorOptions) -> Vec<Sweep> {
    sweeps::read_all(path, opts).unwrap().0
}

#[test]
fn a_reused_ip_id_never_completes_another_datagram() {
    let dir = tempfile::tempdir().unwrap();
    let (d, opts) = os1_64(dir.path());
    let all = |_: usize, _: usize, _: usize| true;
    // Datagram 70 loses a fragment, then 71 comes with the same IP ID: 70 is lost, 71 whole.
    // If it lost its first fragment instead, 71's first one would complete it: the UDP
    // checksum refuses that, and both are lost.
    type Lost = fn(usize, usize) -> bool;
    for (name, lost, expected_lost, warning) in [
        (
            "middle",
            (|i, n| i == n / 2) as Lost,
            vec![70],
            "superseded by another datagram with the same IP ID",
        ),
        (
            "first",
            |i, _| i == 0,
            vec![70, 71],
            "failed their checksum",
        ),
    ] {
        let ids = |k: usize| if k == 71 { 70 } else { k as u16 };
        let reused = fragmented(&d, ids, |k, i, n| !(k == 70 && lost(i, n)));
        let path = capture(dir.path(), &format!("reused-{name}.pcap"), 1, &reused);
        let without: Vec<Datagram> = d
            .iter()
            .enumerate()
            .filter(|(k, _)| !expected_lost.contains(k))
            .map(|(_, d)| d.clone())
            .collect();
        let expected = capture(
            dir.path(),
            &format!("without-{name}.pcap"),
            1,
            &fragmented(&without, |k| k as u16, all),
        );
        let (got, want) = (sweeps(&path, &opts), sweeps(&expected, &opts));
        assert_eq!(got.len(), want.len(), "{name}");
        for (k, (g, w)) in got.iter().zip(&want).enumerate() {
            assert_eq!(g.points.len(), w.points.len(), "{name}: sweep {k} points");
            assert!(g.points == w.points, "{name}: sweep {k} points differ");
            assert_eq!(g.stats.packets, w.stats.packets, "{name}: sweep {k}");
        }
        let r = run(
            &path,
            &dir.path().join(name),
            &["--calibration", s(opts.meta.as_ref().unwrap())],
        );
        r.ok();
        r.warning_with(&[&format!("reused-{name}.pcap"), warning]);
    }
}

#[test]
fn fragments_that_never_complete_are_counted_and_warned() {
    let dir = tempfile::tempdir().unwrap();
    let (d, opts) = os1_64(dir.path());
    // Every tenth datagram loses its last fragment: 20 of 192.
    let frames = fragmented(&d, |k| k as u16, |k, i, n| !(k % 10 == 0 && i + 1 == n));
    let path = capture(dir.path(), "lossy.pcap", 1, &frames);
    let r = run(
        &path,
        &dir.path().join("out"),
        &["--calibration", s(opts.meta.as_ref().unwrap())],
    );
    r.ok();
    r.warning_with(&["lossy.pcap", "20 fragmented IP datagram(s) dropped"]);
}
