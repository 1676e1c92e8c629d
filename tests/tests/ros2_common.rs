//! Helpers shared by the `ros2*.rs` tests: a node and the player in threads of the test
//! process, the `kiss-odom` command as a separate process, `kiss-odom run` for the poses to
//! compare with.
//!
//! DDS matches the two ends of a topic separately, and a reader drops what a writer it has not
//! matched yet sends: whatever publishes to a node here starts once the node's side has matched
//! it ([`Node::wait_matched`]), not after a pause.

#![allow(dead_code)]

use clap::Parser;
use kiss_odom::cli::{Cli, Command};
use kiss_odom::ros2::node::{self, NodeOptions, Summary};
use kiss_odom::ros2::params::NodeParams;
use kiss_odom::ros2::play::Player;
use kiss_odom::ros2::watch::Watch;
use kiss_odom_drive::settings::Settings;
pub use kiss_odom_tests::{wait_until, HANG};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

/// One DDS test at a time in a test binary: they share two cores, and a 10 Hz test must not
/// compete with a 50 Hz one.
static SERIAL: Mutex<()> = Mutex::new(());

/// Takes the test lock (a failed test poisons nothing that matters here).
pub fn serial() -> MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

/// A DDS domain for test `k` (0..12) of this process: runs of the suite started by different
/// processes do not hear each other.
pub fn domain(k: u16) -> u16 {
    assert!(k < 12);
    20 + (std::process::id() % 16) as u16 * 12 + k
}

/// The repository root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The shipped KITTI sample, relative to the repository root.
pub const KITTI_DIR: &str = "fixtures/kitti-05-reduced";

/// The shipped KITTI sample's path.
pub fn kitti() -> String {
    root().join(KITTI_DIR).to_string_lossy().into_owned()
}

/// The `kiss-odom` command (this package's copy of it).
pub fn cli() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_kiss-odom-cli"))
}

/// The node thread and its result.
type NodeThread = std::thread::JoinHandle<Result<Summary, String>>;

/// What a node prints, readable while it runs (its frame lines are its acknowledgements).
#[derive(Clone, Default)]
struct Printed(Arc<Mutex<Vec<u8>>>);

impl std::io::Write for Printed {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Printed {
    fn text(&self) -> String {
        String::from_utf8_lossy(&self.0.lock().unwrap_or_else(|e| e.into_inner())).into_owned()
    }
}

/// A node running in a thread of the test process.
pub struct Node {
    stop: Arc<AtomicBool>,
    handle: NodeThread,
    out: Printed,
    err: Printed,
    /// What its readers and writers have matched.
    pub watch: Arc<Watch>,
    /// The IMU topic it reads, if any.
    pub imu_topic: Option<String>,
    /// Where it writes its poses.
    pub poses: PathBuf,
}

/// What a stopped node printed and counted.
pub struct Stopped {
    /// Counters.
    pub summary: Summary,
    /// Standard output (frame lines and the summary).
    pub out: String,
    /// Warnings.
    pub err: String,
    /// Poses written, KITTI lines.
    pub poses: String,
}

/// Starts a node on `domain` with default parameters, taking a cloud at most every `min_period`,
/// its poses written to `dir/node_poses.txt`.
pub fn start_node(domain: u16, dir: &Path, min_period: Duration) -> Node {
    start_node_with(domain, dir, min_period, NodeParams::default())
}

/// [`start_node`] with other node parameters.
pub fn start_node_with(domain: u16, dir: &Path, min_period: Duration, params: NodeParams) -> Node {
    start_node_opts(domain, dir, min_period, params, None)
}

/// A node with the gyroscope prior on, reading IMU samples from `topic` (as `--imu TOPIC`).
pub fn start_node_imu(domain: u16, dir: &Path, topic: &str) -> Node {
    start_node_opts(
        domain,
        dir,
        Duration::ZERO,
        NodeParams::default(),
        Some(topic.into()),
    )
}

fn start_node_opts(
    domain: u16,
    dir: &Path,
    min_period: Duration,
    params: NodeParams,
    imu_topic: Option<String>,
) -> Node {
    let mut settings = Settings::default();
    settings.imu.enabled = imu_topic.is_some();
    let poses = dir.join("node_poses.txt");
    let watch = Arc::new(Watch::default());
    let opts = NodeOptions {
        settings,
        params,
        domain,
        poses: Some(poses.clone()),
        min_period,
        imu_topic: imu_topic.clone(),
        watch: watch.clone(),
    };
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let (out, err) = (Printed::default(), Printed::default());
    let (mut o, mut e) = (out.clone(), err.clone());
    let handle = std::thread::spawn(move || {
        node::run(&opts, &flag, &mut o, &mut e).map_err(|e| format!("{e:#}"))
    });
    Node {
        stop,
        handle,
        out,
        err,
        watch,
        imu_topic,
        poses,
    }
}

impl Node {
    /// Poses written so far.
    pub fn registered(&self) -> usize {
        std::fs::read_to_string(&self.poses)
            .map(|s| s.lines().count())
            .unwrap_or(0)
    }

    /// Whether the node has registered the cloud stamped `stamp` (s): a frame line says so.
    pub fn has_registered(&self, stamp: f64) -> bool {
        registered_stamps(&self.out.text())
            .iter()
            .any(|s| s.parse::<f64>().is_ok_and(|t| (t - stamp).abs() < 1e-6))
    }

    /// Warnings printed so far (one per skipped cloud, and per problem in a registered one).
    pub fn warnings(&self) -> usize {
        self.err
            .text()
            .lines()
            .filter(|l| l.starts_with("warning:"))
            .count()
    }

    /// Waits until the node has matched at least `n` remote endpoints on `topic` (publishers
    /// of a topic it reads, subscribers of one it publishes); fails the test after [`HANG`].
    pub fn wait_matched(&self, topic: &str, n: usize) {
        let ok = wait_until(HANG, || self.watch.matched(topic) >= n);
        assert!(
            ok,
            "the node matched {} endpoints on {topic}, not {n}",
            self.watch.matched(topic)
        );
    }

    /// Waits until `n` poses are written (at most [`HANG`]), then stops the node.
    pub fn stop_after(self, n: usize) -> Stopped {
        wait_until(HANG, || self.registered() >= n);
        self.stop()
    }

    /// Stops the node and collects what it printed.
    pub fn stop(self) -> Stopped {
        self.stop.store(true, Ordering::SeqCst);
        let r = self.handle.join().expect("node thread");
        let (out, err) = (self.out.text(), self.err.text());
        let summary = r.unwrap_or_else(|e| panic!("node failed: {e}\n{out}\n{err}"));
        let poses = std::fs::read_to_string(&self.poses).unwrap_or_default();
        Stopped {
            summary,
            out,
            err,
            poses,
        }
    }
}

/// `kiss-odom run ARGS --out DIR` in-process; returns its `poses_kitti.txt`.
pub fn run_poses(args: &[&str], out: &Path) -> String {
    let mut argv: Vec<std::ffi::OsString> = vec!["kiss-odom".into(), "run".into()];
    argv.extend(args.iter().map(|a| a.into()));
    argv.extend(["--out".into(), out.as_os_str().to_owned(), "--quiet".into()]);
    let mut err = Vec::new();
    let code = kiss_odom::cli::main_with(argv, &mut err);
    assert_eq!(code, 0, "run failed: {}", String::from_utf8_lossy(&err));
    std::fs::read_to_string(out.join("poses_kitti.txt")).expect("poses_kitti.txt")
}

/// `kiss-odom ros2 --play PATH --domain D ARGS` in this thread, into `node`: the player sets
/// up its writers (and with `--lockstep` its odometry reader), waits until `node` has matched
/// them, then plays to the end. Its `--wait` (for a subscriber, for each cloud's odometry) is
/// [`HANG`] unless `args` give one. Returns what it printed.
pub fn play(node: &Node, path: &Path, domain: u16, args: &[&str]) -> String {
    let mut argv: Vec<String> = ["kiss-odom", "ros2", "--play"].map(String::from).into();
    argv.push(path.to_string_lossy().into_owned());
    argv.extend(["--domain".into(), domain.to_string()]);
    if !args.contains(&"--wait") {
        argv.extend(["--wait".into(), HANG.as_secs().to_string()]);
    }
    argv.extend(args.iter().map(|a| a.to_string()));
    let cli = Cli::try_parse_from(&argv).unwrap_or_else(|e| panic!("{argv:?}: {e}"));
    let Command::Ros2(ros2) = cli.command else {
        unreachable!("a ros2 command")
    };
    let opts = kiss_odom::ros2::play_options(&ros2).expect("--play");
    let (mut out, mut err) = (Vec::new(), Vec::new());
    let player = Player::new(&opts, &mut err).unwrap_or_else(|e| panic!("--play: {e:#}"));
    node.wait_matched(&opts.points_topic, 1);
    if let Some(topic) = &opts.lockstep {
        node.wait_matched(topic, 1);
    }
    if let (Some(read), Some((_, sent))) = (&node.imu_topic, &opts.imu) {
        if read == sent {
            node.wait_matched(read, 1);
        }
    }
    let played = player.play(&AtomicBool::new(false), &mut out, &mut err);
    let text = String::from_utf8_lossy(&out).into_owned();
    let err = String::from_utf8_lossy(&err);
    played.unwrap_or_else(|e| panic!("--play failed: {e:#}\n{text}{err}"));
    print!("{err}");
    text
}

/// The stamps of the clouds `--play` published, from its lines (`published K NAME stamp T`).
pub fn published_stamps(played: &str) -> Vec<f64> {
    played
        .lines()
        .filter(|l| l.starts_with("published "))
        .filter_map(|l| l.split_whitespace().nth(4)?.parse().ok())
        .collect()
}

/// The stamps (`sec.nanosec`) of the clouds a node registered, from its frame lines.
pub fn registered_stamps(out: &str) -> Vec<String> {
    out.lines()
        .filter(|l| l.starts_with("frame "))
        .filter_map(|l| l.split_whitespace().nth(3).map(String::from))
        .collect()
}
