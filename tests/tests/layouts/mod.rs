//! The public datasets' own layouts, end to end. One simulated drive, entered in a turn, is
//! written once per layout (`simulate --layout X`) and shared by every test of this module;
//! then
//!
//! - [`reference`]: kiss-icp 1.3.0's own dataloader for X (`tests/reference/dump_layout.py`,
//!   one Python process a layout) and ours read the same points (bit for bit), the same
//!   per-point times and the same ground truth, and `kiss-odom run --format X` gives the
//!   poses and error figures kiss-icp's pipeline gives on the loader;
//! - here: `auto` recognises every layout by its folders;
//! - [`bad_input`]: a ground truth with rows missing, a MulRan folder without
//!   `global_pose.csv`, an NCLT scan cut mid-point, files that disagree in count and two
//!   layouts in one folder are refused or reported naming the file.
//!
//! Only [`reference`] needs Python; without it it prints SKIP.

mod bad_input;
mod reference;

use kiss_odom_io::{open, Format, OpenOptions};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The drive: 12 sweeps of a 16 x 512 sensor at 10 Hz, 8 s into the urban drive under seed 0,
/// in its first turn. MulRan and Newer College store it as their 64 x 1024 Ouster grids.
const DRIVE: [&str; 12] = [
    "--profile",
    "urban",
    "--seed",
    "0",
    "--lead-in",
    "8",
    "--frames",
    "12",
    "--beams",
    "16",
    "--columns",
    "512",
];

/// Frames of [`DRIVE`].
const FRAMES: usize = 12;

/// The simulator's `--layout` values, with our `--format`.
const LAYOUTS: [(&str, Format); 8] = [
    ("mulran", Format::Mulran),
    ("nclt", Format::Nclt),
    ("ncd", Format::Ncd),
    ("helipr", Format::Helipr),
    ("boreas", Format::Boreas),
    ("nuscenes", Format::Nuscenes),
    ("apollo", Format::Apollo),
    ("kitti-raw", Format::KittiRaw),
];

/// Where `--layout X` puts the folder `--format X` opens, and the `--sequence` that picks
/// each sequence it holds (HeLiPR's four LiDARs).
fn folder(layout: &str) -> (&'static str, &'static [Option<&'static str>]) {
    match layout {
        "nclt" => ("2012-01-08", &[None]),
        "helipr" => (
            "",
            &[Some("Ouster"), Some("Velodyne"), Some("Avia"), Some("Aeva")],
        ),
        "nuscenes" => ("", &[Some("61")]),
        "kitti-raw" => ("", &[Some("00")]),
        _ => ("", &[None]),
    }
}

/// This process's folder for the simulated layouts: `layouts-<pid>` in cargo's temporary
/// folder for tests. Folders of earlier runs whose process has ended go first.
fn shared_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
        let proc = Path::new("/proc");
        if proc.join("self").exists() {
            for entry in std::fs::read_dir(&root).into_iter().flatten().flatten() {
                let name = entry.file_name().to_string_lossy().into_owned();
                match name.strip_prefix("layouts-") {
                    Some(pid) if !proc.join(pid).exists() => {
                        let _ = std::fs::remove_dir_all(entry.path());
                    }
                    _ => {}
                }
            }
        }
        let dir = root.join(format!("layouts-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    })
}

fn index(layout: &str) -> usize {
    LAYOUTS
        .iter()
        .position(|(l, _)| *l == layout)
        .unwrap_or_else(|| panic!("no layout {layout}"))
}

/// [`DRIVE`] written in `layout`, once per process: the folder `simulate --out` was given.
/// Tests that change files work on a copy ([`copy_of`]).
fn simulated(layout: &str) -> &'static Path {
    static DONE: [OnceLock<PathBuf>; 8] = [const { OnceLock::new() }; 8];
    DONE[index(layout)].get_or_init(|| {
        let out = shared_dir().join(layout);
        let mut args = vec!["--layout", layout];
        args.extend(DRIVE);
        kiss_odom_tests::simulate(&out, &args);
        out
    })
}

/// A copy of the simulated `layout` in `dir`, to break.
fn copy_of(dir: &Path, layout: &str) -> PathBuf {
    let to = dir.join(layout);
    kiss_odom_tests::copy_tree(simulated(layout), &to);
    to
}

fn options(sequence: Option<&str>) -> OpenOptions {
    OpenOptions {
        sequence: sequence.map(String::from),
        ..OpenOptions::default()
    }
}

fn name(layout: &str, sequence: Option<&str>) -> String {
    match sequence {
        Some(s) => format!("{layout} {s}"),
        None => layout.to_string(),
    }
}

#[test]
fn auto_recognises_every_layout_by_its_folders() {
    for (layout, format) in LAYOUTS {
        let (sub, sequences) = folder(layout);
        let data = simulated(layout).join(sub);
        let found = kiss_odom_io::open::detect(&data).unwrap();
        assert_eq!(found, format, "{}", data.display());
        let sequence = sequences[0];
        let ds = open(&data, Format::Auto, &options(sequence)).unwrap();
        let gt = ds.info.ground_truth.as_ref().expect("ground truth");
        // HeLiPR's loader leaves each scan's last record out, never a scan.
        assert_eq!(gt.len(), FRAMES, "{}", name(layout, sequence));
        assert_eq!(
            Some(FRAMES),
            ds.frames.len_hint(),
            "{}",
            name(layout, sequence)
        );
        assert!(
            ds.info.warnings.is_empty(),
            "{}: {:?}",
            name(layout, sequence),
            ds.info.warnings
        );
    }
}
