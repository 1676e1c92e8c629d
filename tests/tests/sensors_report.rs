//! What the decoders report about a recording, on recordings built from simulated ones: what
//! comes after the last sweep (refused packets, a second sender, another sensor) reaches the
//! warnings and `summary.json` for `run` and `live`; the default Velodyne port is 2368;
//! Ouster metadata that contradicts itself or the packets is refused naming the field; the
//! shared VLP-16 recording whose product byte says HDL-32E is decoded without invented
//! losses and `--sensor vlp16` overrides the byte; a Velodyne clock jump, an Ouster frame id
//! far ahead and an Ouster restart resynchronise the decoder with a warning.

use crate::capture_kit;
use crate::common;

use capture_kit::{datagrams, ethernet_frames, ouster, simulate, velodyne, write_pcap};
use common::run;
use kiss_odom_io::capture::pcap::Datagram;
use kiss_odom_tests::{have_sensor_file, sensor_data};
use std::net::UdpSocket;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `d` as an Ethernet pcap `dir/name`.
fn capture(dir: &Path, name: &str, d: &[Datagram]) -> PathBuf {
    let path = dir.join(name);
    write_pcap(&path, 1, &ethernet_frames(d));
    path
}

/// A VLP-16 recording of `frames` sweeps cut right after the last packet that ends a sweep
/// at azimuth 0 (`--cut-angle 0`), so that nothing of a sweep follows.
fn vlp16_ending_a_sweep(dir: &Path, frames: usize) -> Vec<Datagram> {
    let mut d = datagrams(&simulate(dir, "vlp16", "vlp16", frames, 0).join("packets.pcap"));
    let last = d.iter().rposition(|p| velodyne::wraps(&p.payload)).unwrap();
    d.truncate(last + 1);
    d
}

/// After `d`, 1 ms apart: `n` of the sensor's last data packets again, edited by `edit`, from
/// its address or `from`.
fn after(d: &mut Vec<Datagram>, n: usize, from: Option<&str>, edit: impl Fn(&mut Vec<u8>)) {
    let sensor = d[0].source;
    let template: Vec<Datagram> = d
        .iter()
        .rev()
        .filter(|p| p.source == sensor && p.payload.len() == 1206)
        .take(50)
        .cloned()
        .collect();
    let last = d.last().unwrap().time_ns;
    for k in 0..n {
        let mut p = template[k % template.len()].clone();
        p.time_ns = last + (k as u64 + 1) * 1_000_000;
        if let Some(a) = from {
            p.source = a.parse().unwrap();
        }
        edit(&mut p.payload);
        d.push(p);
    }
}

#[test]
fn what_comes_after_the_last_sweep_is_warned_and_in_the_totals() {
    let dir = tempfile::tempdir().unwrap();
    let mut d = vlp16_ending_a_sweep(dir.path(), 3);
    after(&mut d, 20, Some("192.168.1.202:2368"), |_| {});
    after(&mut d, 10, None, |p| p.truncate(700));
    // A VLP-32C's product byte: another sensor on the port.
    after(&mut d, 10, None, |p| p[1205] = 0x28);
    let path = capture(dir.path(), "tail.pcap", &d);
    let r = run(
        &path,
        &dir.path().join("out"),
        &["--set", "input.cut_angle=0"],
    );
    r.ok();
    r.warning_with(&["tail.pcap", "other sender", "192.168.1.202:2368 (20)"]);
    r.warning_with(&["tail.pcap", "10 packet(s) refused", "truncated"]);
    r.warning_with(&["tail.pcap", "10 packet(s) refused", "another sensor"]);
    assert_eq!(r.number("packets.other_sensor"), 30.0, "{}", r.stderr);
    assert_eq!(r.number("packets.bad"), 10.0, "{}", r.stderr);
}

/// A loopback address no one listens on now.
fn free_address() -> String {
    let probe = UdpSocket::bind("127.0.0.1:0").unwrap();
    probe.local_addr().unwrap().to_string()
}

#[test]
fn live_warns_of_a_second_sender_after_the_last_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let d = vlp16_ending_a_sweep(dir.path(), 3);
    let addr = free_address();
    let out = dir.path().join("live");
    let mut child = Command::new(env!("CARGO_BIN_EXE_kiss-odom-cli"))
        .args(["live", "--udp", &addr, "--idle-timeout", "1.5"])
        .args(["--set", "input.cut_angle=0", "--quiet", "--out", s(&out)])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    common::wait_listening(&mut child, &addr, "live");
    let sensor = UdpSocket::bind("127.0.0.1:0").unwrap();
    let second = UdpSocket::bind("127.0.0.1:0").unwrap();
    // Paced at 2 kHz on purpose, as a sensor sends: a burst of the whole recording could
    // overflow the receive buffer. The pauses wait for nothing.
    for p in &d {
        sensor.send_to(&p.payload, &addr).unwrap();
        std::thread::sleep(Duration::from_micros(500));
    }
    for p in d.iter().rev().take(20) {
        second.send_to(&p.payload, &addr).unwrap();
        std::thread::sleep(Duration::from_micros(500));
    }
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    // However many of the second sender's packets the machine received, they are reported.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let n = summary["packets"]["other_sensor"].as_u64().unwrap();
    let sender = second.local_addr().unwrap();
    assert!(
        n > 0 && stderr.contains(&format!("{sender} ({n})")),
        "{n} from the second sender in summary.json; stderr:\n{stderr}"
    );
}

#[test]
fn the_default_velodyne_port_is_2368_and_packets_elsewhere_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let a = datagrams(&simulate(dir.path(), "a", "vlp16", 3, 0).join("packets.pcap"));
    // A second VLP-16 elsewhere in the scene, sending to port 2000.
    let b: Vec<Datagram> =
        datagrams(&simulate(dir.path(), "b", "vlp16", 3, 1).join("packets.pcap"))
            .into_iter()
            .map(|mut p| {
                p.port = 2000;
                p.source = "192.168.1.202:2368".parse().unwrap();
                p.time_ns += 300_000;
                p
            })
            .collect();
    let mut both = [a.clone(), b.clone()].concat();
    both.sort_by_key(|p| p.time_ns);
    let alone = run(
        &capture(dir.path(), "a.pcap", &a),
        &dir.path().join("a"),
        &[],
    );
    alone.ok();
    let r = run(
        &capture(dir.path(), "both.pcap", &both),
        &dir.path().join("both"),
        &[],
    );
    r.ok();
    assert_eq!(
        r.lines("poses_kitti.txt"),
        alone.lines("poses_kitti.txt"),
        "the sensor on 2368 is the one decoded"
    );
    r.warning_with(&["both.pcap", "port 2000", "--set input.port=2000"]);
    // Nothing on 2368: an error naming where the packets are.
    let r = run(
        &capture(dir.path(), "b.pcap", &b),
        &dir.path().join("b"),
        &[],
    );
    r.failed_with(&["b.pcap", "port 2368", "port 2000", "--set input.port=2000"]);
}

#[test]
fn ouster_metadata_contradicting_itself_or_the_packets_is_refused_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulate(dir.path(), "os1", "os1-64", 2, 0);
    let pcap = sim.join("packets.pcap");
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(sim.join("packets.json")).unwrap()).unwrap();
    let good = run(
        &pcap,
        &dir.path().join("good"),
        &["--calibration", s(&sim.join("packets.json"))],
    );
    good.ok();
    type Edit = fn(&mut serde_json::Value);
    let cases: [(&str, &str, Edit); 9] = [
        ("columns", "columns_per_frame", |m| {
            m["data_format"]["columns_per_frame"] = 2048.into();
            m["data_format"]["column_window"] = serde_json::json!([0, 2047]);
        }),
        ("mode", "columns_per_frame", |m| {
            m["data_format"]["columns_per_frame"] = 2048.into();
            m["data_format"]["column_window"] = serde_json::json!([0, 2047]);
            m["lidar_mode"] = "2048x10".into();
        }),
        ("scaled", "lidar_to_sensor_transform", |m| {
            for k in [0, 5, 10] {
                let v = m["lidar_to_sensor_transform"][k].as_f64().unwrap();
                m["lidar_to_sensor_transform"][k] = (v * 1.5).into();
            }
        }),
        ("last-row", "lidar_to_sensor_transform", |m| {
            m["lidar_to_sensor_transform"][14] = 1.0.into();
        }),
        ("altitude", "beam_altitude_angles", |m| {
            m["beam_altitude_angles"][3] = 200.0.into();
        }),
        ("azimuth", "beam_azimuth_angles", |m| {
            m["beam_azimuth_angles"][3] = (-400.0).into();
        }),
        ("origin", "lidar_origin_to_beam_origin_mm", |m| {
            m["lidar_origin_to_beam_origin_mm"] = 5000.0.into();
        }),
        ("inverted", "column_window", |m| {
            m["data_format"]["column_window"] = serde_json::json!([1023, 0]);
        }),
        ("tiny", "column_window", |m| {
            m["data_format"]["column_window"] = serde_json::json!([0, 20]);
        }),
    ];
    for (name, field, edit) in cases {
        let mut m = meta.clone();
        edit(&mut m);
        let path = dir.path().join(format!("{name}.json"));
        std::fs::write(&path, serde_json::to_string_pretty(&m).unwrap()).unwrap();
        let r = run(&pcap, &dir.path().join(name), &["--calibration", s(&path)]);
        r.failed_with(&[&format!("{name}.json"), field]);
    }
}

fn vlp16_file() -> Option<PathBuf> {
    have_sensor_file("velodyne/velodyne_vlp16.pcap")
        .then(|| sensor_data().join("velodyne/velodyne_vlp16.pcap"))
}

#[test]
fn a_product_byte_the_packet_timing_contradicts_is_warned_and_invents_no_loss() {
    let Some(file) = vlp16_file() else { return };
    let dir = tempfile::tempdir().unwrap();
    // Its packets say HDL-32E (0x21), but come 1327 us apart as a VLP-16's do, where an
    // HDL-32E sends one every 553 us: none is lost.
    let r = run(&file, &dir.path().join("byte"), &[]);
    r.ok();
    r.warning_with(&["velodyne_vlp16.pcap", "HDL-32E", "1327 us", "--sensor"]);
    assert_eq!(r.number("packets.lost"), 0.0, "{}", r.stderr);
    assert_eq!(r.number("packets.decoded"), 84.0, "{}", r.stderr);
    // What the packets' timing says it is, overriding the byte.
    let r = run(&file, &dir.path().join("vlp16"), &["--sensor", "vlp16"]);
    r.ok();
    assert!(!r.stderr.contains("HDL-32E"), "{}", r.stderr);
    assert_eq!(r.number("packets.lost"), 0.0, "{}", r.stderr);
    assert_eq!(r.number("packets.decoded"), 84.0, "{}", r.stderr);
}

/// Registered frames of a run.
fn registered(r: &common::Run) -> usize {
    r.column("outcome")
        .iter()
        .filter(|o| *o == "registered")
        .count()
}

#[test]
fn a_velodyne_clock_jump_of_more_than_half_an_hour_resynchronises_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let mut d = datagrams(&simulate(dir.path(), "vlp16", "vlp16", 6, 0).join("packets.pcap"));
    let base = run(
        &capture(dir.path(), "base.pcap", &d),
        &dir.path().join("base"),
        &["--set", "input.cut_angle=0"],
    );
    base.ok();
    const HOUR_US: u32 = 3_600_000_000;
    for p in d.iter_mut().skip(200) {
        let t = velodyne::timestamp(&p.payload);
        velodyne::set_timestamp(&mut p.payload, (t + 40 * 60_000_000) % HOUR_US);
    }
    let r = run(
        &capture(dir.path(), "jump.pcap", &d),
        &dir.path().join("jump"),
        &["--set", "input.cut_angle=0"],
    );
    r.ok();
    r.warning_with(&["jump.pcap", "resynchronised"]);
    assert!(
        registered(&r) + 1 >= registered(&base),
        "{} of {} frames registered; stderr:\n{}",
        registered(&r),
        registered(&base),
        r.stderr
    );
    assert!(r.number("packets.decoded") >= 450.0 - 32.0, "{}", r.stderr);
}

#[test]
fn an_ouster_frame_id_far_ahead_or_a_restart_resynchronises_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulate(dir.path(), "os1", "os1-64", 6, 0);
    let meta = sim.join("packets.json");
    let d = datagrams(&sim.join("packets.pcap"));
    let base = run(
        &sim.join("packets.pcap"),
        &dir.path().join("base"),
        &["--calibration", s(&meta)],
    );
    base.ok();
    // One packet of the second sweep says frame id + 1000; or the sensor restarts after the
    // third sweep and counts frames from its first one again.
    let first = ouster::frame_id(&d[0].payload);
    let ahead = |d: &mut Vec<Datagram>| {
        let f = ouster::frame_id(&d[100].payload);
        ouster::set_frame_id(&mut d[100].payload, f.wrapping_add(1000));
    };
    let restart = |d: &mut Vec<Datagram>| {
        for p in d.iter_mut().skip(3 * 64) {
            let f = ouster::frame_id(&p.payload);
            ouster::set_frame_id(&mut p.payload, first + (f - first - 3));
        }
    };
    for (name, edit, lost_frames) in [
        ("ahead", &ahead as &dyn Fn(&mut Vec<Datagram>), 1),
        ("restart", &restart, 1),
    ] {
        let mut d = d.clone();
        edit(&mut d);
        let path = capture(dir.path(), &format!("{name}.pcap"), &d);
        let r = run(&path, &dir.path().join(name), &["--calibration", s(&meta)]);
        r.ok();
        r.warning_with(&[&format!("{name}.pcap"), "resynchronised"]);
        assert!(
            registered(&r) + lost_frames >= registered(&base),
            "{name}: {} of {} frames registered; stderr:\n{}",
            registered(&r),
            registered(&base),
            r.stderr
        );
        assert!(
            r.number("packets.decoded") >= 384.0 - 32.0,
            "{name}: {}",
            r.stderr
        );
    }
}
