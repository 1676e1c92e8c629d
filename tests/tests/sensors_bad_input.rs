//! Damaged sensor recordings: every kind of damage gives an error naming the file and the
//! reason, or a counted skip reported per sweep and in the capture report, never a panic.

use kiss_odom_io::capture::pcap::{self, Datagram};
use kiss_odom_io::capture::sweeps;
use kiss_odom_io::SensorOptions;
use std::path::{Path, PathBuf};

use kiss_odom_tests::{add_second_vlp16, have_sensor_file, sensor_data as data};

fn have_data() -> bool {
    have_sensor_file("velodyne/velodyne_vlp16.pcap")
}

fn datagrams(path: &Path) -> Vec<Datagram> {
    pcap::open(path).unwrap().map(|d| d.unwrap()).collect()
}

/// The VLP recording with `edit` applied to its datagrams, written to `dir/name`.
fn edited(dir: &Path, name: &str, edit: impl FnOnce(&mut Vec<Datagram>)) -> PathBuf {
    let mut d = datagrams(&data().join("velodyne/velodyne_vlp16.pcap"));
    edit(&mut d);
    let path = dir.join(name);
    pcap::write(&path, &d, 9000).unwrap();
    path
}

fn is_data(d: &Datagram) -> bool {
    d.port == 2368 && d.payload.len() == 1206
}

fn err(path: &Path, opts: &SensorOptions) -> String {
    let e = sweeps::read_all(path, opts).unwrap_err();
    format!("{e:#}")
}

#[test]
fn a_truncated_or_corrupted_packet_is_a_counted_skip() {
    if !have_data() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let path = edited(dir.path(), "damaged.pcap", |d| {
        let mut data = d.iter_mut().filter(|d| is_data(d));
        data.nth(5).unwrap().payload.truncate(700);
        // Block 4's azimuth at 655.35 degrees.
        data.nth(10).unwrap().payload[402..404].copy_from_slice(&[0xFF, 0xFF]);
    });
    let (sweeps, report) = sweeps::read_all(&path, &SensorOptions::default()).unwrap();
    let (clean, _) = sweeps::read_all(
        &data().join("velodyne/velodyne_vlp16.pcap"),
        &SensorOptions::default(),
    )
    .unwrap();
    let bad: u32 = sweeps.iter().map(|s| s.stats.bad_packets).sum();
    assert_eq!(bad, 2);
    assert_eq!(
        report.decoded + 2,
        clean
            .iter()
            .map(|s| u64::from(s.stats.packets))
            .sum::<u64>()
    );
    let w = report.warnings().join("\n");
    println!("{w}");
    assert!(
        w.contains("truncated") && w.contains("azimuth of 360 degrees"),
        "{w}"
    );
}

#[test]
fn packets_of_the_wrong_length_or_unknown_model_name_the_file_and_reason() {
    if !have_data() {
        return;
    }
    let one = data().join("velodyne/VLI-16-one-packet.pcap");
    let e = err(&one, &SensorOptions::default());
    println!("{e}");
    assert!(
        e.contains("VLI-16-one-packet.pcap") && e.contains("1 x 1212 bytes on port 2368"),
        "{e}"
    );
    // With the port given, the same packet is refused for its length.
    let opts = SensorOptions {
        port: Some(2368),
        ..SensorOptions::default()
    };
    let e = err(&one, &opts);
    assert!(
        e.contains("VLI-16-one-packet.pcap") && e.contains("none decoded: packet longer"),
        "{e}"
    );

    let dir = tempfile::tempdir().unwrap();
    let path = edited(dir.path(), "unknown.pcap", |d| {
        for p in d.iter_mut().filter(|d| is_data(d)) {
            p.payload[1205] = 0x99;
        }
    });
    let e = err(&path, &SensorOptions::default());
    println!("{e}");
    assert!(
        e.contains("unknown.pcap") && e.contains("unknown model (Velodyne product byte"),
        "{e}"
    );
}

#[test]
fn metadata_of_another_sensor_names_both_files() {
    if !have_data() {
        return;
    }
    let o = data().join("ouster");
    // Same packet size (8448 bytes), another sensor: the packets' serial says so.
    let opts = SensorOptions {
        meta: Some(o.join("OS-1-128_v2.3.0_1024x10.json")),
        ..SensorOptions::default()
    };
    let e = err(&o.join("OS-0-32-U1_v2.2.0_1024x10.pcap"), &opts);
    println!("{e}");
    assert!(
        e.contains("OS-0-32-U1_v2.2.0_1024x10.pcap")
            && e.contains("serial differs from the metadata")
            && e.contains("OS-1-128_v2.3.0_1024x10.json"),
        "{e}"
    );
    // A legacy sensor's packets with a dual-profile sensor's metadata: the length says so.
    let opts = SensorOptions {
        meta: Some(o.join("OS-0-32-U1_v2.2.0_1024x10.json")),
        ..SensorOptions::default()
    };
    let e = err(&o.join("OS-1-32-G_v2.1.1_1024x10.pcap"), &opts);
    println!("{e}");
    assert!(
        e.contains("OS-1-32-G_v2.1.1_1024x10.pcap") && e.contains("shorter"),
        "{e}"
    );
    // No metadata at all for an Ouster recording.
    let e = err(
        &o.join("OS-1-32-G_v2.1.1_1024x10.pcap"),
        &SensorOptions::default(),
    );
    assert!(
        e.contains("look like an Ouster") && e.contains("--calibration"),
        "{e}"
    );
}

#[test]
fn a_capture_cut_in_the_middle_gives_the_sweeps_before_then_an_error() {
    if !have_data() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let src = data().join("velodyne/velodyne_vlp16.pcap");
    let bytes = std::fs::read(&src).unwrap();
    let path = dir.path().join("cut.pcap");
    std::fs::write(&path, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let mut it = sweeps::open(&path, &SensorOptions::default()).unwrap();
    let first = it.next().unwrap();
    let e = match first {
        Ok(_) => format!("{:#}", it.next().unwrap().unwrap_err()),
        Err(e) => format!("{e:#}"),
    };
    println!("{e}");
    assert!(
        e.contains("cut.pcap") && e.contains("cut in the middle"),
        "{e}"
    );
    assert!(it.next().is_none());
}

#[test]
fn no_packets_on_the_port_names_the_ports_seen() {
    if !have_data() {
        return;
    }
    let opts = SensorOptions {
        port: Some(9999),
        ..SensorOptions::default()
    };
    let e = err(&data().join("velodyne/velodyne_vlp16.pcap"), &opts);
    println!("{e}");
    assert!(
        e.contains("velodyne_vlp16.pcap")
            && e.contains("no packets on port 9999")
            && e.contains("on port 2368"),
        "{e}"
    );
    let dir = tempfile::tempdir().unwrap();
    let path = edited(dir.path(), "no-udp.pcap", Vec::clear);
    let e = err(&path, &SensorOptions::default());
    assert!(
        e.contains("no-udp.pcap") && e.contains("no UDP packets at all"),
        "{e}"
    );
}

#[test]
fn two_sensors_on_one_port_decode_one_and_report_the_other() {
    if !have_data() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let path = edited(dir.path(), "two.pcap", add_second_vlp16);
    let (two, report) = sweeps::read_all(&path, &SensorOptions::default()).unwrap();
    let (one, _) = sweeps::read_all(
        &data().join("velodyne/velodyne_vlp16.pcap"),
        &SensorOptions::default(),
    )
    .unwrap();
    assert_eq!(two.len(), one.len());
    for (a, b) in two.iter().zip(&one) {
        assert_eq!(a.points, b.points);
    }
    let w = report.warnings().join("\n");
    println!("{w}");
    assert!(
        w.contains("192.168.1.202:2368 (84)") && w.contains("two sensors"),
        "{w}"
    );
}

/// A spinning Robosense's MSOP packets say nothing of the model (the RS-16, RS-32 and Bpearl
/// send alike): without `--sensor` the refusal says so and names the models to choose from,
/// rather than that nothing was found.
#[test]
fn robosense_packets_without_a_model_are_refused_naming_the_models() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rs.pcap");
    let msop = Datagram {
        time_ns: 1_000,
        source: "192.168.1.200:6699".parse().unwrap(),
        port: 6699,
        payload: vec![0x55; kiss_odom_sensors::robosense::wire::LEN],
    };
    pcap::write(&path, &[msop.clone(), msop], 9000).unwrap();
    let e = err(&path, &SensorOptions::default());
    println!("{e}");
    assert!(
        e.contains("rs.pcap") && e.contains("spinning Robosense") && e.contains("--sensor rs16"),
        "{e}"
    );
}
