//! Sensor packets recorded in ROS recordings as the vendors' drivers record them (`simulate
//! --messages packets`: VelodyneScan, nebula's PandarScan and NebulaPackets, ouster-ros'
//! PacketMsg with its metadata topic) decode, through the same decoders and sweep assembly, to
//! the same frames as a pcap of the same packets: points, per-point times, sweep statistics
//! and times, and the IMU samples of a sensor that sends IMU packets.

use kiss_odom_io::{Format, Frame, ImuInput, Item, OpenOptions, SensorOptions};
use std::path::{Path, PathBuf};

/// A simulated sensor, the container its packets are recorded in, whether it sends IMU
/// packets, and how many sweeps are simulated (the OT128's are the costliest to cast).
struct Case {
    sensor: &'static str,
    format: &'static str,
    imu: bool,
    frames: &'static str,
}

const CASES: [Case; 8] = [
    Case {
        sensor: "vlp16",
        format: "bag",
        imu: false,
        frames: "2",
    },
    Case {
        sensor: "vlp32c",
        format: "mcap",
        imu: false,
        frames: "2",
    },
    Case {
        sensor: "os1-64",
        format: "db3",
        imu: true,
        frames: "2",
    },
    Case {
        sensor: "xt32",
        format: "db3",
        imu: false,
        frames: "2",
    },
    Case {
        sensor: "qt128",
        format: "mcap",
        imu: false,
        frames: "2",
    },
    Case {
        sensor: "ot128",
        format: "bag",
        imu: false,
        frames: "1",
    },
    Case {
        sensor: "mid360",
        format: "db3",
        imu: true,
        frames: "2",
    },
    Case {
        sensor: "avia",
        format: "mcap",
        imu: false,
        frames: "2",
    },
];

fn simulate(dir: &Path, case: &Case, format: &str) {
    let mut args = vec![
        "--sensor",
        case.sensor,
        "--format",
        format,
        "--frames",
        case.frames,
        "--profile",
        "fast",
        "--seed",
        "5",
    ];
    if format != "pcap" {
        args.extend(["--messages", "packets"]);
    }
    if case.imu {
        args.extend(["--imu-rate", "200"]);
    }
    kiss_odom_tests::simulate(dir, &args);
}

/// Every frame of `path`; a skipped frame or an error fails the test.
fn frames(path: &Path, sensor: SensorOptions) -> Vec<Frame> {
    let opts = OpenOptions {
        sensor,
        imu: ImuInput::Builtin,
        ..OpenOptions::default()
    };
    let mut ds = kiss_odom_io::open(path, Format::Auto, &opts)
        .unwrap_or_else(|e| panic!("{}: {e:#}", path.display()));
    assert!(ds.info.warnings.is_empty(), "{:?}", ds.info.warnings);
    let mut out = Vec::new();
    while let Some(item) = ds.frames.next_item().unwrap() {
        match item {
            Item::Frame(f) => out.push(f),
            Item::Skipped { reason, .. } => panic!("{reason}"),
        }
    }
    let trailer = ds.frames.trailer();
    assert!(trailer.warnings.is_empty(), "{:?}", trailer.warnings);
    out
}

fn file_in(dir: &Path, names: &[&str]) -> Option<PathBuf> {
    names.iter().map(|n| dir.join(n)).find(|p| p.exists())
}

#[test]
fn a_bag_of_packets_decodes_to_the_frames_of_a_pcap_of_the_same_packets() {
    let tmp = tempfile::tempdir().unwrap();
    for case in &CASES {
        let (pcap_dir, bag_dir) = (tmp.path().join("pcap"), tmp.path().join("bag"));
        let _ = std::fs::remove_dir_all(&pcap_dir);
        let _ = std::fs::remove_dir_all(&bag_dir);
        simulate(&pcap_dir, case, "pcap");
        simulate(&bag_dir, case, case.format);
        let calibration = file_in(&pcap_dir, &["packets.csv"]);
        let from_pcap = frames(
            &pcap_dir.join("packets.pcap"),
            SensorOptions {
                meta: file_in(&pcap_dir, &["packets.json"]),
                calibration: calibration.clone(),
                ..SensorOptions::default()
            },
        );
        // The bag carries an Ouster's metadata itself; a QT128's or OT128's angle file is
        // beside it, as beside the pcap.
        let bag = file_in(&bag_dir, &["points.bag", "points.mcap", "points"]).unwrap();
        let from_bag = frames(
            &bag,
            SensorOptions {
                calibration: file_in(&bag_dir, &["packets.csv"]),
                ..SensorOptions::default()
            },
        );
        assert!(!from_pcap.is_empty(), "{}: no frames", case.sensor);
        assert_eq!(from_pcap.len(), from_bag.len(), "{}: frames", case.sensor);
        let (mut points, mut imu) = (0, 0);
        for (p, b) in from_pcap.iter().zip(&from_bag) {
            let k = p.index;
            assert_eq!(p.points, b.points, "{} frame {k}: points", case.sensor);
            assert_eq!(p.stamps, b.stamps, "{} frame {k}: times", case.sensor);
            assert_eq!(p.intensity, b.intensity, "{} frame {k}", case.sensor);
            assert_eq!(
                (p.index, p.time),
                (b.index, b.time),
                "{} frame {k}",
                case.sensor
            );
            assert_eq!(p.sweep, b.sweep, "{} frame {k}: sweep", case.sensor);
            assert_eq!(p.imu, b.imu, "{} frame {k}: IMU samples", case.sensor);
            points += p.points.len();
            imu += p.imu.len();
        }
        println!(
            "{} in a {}: {} frames, {points} points, {imu} IMU samples, each as from the pcap",
            case.sensor,
            case.format,
            from_bag.len()
        );
        assert_eq!(imu > 0, case.imu, "{}: IMU samples", case.sensor);
    }
}

#[test]
fn an_ouster_bag_decodes_with_its_own_metadata_or_the_file_given() {
    let tmp = tempfile::tempdir().unwrap();
    let case = Case {
        sensor: "os1-64",
        format: "bag",
        imu: true,
        frames: "2",
    };
    let (pcap_dir, bag_dir) = (tmp.path().join("pcap"), tmp.path().join("bag"));
    simulate(&pcap_dir, &case, "pcap");
    simulate(&bag_dir, &case, "bag");
    let meta = pcap_dir.join("packets.json");
    let from_pcap = frames(
        &pcap_dir.join("packets.pcap"),
        SensorOptions {
            meta: Some(meta.clone()),
            ..SensorOptions::default()
        },
    );
    // A ROS 1 bag: ouster_ros/PacketMsg on both packet topics, the metadata a std_msgs/String.
    let bag = bag_dir.join("points.bag");
    let own = frames(&bag, SensorOptions::default());
    let given = frames(
        &bag,
        SensorOptions {
            meta: Some(meta),
            ..SensorOptions::default()
        },
    );
    let samples: usize = own.iter().map(|f| f.imu.len()).sum();
    println!(
        "os1-64 in a ROS 1 bag: {} frames, {samples} IMU samples, as from the pcap with its \
         own metadata and with the file's",
        own.len()
    );
    assert!(samples > 0);
    assert_eq!(own, given);
    for (p, b) in from_pcap.iter().zip(&own) {
        assert_eq!(
            (&p.points, &p.stamps, &p.imu),
            (&b.points, &b.stamps, &b.imu)
        );
    }
    assert_eq!(from_pcap.len(), own.len());
    // Metadata of another sensor layout is refused before the first sweep, naming the file.
    let wrong = tmp.path().join("wrong.json");
    let text = std::fs::read_to_string(pcap_dir.join("packets.json")).unwrap();
    std::fs::write(
        &wrong,
        text.replace("\"columns_per_packet\": 16", "\"columns_per_packet\": 8"),
    )
    .unwrap();
    let opts = OpenOptions {
        sensor: SensorOptions {
            meta: Some(wrong.clone()),
            ..SensorOptions::default()
        },
        ..OpenOptions::default()
    };
    let e = match kiss_odom_io::open(&bag, Format::Auto, &opts) {
        Err(e) => format!("{e:#}"),
        Ok(mut ds) => loop {
            match ds.frames.next_item() {
                Err(e) => break format!("{e:#}"),
                Ok(Some(_)) => continue,
                Ok(None) => panic!("wrong metadata decoded"),
            }
        },
    };
    println!("{e}");
    assert!(e.contains("wrong.json"), "{e}");
}
