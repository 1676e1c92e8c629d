//! The Velodyne decoder on TIER IV nebula's decoder test bags (`fixtures/velodyne-nebula/`,
//! see its SOURCE.md): VLP-16 (dual return), VLP-32 (strongest) and VLS-128 (strongest)
//! packets decoded with nebula's own calibration files, point by point against nebula's
//! ground-truth clouds.
//!
//! Where nebula reads a return as the manuals do, our point is nebula's within 1e-4 m. Where
//! it does not ([`nebula_reading`]'s departures: its azimuth chain in dual mode, the blocks it
//! leaves uninterpolated, the VLP-32's channel timing), our point is the manual's reading of
//! that same return, and the count of each departure is printed.

use crate::common::pcd_points;
use crate::nebula_reading::{read, Departure, Laser, Neb, Reading};
use kiss_odom_io::capture::{pcap, sweeps, velodyne_calib};
use kiss_odom_io::dataset::{SensorKind, SensorOptions};
use kiss_odom_tests::repo;
use std::collections::{BTreeMap, HashMap};
use std::path::PathBuf;

/// Ours against nebula where nebula follows the manual.
const TOL_M: f64 = 1e-4;
/// Our reading of nebula against nebula's cloud: its f32 arithmetic at up to 300 m.
const F32_TOL_M: f64 = 4e-5;

fn fixture(name: &str) -> PathBuf {
    repo().join("fixtures/velodyne-nebula").join(name)
}

/// Points hashed on a 1 cm grid, for nearest-point look-ups within a few millimetres.
struct Grid<'a> {
    points: &'a [[f64; 3]],
    cells: HashMap<[i64; 3], Vec<usize>>,
    cell: f64,
}

impl<'a> Grid<'a> {
    fn new(points: &'a [[f64; 3]], cell: f64) -> Self {
        let mut cells: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
        for (i, p) in points.iter().enumerate() {
            cells.entry(Self::cell_of(p, cell)).or_default().push(i);
        }
        Self {
            points,
            cells,
            cell,
        }
    }
    fn cell_of(p: &[f64; 3], cell: f64) -> [i64; 3] {
        p.map(|v| (v / cell).floor() as i64)
    }
    /// The nearest point within a cell's reach, and its distance.
    fn nearest(&self, q: &[f64; 3]) -> Option<(usize, f64)> {
        let c = Self::cell_of(q, self.cell);
        let mut best: Option<(usize, f64)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(ids) = self.cells.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                        continue;
                    };
                    for &i in ids {
                        let d = dist(&self.points[i], q);
                        if best.is_none_or(|(_, b)| d < b) {
                            best = Some((i, d));
                        }
                    }
                }
            }
        }
        best
    }
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

/// One bag: the packets, nebula's calibration and cloud, nebula's range filter.
struct Case {
    model: Neb,
    sensor: SensorKind,
    pcap: &'static str,
    yaml: &'static str,
    cloud: &'static str,
    range: (f64, f64),
}

fn check(case: &Case) {
    let opts = SensorOptions {
        sensor: case.sensor,
        calibration: Some(fixture(case.yaml)),
        ..SensorOptions::default()
    };
    let (sweeps, report) = sweeps::read_all(&fixture(case.pcap), &opts).expect("decoded");
    let ours: Vec<[f64; 3]> = sweeps.iter().flat_map(|s| s.points.clone()).collect();
    let in_range = ours
        .iter()
        .filter(|p| {
            let r = dist(p, &[0.0; 3]);
            r > case.range.0 && r < case.range.1
        })
        .count();

    // Nebula's reading of every packet.
    let calib = velodyne_calib::read(&fixture(case.yaml)).unwrap();
    let lasers: Vec<Laser> = calib
        .lasers
        .iter()
        .map(|l| Laser {
            vert: l.vertical_deg.to_radians() as f32,
            rot: (-l.azimuth_offset_deg).to_radians() as f32,
            dist: l.distance_offset_m as f32,
        })
        .collect();
    let resolution = match case.model {
        Neb::Vls128 => 0.004f32,
        _ => calib.distance_resolution_m as f32,
    };
    let mut cap = pcap::open(&fixture(case.pcap)).unwrap();
    let mut readings: Vec<Reading> = Vec::new();
    while let Some(d) = cap.next_datagram().unwrap() {
        readings.extend(read(case.model, &d.payload, &lasers, resolution));
    }
    let kept = readings
        .iter()
        .filter(|r| r.range > case.range.0 && r.range < case.range.1)
        .count();
    let nebula_xyz: Vec<[f64; 3]> = readings.iter().map(|r| r.nebula).collect();

    let theirs = pcd_points(&std::fs::read(fixture(case.cloud)).unwrap());
    let ours_grid = Grid::new(&ours, 0.01);
    // For the distance statistics: nebula's points up to a metre from ours.
    let ours_coarse = Grid::new(&ours, 1.0);
    let reading_grid = Grid::new(&nebula_xyz, 0.01);
    let mut worst_reading = 0f64;
    let mut worst_agreeing = 0f64;
    let mut worst_manual = 0f64;
    // Where nebula rounds after a fractional offset: its point against ours, as a fraction
    // of the 0.01 degree (plus f32) the two roundings of one exact azimuth may be apart.
    let mut worst_rounding = 0f64;
    let mut departures: BTreeMap<Departure, usize> = BTreeMap::new();
    let mut to_ours = Vec::with_capacity(theirs.len());
    for t in &theirs {
        let (i, e) = reading_grid
            .nearest(t)
            .expect("nebula's point read from the packets");
        worst_reading = worst_reading.max(e);
        let r = &readings[i];
        *departures.entry(r.departure).or_default() += 1;
        let d_ours = ours_coarse.nearest(t).map_or(f64::INFINITY, |(_, d)| d);
        to_ours.push(d_ours);
        if r.departure == Departure::None {
            worst_agreeing = worst_agreeing.max(d_ours);
        } else {
            let m = ours_grid
                .nearest(&r.manual)
                .map_or(f64::INFINITY, |(_, d)| d);
            worst_manual = worst_manual.max(m);
        }
        if r.departure == Departure::RoundsAfterOffset {
            let bound = r.range * 0.01f64.to_radians() + F32_TOL_M;
            worst_rounding = worst_rounding.max(d_ours / bound);
        }
    }
    to_ours.sort_by(f64::total_cmp);
    println!(
        "{} ({:?}): {} points of ours ({in_range} within nebula's range filter {:?} m), {} of \
         nebula's ({kept} returns in the packets pass its range filter; the rest are outside \
         its cloud: azimuth window, scan cut); nebula to ours: median {:.2e} m, p99 {:.2e} m, \
         max {:.2e} m",
        report.sensor,
        case.model,
        ours.len(),
        case.range,
        theirs.len(),
        percentile(&to_ours, 0.5),
        percentile(&to_ours, 0.99),
        to_ours.last().unwrap(),
    );
    println!(
        "  nebula's points by how nebula read them: {departures:?}; our reading of nebula \
         reproduces its cloud within {worst_reading:.2e} m (tolerance {F32_TOL_M:e}); where \
         nebula reads as the manual, ours is within {worst_agreeing:.2e} m (tolerance \
         {TOL_M:e}); elsewhere ours is the manual's reading within {worst_manual:.2e} m \
         (tolerance {TOL_M:e}); nebula's rounding after a fractional offset moves its points \
         at most {worst_rounding:.2} of the 0.01 degree bound"
    );
    assert!(
        worst_rounding <= 1.0,
        "nebula's rounding does not explain a point"
    );
    assert!(worst_reading <= F32_TOL_M, "our reading of nebula is off");
    assert!(
        worst_agreeing <= TOL_M,
        "ours differs where nebula follows the manual"
    );
    assert!(worst_manual <= TOL_M, "ours is not the manual's reading");
}

#[test]
fn vlp16_dual_agrees_with_nebula_where_nebula_follows_the_manual() {
    check(&Case {
        model: Neb::Vlp16,
        sensor: SensorKind::Vlp16,
        pcap: "vlp16.pcap",
        yaml: "VLP16.yaml",
        cloud: "vlp16-nebula.pcd",
        range: (0.3, 300.0),
    });
}

#[test]
fn vlp32_agrees_with_nebula_where_nebula_follows_the_manual() {
    check(&Case {
        model: Neb::Vlp32,
        sensor: SensorKind::Vlp32c,
        pcap: "vlp32.pcap",
        yaml: "VLP32.yaml",
        cloud: "vlp32-nebula.pcd",
        range: (0.4, 50.0),
    });
}

#[test]
fn vls128_agrees_with_nebula_where_nebula_follows_the_manual() {
    check(&Case {
        model: Neb::Vls128,
        sensor: SensorKind::Vls128,
        pcap: "vls128-sector.pcap",
        yaml: "VLS128.yaml",
        cloud: "vls128-nebula.pcd",
        range: (0.3, 300.0),
    });
}

#[test]
fn a_vls128_or_helios_without_its_angles_exits_naming_what_is_missing() {
    let sector = fixture("vls128-sector.pcap");
    let no_file = SensorOptions {
        sensor: SensorKind::Vls128,
        ..SensorOptions::default()
    };
    let e = format!("{:#}", sweeps::read_all(&sector, &no_file).unwrap_err());
    assert!(
        e.contains("vls128-sector.pcap") && e.contains("VLS-128 needs the unit's calibration"),
        "{e}"
    );
    // Found by its product byte, with no file: every packet refused, the reason reported.
    let e = format!(
        "{:#}",
        sweeps::read_all(&sector, &SensorOptions::default()).unwrap_err()
    );
    assert!(
        e.contains("none decoded") && e.contains("calibration"),
        "{e}"
    );
    // A malformed calibration file: its name and what is wrong.
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.yaml");
    std::fs::write(&bad, "lasers:\n  - {laser_id: 0, vert_correction: x}\n").unwrap();
    let opts = SensorOptions {
        calibration: Some(bad),
        ..no_file.clone()
    };
    let e = format!("{:#}", sweeps::read_all(&sector, &opts).unwrap_err());
    assert!(e.contains("bad.yaml"), "{e}");
    // A Helios recording without a DIFOP packet and no angle file.
    let helios = SensorOptions {
        sensor: SensorKind::Helios,
        ..SensorOptions::default()
    };
    let e = format!("{:#}", sweeps::read_all(&sector, &helios).unwrap_err());
    assert!(
        e.contains("no DIFOP packet") && e.contains("--calibration"),
        "{e}"
    );
}

#[test]
fn a_second_models_packets_on_the_port_are_counted_not_decoded() {
    // The VLP-16's packets, then the VLS-128 sector's, one port, one sender.
    let mut datagrams = Vec::new();
    for name in ["vlp16.pcap", "vls128-sector.pcap"] {
        let mut cap = pcap::open(&fixture(name)).unwrap();
        while let Some(d) = cap.next_datagram().unwrap() {
            datagrams.push(d);
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let both = dir.path().join("both.pcap");
    pcap::write(&both, &datagrams, 1500).unwrap();
    let opts = SensorOptions {
        calibration: Some(fixture("VLP16.yaml")),
        ..SensorOptions::default()
    };
    let (sweeps, report) = sweeps::read_all(&both, &opts).unwrap();
    let decoded: u32 = sweeps.iter().map(|s| s.stats.packets).sum();
    let other = report
        .refused
        .get(&kiss_odom_sensors::PacketError::OtherSensor.to_string())
        .copied()
        .unwrap_or(0);
    println!(
        "VLP-16 then VLS-128 on one port: {decoded} decoded as {}, {other} refused as another \
         sensor's; warnings: {:?}",
        report.sensor,
        report.warnings()
    );
    assert_eq!((decoded, other), (152, 80));
    assert!(report
        .warnings()
        .iter()
        .any(|w| w.contains("another sensor")));
}
