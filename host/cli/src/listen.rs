//! `kiss-odom listen-poses`: the poses a receiver that runs the odometry itself (the `embedded/`
//! network firmware) sends, one UDP datagram per sweep ([`kiss_odom_sensors::pose_datagram`]),
//! collected into `run`'s outputs.
//!
//! Poses are kept by sweep index, so datagrams that arrive out of order are put back in order;
//! a second datagram for a sweep is counted and ignored; indices skipped between the first and
//! the last sweep received are the pose datagrams lost on the way, named in `summary.json`.
//! Bytes that are not a pose datagram are counted by reason and skipped. `poses_kitti.txt` is
//! written by `run`'s writer, so it compares byte for byte with a `run` of the same poses.

mod outputs;
mod received;

use anyhow::{bail, Context, Result};
use kiss_odom_sensors::pose_datagram::field;
use outputs::{Summary, OUTPUTS};
use received::Received;
use std::io::{ErrorKind, Write};
use std::net::{SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::time::Instant;

/// `kiss-odom listen-poses` arguments.
#[derive(Debug, clap::Args)]
pub struct ListenArgs {
    /// Address to listen on, e.g. 0.0.0.0:9000.
    #[arg(long)]
    pub bind: SocketAddr,
    /// Output folder (created if missing) for poses_kitti.txt, frames.csv and summary.json;
    /// a file of those names that no earlier command wrote refuses the command.
    #[arg(long)]
    pub out: PathBuf,
    /// Stop once this many sweeps have come [default: at the idle timeout or SIGINT/SIGTERM].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub sweeps: Option<u64>,
    /// Stop after this many seconds without a datagram; without any in that time, fail.
    #[arg(long, default_value_t = 10.0)]
    pub idle: f64,
    /// No summary line.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Runs `kiss-odom listen-poses`.
pub fn execute(args: &ListenArgs, err: &mut dyn Write) -> Result<i32> {
    if args.idle.is_nan() || args.idle <= 0.0 {
        bail!(
            "--idle must be a positive number of seconds, not {}",
            args.idle
        );
    }
    let idle = crate::interrupt::seconds(args.idle);
    // Only the files an earlier command wrote there are replaced; any other refuses this one.
    let earlier = kiss_odom_io::write::outputs::Earlier::check(&args.out, &OUTPUTS)?;
    let name = format!("udp://{}", args.bind);
    let socket = UdpSocket::bind(args.bind).with_context(|| format!("{name}: cannot listen"))?;
    socket.set_read_timeout(Some(crate::interrupt::POLL))?;
    let bound = socket.local_addr()?;
    earlier.remove()?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("{}: cannot create output folder", args.out.display()))?;
    let mut received = Received::default();
    // One byte more than a datagram: anything longer arrives cut, still the wrong length.
    let mut buf = [0u8; field::LEN + 1];
    let mut last = Instant::now();
    let signal = loop {
        if let Some(sig) = crate::interrupt::requested() {
            break Some(sig);
        }
        if args
            .sweeps
            .is_some_and(|n| received.sweeps.len() as u64 >= n)
        {
            break None;
        }
        match socket.recv_from(&mut buf) {
            Ok((n, from)) => {
                last = Instant::now();
                received.take(&buf[..n], from);
            }
            // A signal cuts a receive with a timeout short (EINTR) even with SA_RESTART.
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                if last.elapsed() >= idle {
                    break None;
                }
            }
            Err(e) => return Err(e).with_context(|| format!("{name}: cannot receive")),
        }
    };
    let mut summary = Summary::of(bound, &received, signal.is_some());
    outputs::write(&args.out, &mut summary, &received)?;
    for w in &summary.warned {
        writeln!(err, "warning: {w}")?;
    }
    match received.datagrams {
        _ if signal.is_some() || !received.sweeps.is_empty() => {}
        0 => bail!(
            "{name}: no datagram in {} s (is the receiver sending to this address?)",
            args.idle
        ),
        n => bail!("{name}: {n} datagram(s), none a pose datagram (see summary.json)"),
    }
    if !args.quiet {
        writeln!(err, "{}", summary.line())?;
    }
    Ok(signal.map_or(0, crate::interrupt::exit_status))
}
