//! What the Hesai and Livox recording tests share: the recording's payloads, a sink that keeps
//! every point with its time, and `kiss-odom run` on the recording.

use kiss_odom_sensors::{Chunk, Decode, PointMeta, Pushed, SweepSink, SweepStart, SweepStats};
use kiss_odom_tests::sensor_data;
use std::process::Command;

/// Every UDP payload of the shared recording `file`, in order.
pub fn payloads(file: &str) -> Vec<Vec<u8>> {
    let mut c = kiss_odom_io::capture::pcap::open(&sensor_data().join(file)).unwrap();
    let mut out = Vec::new();
    while let Some(d) = c.next_datagram().unwrap() {
        out.push(d.payload);
    }
    out
}

/// A point's packet (set by the caller), place, time (its sweep's start in ns and seconds
/// after it) and meta.
pub type Point = (usize, [f64; 3], (u64, f64), PointMeta);

/// Every point, and the sweeps.
#[derive(Default)]
pub struct Points {
    start_ns: u64,
    pub points: Vec<Point>,
    pub sweeps: Vec<SweepStats>,
}

impl SweepSink for Points {
    fn begin_sweep(&mut self, s: &SweepStart) {
        self.start_ns = s.start_ns;
    }
    fn points(&mut self, c: Chunk<'_>) {
        for ((p, t), m) in c.xyz.iter().zip(c.times).zip(c.meta) {
            self.points.push((usize::MAX, *p, (self.start_ns, *t), *m));
        }
    }
    fn end_sweep(&mut self, s: &SweepStats) {
        self.sweeps.push(*s);
    }
}

/// `dec` on every payload, pushed again when it says a sweep begins with it.
pub fn decode<D: Decode>(mut dec: D, payloads: &[&[u8]]) -> Points {
    let mut out = Points::default();
    for p in payloads {
        if dec.push(p, &mut out) == Ok(Pushed::Again) {
            assert_ne!(dec.push(p, &mut out), Ok(Pushed::Again));
        }
    }
    dec.finish(&mut out);
    out
}

/// The poses `kiss-odom run` writes for the shared recording `file`, sensor found alone.
pub fn run_poses(file: &str) -> usize {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_kiss-odom-cli"))
        .arg("run")
        .arg(sensor_data().join(file))
        .arg("--out")
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let poses = std::fs::read_to_string(dir.path().join("poses_kitti.txt")).unwrap();
    poses.lines().count()
}

/// The lines `copper-dump KIND FILE` prints, or `None` (with a SKIP line) without the tool.
pub fn copper_dump(kind: &str, file: &str) -> Option<String> {
    let Some(tool) = std::env::var_os("KISS_ODOM_COPPER_DUMP") else {
        println!("SKIP: KISS_ODOM_COPPER_DUMP is not set (bash tests/copper/compare.sh)");
        return None;
    };
    let out = Command::new(tool)
        .arg(kind)
        .arg(sensor_data().join(file))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    Some(String::from_utf8(out.stdout).unwrap())
}
