//! What the tests that run `kiss-odom` in-process share: the KITTI sample scans as frame files,
//! the command run through `kiss_odom::cli::main_with` (a panic inside becomes a test failure
//! naming the command), and readers of what it wrote.

#![allow(dead_code)] // each test file uses its own share

use kiss_odom_io::folders::bin;
use kiss_odom_io::poses;
#[allow(unused_imports)] // each test file uses its own share
pub use kiss_odom_tests::{repo, run, Run};
use nalgebra::Matrix4;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

// ------------------------------------------------------------------------------------------
// Helpers: data

/// The bytes of KITTI sample scan `k` (x, y, z, intensity as little-endian f32).
pub fn kitti_bytes(k: usize) -> Vec<u8> {
    let path = repo().join(format!("fixtures/kitti-05-reduced/velodyne/{k:06}.bin"));
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The points of KITTI sample scan `k`.
pub fn kitti_points(k: usize) -> Vec<[f64; 3]> {
    bin::parse(&kitti_bytes(k)).expect("fixture scans are whole")
}

/// Per-point capture times of a spinning sensor for `points` (10 Hz, by azimuth), as a
/// `timestamps/NNNNNN.bin` file holds them.
pub fn sweep_stamps(points: &[[f64; 3]]) -> Vec<f64> {
    points
        .iter()
        .map(|p| {
            let turn = (std::f64::consts::PI - p[1].atan2(p[0])) / std::f64::consts::TAU;
            1.7e9 + 0.1 * turn
        })
        .collect()
}

pub fn stamp_bytes(stamps: &[f64]) -> Vec<u8> {
    stamps.iter().flat_map(|t| t.to_le_bytes()).collect()
}

/// `root/velodyne`, created.
pub fn velodyne(root: &Path) -> PathBuf {
    let dir = root.join("velodyne");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A generic-layout folder `root` of `n` KITTI scans as `.bin` files, scan `k` at position
/// `k`.
pub fn bin_folder(root: &Path, n: usize) -> PathBuf {
    let frames = velodyne(root);
    for k in 0..n {
        std::fs::write(frames.join(format!("{k:06}.bin")), kitti_bytes(k)).unwrap();
    }
    frames
}

// ------------------------------------------------------------------------------------------
// Helpers: running the tool and reading what it wrote

/// A `frames.csv` row: the columns these tests look at.
#[derive(Debug)]
pub struct Row {
    pub index: usize,
    /// The file (or message) the row came from.
    pub source: String,
    pub deskewed: bool,
    /// `registered`, `empty` or `skipped`.
    pub outcome: String,
    /// The status flags set (their 0/1 columns).
    pub flags: Vec<String>,
}

/// `kiss-odom ARGS...` in-process: the exit status and stderr (see
/// [`kiss_odom_tests::kiss_odom`]).
pub fn kiss_odom(args: Vec<OsString>) -> (i32, String) {
    let r = kiss_odom_tests::kiss_odom(&args, Path::new(""));
    (r.code, r.stderr)
}

/// What these tests read from a run's outputs beyond [`Run`]'s own readers.
pub trait RunExt {
    /// A whole-number field of `summary.json`.
    fn count(&self, key: &str) -> u64;
    /// The rows of `frames.csv`.
    fn rows(&self) -> Vec<Row>;
    /// `poses_kitti.txt` as 4x4 matrices.
    fn poses(&self) -> Vec<Matrix4<f64>>;
    /// The `error: ` lines of stderr.
    fn errors(&self) -> Vec<&str>;
    /// The run failed with exit 1 and exactly one error line, the last line of stderr, that
    /// names `file`; returns that line.
    fn failed_naming(&self, file: &Path) -> &str;
    /// Exit 0, every pose finite, and one `frames.csv` row per pose with the indices `0..n`.
    fn succeeded_with_frames(&self, n: usize) {
        self.succeeded_with_frames_from(0, n);
    }
    /// Exit 0, every pose finite, and one `frames.csv` row per pose with the indices
    /// `first..first + n`.
    fn succeeded_with_frames_from(&self, first: usize, n: usize);
}

impl RunExt for Run {
    fn count(&self, key: &str) -> u64 {
        let s = self.summary();
        s[key]
            .as_u64()
            .unwrap_or_else(|| panic!("summary.json has no count {key}: {s:#}"))
    }

    fn rows(&self) -> Vec<Row> {
        let path = self.out.join("frames.csv");
        let text = std::fs::read_to_string(&path)
            .unwrap_or_else(|e| panic!("{}: {e}\nstderr:\n{}", path.display(), self.stderr));
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().expect("a header line").split(',').collect();
        let col = |name: &str| {
            header
                .iter()
                .position(|c| *c == name)
                .unwrap_or_else(|| panic!("frames.csv has no column {name}: {header:?}"))
        };
        let (index, deskewed, outcome) = (col("index"), col("deskewed"), col("outcome"));
        let source = col("source");
        let flags: Vec<(usize, &str)> = kiss_odom_core::Flag::ALL
            .iter()
            .map(|f| (col(f.name()), f.name()))
            .collect();
        lines
            .map(|line| {
                // No commas in these tests' paths, so a plain split is the CSV.
                let cells: Vec<&str> = line.split(',').collect();
                assert_eq!(cells.len(), header.len(), "frames.csv line {line:?}");
                Row {
                    index: cells[index].parse().expect("an index"),
                    source: cells[source].to_string(),
                    deskewed: cells[deskewed] == "true",
                    outcome: cells[outcome].to_string(),
                    flags: flags
                        .iter()
                        .filter(|(c, _)| cells[*c] == "1")
                        .map(|(_, name)| name.to_string())
                        .collect(),
                }
            })
            .collect()
    }

    fn poses(&self) -> Vec<Matrix4<f64>> {
        let path = self.out.join("poses_kitti.txt");
        poses::read_kitti_matrices(&path)
            .unwrap_or_else(|e| panic!("{e:#}\nstderr:\n{}", self.stderr))
    }

    fn errors(&self) -> Vec<&str> {
        self.stderr
            .lines()
            .filter(|l| l.starts_with("error: "))
            .collect()
    }

    fn failed_naming(&self, file: &Path) -> &str {
        assert_eq!(self.code, 1, "exit status; stderr:\n{}", self.stderr);
        let errors = self.errors();
        assert_eq!(errors.len(), 1, "one error line; stderr:\n{}", self.stderr);
        let line = errors[0];
        assert_eq!(
            self.stderr.lines().last(),
            Some(line),
            "the error is the last line; stderr:\n{}",
            self.stderr
        );
        assert!(
            line.contains(&file.display().to_string()),
            "the error names {}: {line}",
            file.display()
        );
        line
    }

    fn succeeded_with_frames_from(&self, first: usize, n: usize) {
        assert_eq!(self.code, 0, "exit status; stderr:\n{}", self.stderr);
        assert!(self.errors().is_empty(), "stderr:\n{}", self.stderr);
        let poses = self.poses();
        assert_eq!(poses.len(), n, "poses_kitti.txt lines");
        for (k, p) in poses.iter().enumerate() {
            assert!(
                p.iter().all(|v| v.is_finite()),
                "pose {k} is not finite: {p}"
            );
        }
        let indices: Vec<usize> = self.rows().iter().map(|r| r.index).collect();
        let want: Vec<usize> = (first..first + n).collect();
        assert_eq!(indices, want, "frames.csv indices");
        assert_eq!(self.count("frames"), n as u64);
    }
}

/// The warning line that names `file`, with the reason after the name.
pub fn warning_for<'a>(run: &'a Run, file: &Path) -> &'a str {
    let name = file.display().to_string();
    let hits: Vec<&str> = run
        .warnings()
        .into_iter()
        .filter(|w| w.contains(&name))
        .collect();
    assert_eq!(
        hits.len(),
        1,
        "one warning naming {name}; stderr:\n{}",
        run.stderr
    );
    let reason = hits[0].split_once(&format!("{name}: ")).map(|(_, r)| r);
    assert!(
        reason.is_some_and(|r| !r.trim().is_empty()),
        "the warning gives a reason after the file name: {}",
        hits[0]
    );
    hits[0]
}

/// `a^-1 b` translation distance of two 4x4 poses.
pub fn distance(a: &Matrix4<f64>, b: &Matrix4<f64>) -> f64 {
    let d = a.try_inverse().expect("a rigid transform") * b;
    d.fixed_view::<3, 1>(0, 3).norm()
}

/// Checks that frames `skipped` of `run` have the constant-velocity prediction as their pose
/// (`T_k = T_{k-1} T_{k-2}^-1 T_{k-1}`), as `summary.json` documents for skipped and empty
/// frames.
pub fn skipped_poses_are_predictions(run: &Run, skipped: &[usize]) {
    let p = run.poses();
    for &k in skipped {
        assert!(k >= 2, "a prediction needs two frames before");
        let prediction = p[k - 1] * p[k - 2].try_inverse().unwrap() * p[k - 1];
        let off = (p[k] - prediction).amax();
        assert!(
            off < 1e-9,
            "frame {k}: pose differs from the constant-velocity prediction by {off:e}"
        );
    }
}

// ------------------------------------------------------------------------------------------
// Bag and MCAP fixtures

pub fn bag_fixture(name: &str) -> PathBuf {
    repo().join("fixtures/bags").join(name)
}

/// Where the payload of `ouster` frame `k` starts in a fixture: its first point is
/// `(k, 0, 0.5 + k / 2)` as little-endian f32 (make_bags.py), found exactly once.
pub fn ouster_payload_at(bytes: &[u8], k: u32) -> usize {
    let k = k as f32;
    let pattern: Vec<u8> = [k, 0.0, 0.5 + k / 2.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let hits: Vec<usize> = bytes
        .windows(pattern.len())
        .enumerate()
        .filter(|(_, w)| *w == pattern.as_slice())
        .map(|(i, _)| i)
        .collect();
    assert_eq!(hits.len(), 1, "frame {k}'s first point in the fixture");
    hits[0]
}

/// Waits until `child` (named `name` in failures) has bound the UDP address `addr`: that is
/// when the address can no longer be taken. A hang guard of [`kiss_odom_tests::HANG`], not a
/// speed check.
pub fn wait_listening(child: &mut std::process::Child, addr: &str, name: &str) {
    let listening = kiss_odom_tests::wait_until(kiss_odom_tests::HANG, || {
        if let Some(status) = child.try_wait().unwrap() {
            panic!("{name} ended ({status}) before listening");
        }
        std::net::UdpSocket::bind(addr).is_err()
    });
    assert!(listening, "{name} never listened");
}

/// The x y z of a binary PCD file of three float fields.
pub fn pcd_points(bytes: &[u8]) -> Vec<[f64; 3]> {
    let marker = b"DATA binary\n";
    let at = bytes
        .windows(marker.len())
        .position(|w| w == marker)
        .expect("a binary PCD")
        + marker.len();
    bytes[at..]
        .chunks_exact(12)
        .map(|c| {
            let f = |i: usize| f64::from(f32::from_le_bytes(c[i..i + 4].try_into().unwrap()));
            [f(0), f(4), f(8)]
        })
        .collect()
}
