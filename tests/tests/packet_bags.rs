//! Sensor packets recorded in ROS recordings as the vendors' drivers record them (`simulate
//! --messages packets`: VelodyneScan, nebula's PandarScan, RobosenseScan with its info packets
//! and NebulaPackets, ouster-ros' PacketMsg with its metadata topic) decode, through the same
//! decoders and sweep assembly, to the same frames and warnings as a pcap of the same packets:
//! points, per-point times, sweep statistics and times, and the IMU samples of a sensor that
//! sends IMU packets. Every sensor the simulator packetizes is here.

use kiss_odom_io::{Format, Frame, ImuInput, Item, OpenOptions, SensorKind, SensorOptions};
use std::path::{Path, PathBuf};

/// A simulated sensor, the container its packets are recorded in, whether it sends IMU
/// packets, how many sweeps are simulated (the OT128's are the costliest to cast), and the
/// `--sensor` its pcap is read with (the bag of a Robosense names its model itself).
struct Case {
    sensor: &'static str,
    format: &'static str,
    imu: bool,
    frames: &'static str,
    read_as: SensorKind,
}

const fn case(sensor: &'static str, format: &'static str, imu: bool, frames: &'static str) -> Case {
    Case {
        sensor,
        format,
        imu,
        frames,
        read_as: SensorKind::Auto,
    }
}

const CASES: [Case; 17] = [
    case("vlp16", "bag", false, "2"),
    case("vlp32c", "mcap", false, "2"),
    Case {
        read_as: SensorKind::Hdl64eS3,
        ..case("hdl64e-s3", "db3", false, "1")
    },
    case("vls128", "bag", false, "1"),
    case("os1-64", "db3", true, "2"),
    case("xt32", "db3", false, "2"),
    case("qt128", "mcap", false, "2"),
    case("ot128", "bag", false, "1"),
    case("xt16", "mcap", false, "2"),
    case("xt32m", "bag", false, "1"),
    case("pandar40p", "db3", false, "1"),
    case("pandar64", "bag", false, "1"),
    case("qt64", "mcap", false, "1"),
    case("at128", "db3", false, "1"),
    Case {
        read_as: SensorKind::Helios,
        ..case("helios", "db3", false, "2")
    },
    case("mid360", "db3", true, "2"),
    case("avia", "mcap", false, "2"),
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

/// Every frame of `path` and what the reader warned of (the file's name left out); a
/// skipped frame or an error fails the test.
fn frames(path: &Path, sensor: SensorOptions) -> (Vec<Frame>, Vec<String>) {
    let opts = OpenOptions {
        sensor,
        imu: ImuInput::Builtin,
        ..OpenOptions::default()
    };
    let mut ds = kiss_odom_io::open(path, Format::Auto, &opts)
        .unwrap_or_else(|e| panic!("{}: {e:#}", path.display()));
    let mut out = Vec::new();
    while let Some(item) = ds.frames.next_item().unwrap() {
        match item {
            Item::Frame(f) => out.push(f),
            Item::Skipped { reason, .. } => panic!("{reason}"),
        }
    }
    let mut warnings = ds.info.warnings;
    warnings.extend(ds.frames.trailer().warnings);
    let shown = path.display().to_string();
    (
        out,
        warnings.iter().map(|w| w.replace(&shown, "FILE")).collect(),
    )
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
        // A Hesai's angle file (an AT128's .dat), an HDL-64E's or VLS-128's calibration is
        // beside the pcap and the bag; the bag carries an Ouster's metadata and a Robosense's
        // DIFOP packet itself.
        let calibration =
            |dir: &Path| file_in(dir, &["packets.csv", "packets.yaml", "packets.dat"]);
        let (from_pcap, pcap_warnings) = frames(
            &pcap_dir.join("packets.pcap"),
            SensorOptions {
                sensor: case.read_as,
                meta: file_in(&pcap_dir, &["packets.json"]),
                calibration: calibration(&pcap_dir),
                ..SensorOptions::default()
            },
        );
        let bag = file_in(&bag_dir, &["points.bag", "points.mcap", "points"]).unwrap();
        let bag_sensor = match case.read_as {
            SensorKind::Helios => SensorKind::Auto,
            other => other,
        };
        let (from_bag, bag_warnings) = frames(
            &bag,
            SensorOptions {
                sensor: bag_sensor,
                calibration: calibration(&bag_dir),
                ..SensorOptions::default()
            },
        );
        assert_eq!(pcap_warnings, bag_warnings, "{}: warnings", case.sensor);
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
    let case = case("os1-64", "bag", true, "2");
    let (pcap_dir, bag_dir) = (tmp.path().join("pcap"), tmp.path().join("bag"));
    simulate(&pcap_dir, &case, "pcap");
    simulate(&bag_dir, &case, "bag");
    let meta = pcap_dir.join("packets.json");
    let (from_pcap, _) = frames(
        &pcap_dir.join("packets.pcap"),
        SensorOptions {
            meta: Some(meta.clone()),
            ..SensorOptions::default()
        },
    );
    // A ROS 1 bag: ouster_ros/PacketMsg on both packet topics, the metadata a std_msgs/String.
    let bag = bag_dir.join("points.bag");
    let (own, _) = frames(&bag, SensorOptions::default());
    let (given, _) = frames(
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
