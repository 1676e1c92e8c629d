//! Shared helpers for the workspace-level tests in `tests/tests/`: running `kiss-odom` in
//! process on a dataset and reading back what it wrote, and waiting for what another thread or
//! process does (a condition polled against a deadline, never a fixed sleep).

use std::ffi::OsString;
use std::net::UdpSocket;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus};
use std::time::{Duration, Instant};

/// The repository root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Copies the folder `from` (files and subfolders) to `to`.
pub fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_tree(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target).unwrap();
        }
    }
}

/// A copy of `fixtures/kitti-05-reduced` (10 real KITTI scans, calib, times, ground truth) at
/// `dir/name`, to break.
pub fn kitti_copy(dir: &Path, name: &str) -> PathBuf {
    let to = dir.join(name);
    copy_tree(&repo().join("fixtures/kitti-05-reduced"), &to);
    to
}

/// The real sensor recordings beside the repository (`../shared/data/sensors`).
pub fn sensor_data() -> PathBuf {
    repo().join("../shared/data/sensors")
}

/// Whether `file` (relative to [`sensor_data`]) is there; prints SKIP otherwise.
pub fn have_sensor_file(file: &str) -> bool {
    let ok = sensor_data().join(file).is_file();
    if !ok {
        println!("SKIP: {} not found", sensor_data().join(file).display());
    }
    ok
}

/// Adds a second VLP-16 on the same port to a VLP-16 recording's datagrams: each of its data
/// packets (port 2368, 1206 bytes) again, 0.3 ms later, from 192.168.1.202; in time order.
pub fn add_second_vlp16(d: &mut Vec<kiss_odom_io::capture::pcap::Datagram>) {
    let second: Vec<_> = d
        .iter()
        .filter(|p| p.port == 2368 && p.payload.len() == 1206)
        .map(|p| kiss_odom_io::capture::pcap::Datagram {
            time_ns: p.time_ns + 300_000,
            source: "192.168.1.202:2368".parse().unwrap(),
            ..p.clone()
        })
        .collect();
    d.extend(second);
    d.sort_by_key(|p| p.time_ns);
}

/// What one `kiss-odom` command did.
pub struct Run {
    /// Exit status.
    pub code: i32,
    /// Everything written to stderr.
    pub stderr: String,
    /// The output folder (for `run`).
    pub out: PathBuf,
}

/// The message of a panic payload.
pub fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "(non-string panic payload)".into())
}

/// `kiss-odom ARGS...` in process (`kiss-odom-dev` for its commands, `bench` and
/// `crosscheck`); a panic fails the test naming the command.
pub fn kiss_odom(args: &[OsString], out: &Path) -> Run {
    let developer = matches!(
        args.first().and_then(|a| a.to_str()),
        Some("bench" | "crosscheck")
    );
    let name = if developer {
        "kiss-odom-dev"
    } else {
        "kiss-odom"
    };
    let mut argv: Vec<OsString> = vec![name.into()];
    argv.extend(args.iter().cloned());
    let shown: Vec<String> = argv.iter().map(|a| a.to_string_lossy().into()).collect();
    let mut err = Vec::new();
    let code = catch_unwind(AssertUnwindSafe(|| {
        if developer {
            kiss_odom::dev::main_with(argv, &mut err)
        } else {
            kiss_odom::cli::main_with(argv, &mut err)
        }
    }))
    .unwrap_or_else(|p| panic!("`{}` panicked: {}", shown.join(" "), panic_text(p.as_ref())));
    Run {
        code,
        stderr: String::from_utf8_lossy(&err).into_owned(),
        out: out.to_path_buf(),
    }
}

/// `kiss-odom simulate --out OUT EXTRA...` in process; panics with its stderr if it fails.
pub fn simulate(out: &Path, extra: &[&str]) {
    let mut args: Vec<OsString> = vec!["simulate".into(), "--out".into(), out.into()];
    args.extend(extra.iter().map(OsString::from));
    let r = kiss_odom(&args, out);
    assert_eq!(r.code, 0, "{}", r.stderr);
}

/// `kiss-odom run INPUT --out OUT --quiet EXTRA...` in process.
pub fn run(input: &Path, out: &Path, extra: &[&str]) -> Run {
    let mut args: Vec<OsString> = vec![
        "run".into(),
        input.into(),
        "--out".into(),
        out.into(),
        "--quiet".into(),
    ];
    args.extend(extra.iter().map(OsString::from));
    kiss_odom(&args, out)
}

impl Run {
    /// `summary.json`.
    pub fn summary(&self) -> serde_json::Value {
        let path = self.out.join("summary.json");
        let text = std::fs::read_to_string(&path)
            .unwrap_or_else(|e| panic!("{}: {e}\nstderr:\n{}", path.display(), self.stderr));
        serde_json::from_str(&text).expect("summary.json is JSON")
    }

    /// A number of `summary.json` (`a.b` for nested keys); NaN when absent or null.
    pub fn number(&self, key: &str) -> f64 {
        let s = self.summary();
        key.split('.')
            .fold(&s, |v, k| &v[k])
            .as_f64()
            .unwrap_or(f64::NAN)
    }

    /// The lines of an output file.
    pub fn lines(&self, name: &str) -> Vec<String> {
        let path = self.out.join(name);
        std::fs::read_to_string(&path)
            .unwrap_or_else(|e| panic!("{}: {e}\nstderr:\n{}", path.display(), self.stderr))
            .lines()
            .map(String::from)
            .collect()
    }

    /// The time column of `poses_tum.txt` (its `#` header line left out).
    pub fn tum_times(&self) -> Vec<f64> {
        self.lines("poses_tum.txt")
            .iter()
            .filter(|l| !l.starts_with('#'))
            .map(|l| l.split(' ').next().unwrap().parse().unwrap())
            .collect()
    }

    /// A column of `frames.csv`.
    pub fn column(&self, name: &str) -> Vec<String> {
        let lines = self.lines("frames.csv");
        let header: Vec<&str> = lines[0].split(',').collect();
        let col = header
            .iter()
            .position(|c| *c == name)
            .unwrap_or_else(|| panic!("frames.csv has no column {name}: {header:?}"));
        lines[1..]
            .iter()
            .map(|l| l.split(',').nth(col).unwrap_or_default().to_string())
            .collect()
    }

    /// The `warning: ` lines of stderr.
    pub fn warnings(&self) -> Vec<&str> {
        self.stderr
            .lines()
            .filter(|l| l.starts_with("warning: "))
            .collect()
    }

    /// The one warning that contains every one of `needles`; fails showing stderr otherwise.
    pub fn warning_with(&self, needles: &[&str]) -> &str {
        let hits: Vec<&str> = self
            .warnings()
            .into_iter()
            .filter(|w| needles.iter().all(|n| w.contains(n)))
            .collect();
        assert_eq!(
            hits.len(),
            1,
            "one warning containing {needles:?}; stderr:\n{}",
            self.stderr
        );
        hits[0]
    }

    /// Exit 0; fails showing stderr otherwise.
    pub fn ok(&self) -> &Self {
        assert_eq!(self.code, 0, "exit status; stderr:\n{}", self.stderr);
        self
    }

    /// Exit 1 with an `error: ` line containing every one of `needles`; returns the line.
    pub fn failed_with(&self, needles: &[&str]) -> &str {
        assert_eq!(self.code, 1, "exit status; stderr:\n{}", self.stderr);
        let line = self
            .stderr
            .lines()
            .find(|l| l.starts_with("error: "))
            .unwrap_or_else(|| panic!("no error line; stderr:\n{}", self.stderr));
        for n in needles {
            assert!(line.contains(n), "the error names {n:?}: {line}");
        }
        line
    }
}

// ------------------------------------------------------------------------------------------
// Waiting for another thread or process

/// How often [`wait_until`] looks.
pub const POLL: Duration = Duration::from_millis(5);

/// A deadline for what another process or thread must do (bind a socket, match a DDS
/// endpoint, register a cloud, exit): minutes, for a loaded machine. A hang guard, never a
/// speed check: every wait ends as soon as its condition holds.
pub const HANG: Duration = Duration::from_secs(120);

/// Polls `ok` every [`POLL`] until it holds or `limit` has passed; returns whether it held.
pub fn wait_until(limit: Duration, mut ok: impl FnMut() -> bool) -> bool {
    let start = Instant::now();
    loop {
        if ok() {
            return true;
        }
        if start.elapsed() >= limit {
            return false;
        }
        std::thread::sleep(POLL);
    }
}

/// Waits for `child` (named `what` in the failure) to exit; kills it and fails the test if it
/// is still running after `limit`.
pub fn wait_exit(child: &mut Child, what: &str, limit: Duration) -> ExitStatus {
    let mut status = None;
    let ended = wait_until(limit, || {
        status = child.try_wait().unwrap();
        status.is_some()
    });
    if !ended {
        let _ = child.kill();
        let _ = child.wait();
        panic!("{what} still running after {limit:?}");
    }
    status.unwrap()
}

/// Sends `signal` (a name: `INT`, `STOP`...) to `child`.
pub fn signal(child: &Child, signal: &str) {
    let ok = Command::new("kill")
        .args([format!("-{signal}"), child.id().to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok, "kill -{signal} {}", child.id());
}

/// Bytes waiting on the UDP socket bound to the loopback address `addr` (`127.0.0.1:PORT`),
/// as `/proc/net/udp` shows them (`rx_queue`): what its owner has not read yet. `None` when no
/// such socket is open (or not on Linux).
pub fn udp_queued(addr: &str) -> Option<u64> {
    let port: u16 = addr.rsplit_once(':')?.1.parse().ok()?;
    let local = format!("0100007F:{port:04X}");
    let table = std::fs::read_to_string("/proc/net/udp").ok()?;
    table.lines().skip(1).find_map(|line| {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.get(1) != Some(&local.as_str()) {
            return None;
        }
        u64::from_str_radix(f.get(4)?.split_once(':')?.1, 16).ok()
    })
}

/// Sends `datagrams` from `tx` to `addr`, where `child` listens, so that they reach it in the
/// order sent and all before it reads the first: `child` is stopped (SIGSTOP) meanwhile, each
/// datagram goes once the one before is seen queued on its socket, and then `child` goes on
/// (SIGCONT, also if this fails).
pub fn send_in_order(child: &Child, tx: &UdpSocket, addr: &str, datagrams: &[&[u8]]) {
    struct Resume<'a>(&'a Child);
    impl Drop for Resume<'_> {
        fn drop(&mut self) {
            signal(self.0, "CONT");
        }
    }
    signal(child, "STOP");
    let _resume = Resume(child);
    // A signal is delivered, not obeyed on the spot: wait until the child is stopped.
    let stat = format!("/proc/{}/stat", child.id());
    let state = || {
        std::fs::read_to_string(&stat)
            .ok()?
            .rsplit_once(") ")?
            .1
            .chars()
            .next()
    };
    assert!(
        wait_until(HANG, || state() == Some('T')),
        "the listener never stopped"
    );
    for (k, d) in datagrams.iter().enumerate() {
        let before = udp_queued(addr).expect("the listener's socket");
        tx.send_to(d, addr).unwrap();
        let queued = wait_until(HANG, || udp_queued(addr).is_some_and(|q| q > before));
        assert!(queued, "datagram {k} never reached {addr}");
    }
}

/// Waits until the owner of the UDP socket at `addr` has read everything queued on it.
pub fn wait_read(addr: &str) {
    let read = wait_until(HANG, || udp_queued(addr) == Some(0));
    assert!(read, "{addr}: {:?} bytes still unread", udp_queued(addr));
}
