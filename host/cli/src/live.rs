//! `kiss-odom live`: odometry from a sensor on the network, sweep by sweep.
//!
//! A receiving thread reads the socket into a bounded queue, so a frame in the core never
//! holds up the socket; a datagram that finds the queue full is dropped and counted (the
//! decoder also counts the packets it finds missing, per sweep in `frames.csv`). The packets
//! go through the same decoder as a recording and the sweeps through `run`'s frame loop, so
//! the outputs are `run`'s, a recording replayed without loss gives `run`'s very poses, and
//! SIGINT/SIGTERM end the run cleanly with every output written. Each pose is printed as a
//! TUM line when its sweep is done; `summary.json` has the time from a sweep's last packet to
//! its pose (`pose_latency_ms`).

use crate::args::{CommonArgs, CoreArgs, InputArgs, PipelineArgs, SensorArgs};
use crate::run::observe::{Observer, Seen};
use crate::run::viz::ViewArgs;
use crate::run::{FrameRow, RunArgs, RunOptions};
use anyhow::{anyhow, bail, Context, Result};
use kiss_odom_drive::Driver;
use kiss_odom_io::capture::frames::SweepFrames;
use kiss_odom_io::capture::pcap::Datagram;
use kiss_odom_io::capture::sweeps::{self, DatagramSource};
use kiss_odom_io::poses::{format_tum, TimedPose};
use kiss_odom_io::{Dataset, DatasetInfo, Format};
use kiss_odom_sensors::SweepEnd;
use std::io::Write;
use std::net::{SocketAddr, UdpSocket};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, SyncSender, TrySendError};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// Datagrams waiting for the decoder (about 4 s of an Ouster, 5 s of a Velodyne).
const QUEUE: usize = 4096;
/// Socket receive buffer asked for (the kernel caps it at `net.core.rmem_max`): a sweep of
/// packets, so none is lost while the machine is busy elsewhere.
const RECEIVE_BUFFER: usize = 8 << 20;

/// `kiss-odom live` arguments.
#[derive(Debug, clap::Args)]
pub struct LiveArgs {
    /// Address to listen on, e.g. 0.0.0.0:2368 (Velodyne) or 0.0.0.0:7502 (Ouster).
    #[arg(long)]
    pub udp: SocketAddr,
    /// End after this many seconds without a packet, once packets have come [default: run
    /// until SIGINT/SIGTERM]; without any packet in that time the run fails.
    #[arg(long)]
    pub idle_timeout: Option<f64>,
    /// Outputs and how the run goes, as `run`'s.
    #[command(flatten)]
    pub run: RunOptions,
    /// The sensor (its port is the one of `--udp`).
    #[command(flatten, next_help_heading = "Sensor")]
    pub sensor: SensorArgs,
    /// The pipeline's parameters.
    #[command(flatten, next_help_heading = "Pipeline")]
    pub pipeline: PipelineArgs,
    /// How the core runs.
    #[command(flatten, next_help_heading = "Core")]
    pub core: CoreArgs,
    /// Rerun recording and point-cloud exports.
    #[command(flatten)]
    pub view: ViewArgs,
}

/// The receiving thread's end of the socket.
struct Socket {
    name: String,
    queue: Receiver<Datagram>,
    dropped: Arc<AtomicU64>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<Result<()>>>,
    idle: Option<Duration>,
    last: Instant,
    received: bool,
    port: u16,
}

impl Socket {
    fn open(addr: SocketAddr, idle: Option<Duration>) -> Result<Self> {
        let name = format!("udp://{addr}");
        let socket = listen(addr).with_context(|| format!("{name}: cannot listen"))?;
        socket.set_read_timeout(Some(crate::interrupt::POLL))?;
        let port = socket.local_addr()?.port();
        let (tx, queue) = mpsc::sync_channel(QUEUE);
        let dropped = Arc::new(AtomicU64::new(0));
        let stop = Arc::new(AtomicBool::new(false));
        let (d, s) = (Arc::clone(&dropped), Arc::clone(&stop));
        let thread = std::thread::Builder::new()
            .name("kiss-odom-udp".into())
            .spawn(move || receive(&socket, port, &tx, &d, &s))?;
        Ok(Self {
            name,
            queue,
            dropped,
            stop,
            thread: Some(thread),
            idle,
            last: Instant::now(),
            received: false,
            port,
        })
    }

    /// The receiving thread's error, once it has ended.
    fn thread_error(&mut self) -> anyhow::Error {
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(Err(e))) => e.context(self.name.clone()),
            _ => anyhow!("{}: the receiving thread ended", self.name),
        }
    }
}

impl Drop for Socket {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// A UDP socket bound to `addr` with a large receive buffer.
fn listen(addr: SocketAddr) -> std::io::Result<UdpSocket> {
    use socket2::{Domain, Protocol, Socket as Raw, Type};
    let raw = Raw::new(Domain::for_address(addr), Type::DGRAM, Some(Protocol::UDP))?;
    raw.set_recv_buffer_size(RECEIVE_BUFFER)?;
    raw.bind(&addr.into())?;
    Ok(raw.into())
}

/// The receiving thread: datagrams into the queue until told to stop.
fn receive(
    socket: &UdpSocket,
    port: u16,
    tx: &SyncSender<Datagram>,
    dropped: &AtomicU64,
    stop: &AtomicBool,
) -> Result<()> {
    let mut buf = vec![0u8; 65536];
    while !stop.load(Ordering::Relaxed) {
        let (n, source) = match socket.recv_from(&mut buf) {
            Ok(r) => r,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                continue
            }
            Err(e) => return Err(e.into()),
        };
        let time_ns = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos() as u64);
        let d = Datagram {
            time_ns,
            source,
            port,
            payload: buf[..n].to_vec(),
        };
        match tx.try_send(d) {
            Ok(()) => {}
            Err(TrySendError::Full(_)) => {
                dropped.fetch_add(1, Ordering::Relaxed);
            }
            Err(TrySendError::Disconnected(_)) => break,
        }
    }
    Ok(())
}

impl DatagramSource for Socket {
    fn next_datagram(&mut self) -> Result<Option<Datagram>> {
        loop {
            // Before every datagram, not only when the queue runs dry: packets that keep
            // coming must not hold off a signal.
            if crate::interrupt::requested().is_some() {
                return Ok(None);
            }
            match self.queue.recv_timeout(crate::interrupt::POLL) {
                Ok(d) => {
                    self.last = Instant::now();
                    self.received = true;
                    return Ok(Some(d));
                }
                Err(RecvTimeoutError::Disconnected) => return Err(self.thread_error()),
                Err(RecvTimeoutError::Timeout) => {}
            }
            match self.idle {
                Some(idle) if self.last.elapsed() >= idle => {
                    if self.received {
                        return Ok(None);
                    }
                    bail!(
                        "{}: no packets in {:.1} s (is the sensor sending to this address?)",
                        self.name,
                        idle.as_secs_f64()
                    );
                }
                _ => {}
            }
        }
    }
}

/// Watches `run`'s loop for `live`: prints each pose as a TUM line as its sweep completes
/// (flushed, for a pipe) and measures the time since the sweep's last packet (for sweeps the
/// sensor's data closed; one the end of the stream closed was not done when its last packet
/// came).
struct Poses;

impl Observer for Poses {
    fn frame(&mut self, seen: &Seen<'_>, row: &mut FrameRow) -> Result<()> {
        let time = seen.time.unwrap_or(seen.outcome.meta.index as f64);
        let line = format_tum(&[TimedPose {
            time,
            pose: seen.pose,
        }]);
        let mut out = std::io::stdout().lock();
        let _ = out.write_all(line.as_bytes()).and_then(|()| out.flush());
        if let Some(s) = seen.sweep.filter(|s| s.stats.end != SweepEnd::Finished) {
            let now = SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos() as u64);
            // Microseconds, as frames.csv's core latency.
            let ms = (now.saturating_sub(s.last_capture_ns) as f64 * 1e-3).round() / 1e3;
            row.pose_latency_ms = Some(ms);
        }
        Ok(())
    }

    fn finish(&mut self, _: &Driver) -> Result<Vec<String>> {
        Ok(Vec::new())
    }
}

/// Runs `kiss-odom live`.
pub fn execute(args: &LiveArgs, err: &mut dyn Write) -> Result<i32> {
    // From `--set` or `--config` alike: the resolved settings, not the command line's text.
    if crate::args::settings(&args.pipeline, &args.core, None)?
        .input
        .port
        .is_some()
    {
        bail!("live listens on the port of --udp; input.port is for recordings");
    }
    crate::args::ImuMode::recording_only(args.pipeline.imu.as_ref(), "live")?;
    let idle = match args.idle_timeout {
        Some(s) if s > 0.0 => Some(crate::interrupt::seconds(s)),
        Some(s) => bail!("--idle-timeout must be a positive number of seconds, not {s}"),
        None => None,
    };
    let run = RunArgs {
        path: PathBuf::from(format!("udp://{}", args.udp)),
        run: args.run.clone(),
        common: CommonArgs {
            input: InputArgs {
                format: Format::Pcap,
                frames: None,
                topic: None,
                sequence: None,
                sensor: args.sensor.clone(),
            },
            pipeline: args.pipeline.clone(),
            core: args.core.clone(),
        },
        view: args.view.clone(),
    };
    let mut dropped = None;
    let code = crate::run::execute_on(
        &run,
        |opts| {
            let socket = Socket::open(args.udp, idle)?;
            dropped = Some(Arc::clone(&socket.dropped));
            let name = socket.name.clone();
            let mut sensor = opts.sensor.clone();
            sensor.port = Some(socket.port);
            let sweeps = sweeps::decode(Path::new(&name), Box::new(socket), &sensor)?;
            Ok(Dataset {
                frames: Box::new(SweepFrames::new(sweeps, &name, opts.scan_points)),
                info: DatasetInfo {
                    format: Some(Format::Pcap),
                    ..DatasetInfo::default()
                },
            })
        },
        vec![Box::new(Poses)],
        err,
    )?;
    let dropped = dropped.map_or(0, |d| d.load(Ordering::Relaxed));
    if dropped > 0 {
        writeln!(
            err,
            "warning: {dropped} datagram(s) dropped: the decoder fell {QUEUE} behind"
        )?;
    }
    Ok(code)
}
