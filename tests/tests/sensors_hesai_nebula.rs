//! The Hesai decoders against TIER IV nebula's decoded points, one model at a time: a sector
//! of each model's recorded packets (`fixtures/hesai-nebula/`, see its SOURCE.md) read
//! through the capture reader with the unit's angle correction file, and every point nebula
//! decoded from those packets found among ours. With `KISS_ODOM_NEBULA_CAPTURES` set to a
//! folder of whole captures (`bench/hesai/nebula_captures.py` writes it from nebula's bags)
//! the same comparison runs on each whole bag and prints its figures.

use crate::common::pcd_points;
use kiss_odom_io::capture::sweeps;
use kiss_odom_io::dataset::{SensorKind, SensorOptions};
use kiss_odom_tests::repo;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// What nebula's decoder test decodes a model with and keeps (its `TEST_CONFIGS` and the
/// model's `min_range`/`max_range`): the tighter of the two ranges, and dual returns of one
/// firing less than 0.1 m apart reduced to the later block's.
struct Case {
    dir: &'static str,
    kind: SensorKind,
    name: &'static str,
    calibration: Option<&'static str>,
    range: (f64, f64),
    /// Metres per distance unit (the XT32M's header says 5 mm).
    unit_m: f64,
}

const CASES: [Case; 7] = [
    Case {
        dir: "40p",
        kind: SensorKind::Pandar40p,
        name: "Hesai Pandar40P",
        calibration: Some("Pandar40P.csv"),
        range: (0.3, 200.0),
        unit_m: 0.004,
    },
    Case {
        dir: "64",
        kind: SensorKind::Pandar64,
        name: "Hesai Pandar64",
        calibration: Some("Pandar64.csv"),
        range: (0.3, 200.0),
        unit_m: 0.004,
    },
    Case {
        dir: "qt64",
        kind: SensorKind::Qt64,
        name: "Hesai PandarQT64",
        calibration: Some("PandarQT64.csv"),
        range: (0.1, 60.0),
        unit_m: 0.004,
    },
    Case {
        dir: "xt16",
        kind: SensorKind::Xt16,
        name: "Hesai PandarXT-16",
        calibration: Some("PandarXT16.csv"),
        range: (0.05, 120.0),
        unit_m: 0.004,
    },
    Case {
        dir: "xt32",
        kind: SensorKind::Xt32,
        name: "Hesai PandarXT-32",
        calibration: Some("PandarXT32.csv"),
        range: (0.05, 120.0),
        unit_m: 0.004,
    },
    Case {
        dir: "xt32m",
        kind: SensorKind::Xt32m,
        name: "Hesai PandarXT32M",
        calibration: Some("PandarXT32M.csv"),
        range: (0.5, 300.0),
        unit_m: 0.005,
    },
    Case {
        dir: "qt128",
        kind: SensorKind::Qt128,
        name: "Hesai PandarQT128",
        calibration: Some("PandarQT128.csv"),
        range: (0.3, 50.0),
        unit_m: 0.004,
    },
];

/// Our points as nebula keeps them, in nebula's axes, with their sweep; sweeps cut at
/// azimuth 0 (nebula's cut, which it makes channel by channel and we at whole packets).
fn ours_as_nebula_keeps(pcap: &Path, case: &Case, calib_dir: &Path) -> Vec<([f64; 3], u32)> {
    let opts = SensorOptions {
        sensor: case.kind,
        calibration: case.calibration.map(|c| calib_dir.join(c)),
        cut_angle_deg: Some(0.0),
        ..SensorOptions::default()
    };
    let (sweeps, report) = sweeps::read_all(pcap, &opts).expect("the capture decodes");
    assert_eq!(report.sensor, case.name);
    assert_eq!(report.decoded, report.on_port, "every packet decoded");
    let mut out = Vec::new();
    for s in &sweeps {
        // A firing's returns of one channel, in block order (the decoder emits them so).
        let mut groups: HashMap<(u16, u16), Vec<usize>> = HashMap::new();
        for (i, m) in s.meta.iter().enumerate() {
            groups.entry((m.ring, m.column)).or_default().push(i);
        }
        // Nebula's distance: the raw distance times the unit, as float32.
        let d32 = |p: &[f64; 3]| ((norm(p) / case.unit_m).round() * case.unit_m) as f32;
        for (i, (p, m)) in s.points.iter().zip(&s.meta).enumerate() {
            let d = d32(p);
            if !(case.range.0 as f32..=case.range.1 as f32).contains(&d) {
                continue;
            }
            let later = &groups[&(m.ring, m.column)];
            let dropped = later
                .iter()
                .skip_while(|&&j| j != i)
                .skip(1)
                .any(|&j| (d32(&s.points[j]) - d).abs() < 0.1);
            if dropped {
                continue;
            }
            out.push(([-p[1], p[0], p[2]], s.stats.index));
        }
    }
    out
}

/// How nebula's points and ours agree.
#[derive(Debug)]
struct Figures {
    nebula: usize,
    ours: usize,
    /// Nebula's points with no point of ours within 1e-4 m, and their azimuths' range.
    unmatched: usize,
    unmatched_deg: (f64, f64),
    /// Our points with no point of nebula's within 1e-4 m, and their azimuths' range
    /// (nebula's, degrees in (-180, 180]).
    ours_unmatched: usize,
    ours_unmatched_deg: (f64, f64),
    median: f64,
    p99: f64,
    max: f64,
}

/// For each point of `from`, the distance to its nearest point of `to` (a grid of 1 cm cells;
/// `f64::MAX` beyond a cell).
fn nearest(from: &[[f64; 3]], to: &[[f64; 3]]) -> Vec<f64> {
    const CELL: f64 = 0.01;
    let cell = |p: &[f64; 3]| p.map(|v| (v / CELL).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (i, p) in to.iter().enumerate() {
        grid.entry(cell(p)).or_default().push(i);
    }
    from.iter()
        .map(|t| {
            let c = cell(t);
            let mut best = f64::MAX;
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        for &i in grid
                            .get(&[c[0] + dx, c[1] + dy, c[2] + dz])
                            .into_iter()
                            .flatten()
                        {
                            best = best.min(dist(&to[i], t));
                        }
                    }
                }
            }
            best
        })
        .collect()
}

/// Nebula's points against ours, both ways.
fn compare(ours: &[[f64; 3]], theirs: &[[f64; 3]]) -> Figures {
    let mut dists = nearest(theirs, ours);
    let back = nearest(ours, theirs);
    let az = |p: &[f64; 3]| p[0].atan2(p[1]).to_degrees();
    let lost: Vec<f64> = ours
        .iter()
        .zip(&back)
        .filter(|(_, d)| **d > 1e-4)
        .map(|(p, _)| az(p))
        .collect();
    let range = |v: &mut dyn Iterator<Item = f64>| {
        v.fold((f64::MAX, f64::MIN), |(lo, hi), a| (lo.min(a), hi.max(a)))
    };
    let unmatched = dists.iter().filter(|d| **d > 1e-4).count();
    let unmatched_deg = range(
        &mut theirs
            .iter()
            .zip(&dists)
            .filter(|(_, d)| **d > 1e-4)
            .map(|(p, _)| az(p)),
    );
    dists.sort_by(f64::total_cmp);
    let q = |f: f64| dists[((dists.len() - 1) as f64 * f).round() as usize];
    Figures {
        nebula: theirs.len(),
        ours: ours.len(),
        unmatched,
        unmatched_deg,
        ours_unmatched: lost.len(),
        ours_unmatched_deg: range(&mut lost.iter().copied()),
        median: q(0.5),
        p99: q(0.99),
        max: q(1.0),
    }
}

fn fixture(name: &str) -> PathBuf {
    repo().join("fixtures/hesai-nebula").join(name)
}

/// The sector of `dir`'s capture against nebula's points for it: both cut to the points
/// whose azimuth (nebula's, `atan2(x, y)`) lies within `from_deg` + 10 to + 30 degrees, inside
/// the sector's packets' 40 degrees whatever a channel's azimuth offset.
fn sector_equals_nebulas_points(dir: &str, from_deg: f64) {
    let case = CASES.iter().find(|c| c.dir == dir).unwrap();
    let window = from_deg + 10.0..from_deg + 30.0;
    let ours: Vec<_> = ours_as_nebula_keeps(&fixture(&format!("{dir}.pcap")), case, &fixture(""))
        .into_iter()
        .map(|(p, _)| p)
        .filter(|p| window.contains(&p[0].atan2(p[1]).to_degrees().rem_euclid(360.0)))
        .collect();
    let theirs = pcd_points(&std::fs::read(fixture(&format!("{dir}.pcd"))).unwrap());
    let f = compare(&ours, &theirs);
    println!(
        "{}: sector of {} nebula points, {} of ours, {} unmatched; distance median {:.1e} \
         p99 {:.1e} max {:.1e} m, tolerance 1e-4 m",
        case.name,
        f.nebula,
        ours.len(),
        f.unmatched,
        f.median,
        f.p99,
        f.max
    );
    assert!(f.nebula > 1000, "a sector of a thousand points or more");
    assert_eq!(f.unmatched, 0);
    assert!(f.max <= 1e-4);
    // Within the window, nebula kept exactly the points we keep.
    assert_eq!(f.ours_unmatched, 0);
    assert_eq!(ours.len(), f.nebula);
}

#[test]
fn pandar40p_sector_equals_nebulas_points() {
    sector_equals_nebulas_points("40p", 100.0);
}

#[test]
fn pandar64_sector_equals_nebulas_points() {
    sector_equals_nebulas_points("64", 100.0);
}

#[test]
fn pandarqt64_sector_equals_nebulas_points() {
    sector_equals_nebulas_points("qt64", 100.0);
}

#[test]
fn pandarxt16_sector_equals_nebulas_points() {
    sector_equals_nebulas_points("xt16", 100.0);
}

#[test]
fn pandarxt32m_sector_equals_nebulas_points() {
    sector_equals_nebulas_points("xt32m", 10.0);
}

/// Every model's whole capture (nebula's bag as a pcap) against nebula's decoded scan.
#[test]
fn whole_captures_equal_nebulas_scans() {
    let Some(dir) = std::env::var_os("KISS_ODOM_NEBULA_CAPTURES") else {
        println!("SKIP: KISS_ODOM_NEBULA_CAPTURES is not set (bench/hesai/nebula_captures.py)");
        return;
    };
    let dir = PathBuf::from(dir);
    for case in &CASES {
        let pcap = dir.join(format!("{}.pcap", case.dir));
        if !pcap.exists() {
            println!("{}: no {} here", case.name, pcap.display());
            continue;
        }
        let all = ours_as_nebula_keeps(&pcap, case, &dir);
        let theirs = pcd_points(&std::fs::read(dir.join(format!("{}.pcd", case.dir))).unwrap());
        // Every point of nebula's scan is one of ours.
        let points: Vec<_> = all.iter().map(|(p, _)| *p).collect();
        let f = compare(&points, &theirs);
        println!(
            "{}: each of nebula's {} points against the nearest of our {}: {} beyond 1e-4 m; \
             distance median {:.1e} p99 {:.1e} max {:.1e} m, tolerance 1e-4 m",
            case.name, f.nebula, f.ours, f.unmatched, f.median, f.p99, f.max
        );
        assert_eq!(f.unmatched, 0, "{}", case.name);
        assert!(f.max <= 1e-4, "{}", case.name);
        // Our sweep that is nebula's scan (the one leaving fewest of nebula's points
        // unmatched): the points either has alone lie at the cut, which nebula makes channel
        // by channel and we at whole packets.
        let sweeps = all.iter().map(|(_, s)| *s).max().unwrap_or(0);
        let s = (0..=sweeps)
            .map(|k| {
                let ours: Vec<_> = all
                    .iter()
                    .filter(|(_, s)| *s == k)
                    .map(|(p, _)| *p)
                    .collect();
                compare(&ours, &theirs)
            })
            .min_by_key(|f| f.unmatched)
            .unwrap();
        println!(
            "  the sweep cut at 0 degrees: ours {} points, nebula {} ({:+}); {} of ours alone, at \
             azimuths {:.1} to {:.1} degrees; {} of nebula's alone, at {:.1} to {:.1} degrees",
            s.ours,
            s.nebula,
            s.ours as i64 - s.nebula as i64,
            s.ours_unmatched,
            s.ours_unmatched_deg.0,
            s.ours_unmatched_deg.1,
            s.unmatched,
            s.unmatched_deg.0,
            s.unmatched_deg.1
        );
        let at_cut = |n: usize, (lo, hi): (f64, f64)| n == 0 || (lo > -10.0 && hi < 10.0);
        assert!(
            at_cut(s.ours_unmatched, s.ours_unmatched_deg),
            "{}",
            case.name
        );
        assert!(at_cut(s.unmatched, s.unmatched_deg), "{}", case.name);
    }
}

fn norm(p: &[f64; 3]) -> f64 {
    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    norm(&[a[0] - b[0], a[1] - b[1], a[2] - b[2]])
}
