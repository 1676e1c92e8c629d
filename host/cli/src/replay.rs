//! `kiss-odom replay`: a sensor recording sent as UDP at its recorded pace, so that `live`
//! (and any other receiver) can be tested without the sensor.
//!
//! Each datagram to the sensor's data port leaves when its capture time, measured from the
//! first one and divided by `--rate`, has elapsed; a sender that falls behind sends at once
//! and catches up (the pace is kept on average, never by skipping). SIGINT/SIGTERM stop
//! between datagrams or during a wait, however long, with `128 + signal`; a capture damaged
//! in the middle is sent up to the damage and then reported as the error.

use anyhow::{bail, Context, Result};
use kiss_odom_io::capture::pcap;
use std::collections::BTreeMap;
use std::net::{SocketAddr, UdpSocket};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `kiss-odom replay` arguments.
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// The recording (.pcap or .pcapng).
    pub path: PathBuf,
    /// Where to send the datagrams, e.g. 127.0.0.1:2368.
    #[arg(long)]
    pub to: SocketAddr,
    /// Pace: 1 as recorded, 5 five times faster.
    #[arg(long, default_value_t = 1.0)]
    pub rate: f64,
    /// Send only the datagrams to this UDP port [default: the port most datagrams go to, the
    /// sensor's data port].
    #[arg(long)]
    pub port: Option<u16>,
    /// Nothing printed.
    #[arg(long, short)]
    pub quiet: bool,
}

/// The port most datagrams of the capture go to (up to any damage, which sending reports).
fn busiest_port(path: &Path) -> Result<u16> {
    let mut counts: BTreeMap<u16, u64> = BTreeMap::new();
    for d in pcap::open(path)?.map_while(Result::ok) {
        *counts.entry(d.port).or_insert(0) += 1;
    }
    match counts.iter().max_by_key(|(_, n)| **n) {
        Some((&port, _)) => Ok(port),
        None => bail!("{}: no UDP datagrams to replay", path.display()),
    }
}

/// Runs `kiss-odom replay`.
pub fn execute(args: &ReplayArgs) -> Result<i32> {
    if !(args.rate.is_finite() && args.rate > 0.0) {
        bail!("--rate must be a positive number, not {}", args.rate);
    }
    let port = match args.port {
        Some(p) => p,
        None => busiest_port(&args.path)?,
    };
    let local: SocketAddr = if args.to.is_ipv4() {
        "0.0.0.0:0".parse()?
    } else {
        "[::]:0".parse()?
    };
    let socket = UdpSocket::bind(local).context("cannot open a UDP socket")?;
    let mut capture = pcap::open(&args.path)?;
    let (mut sent, mut bytes) = (0u64, 0u64);
    let mut first: Option<(u64, Instant)> = None;
    let interrupted = loop {
        let Some(d) = capture.next_datagram()? else {
            break None;
        };
        if d.port != port {
            continue;
        }
        let (t0, start) = *first.get_or_insert((d.time_ns, Instant::now()));
        // A tiny rate or a long gap in the recording is a long wait, which a signal ends.
        let due = crate::interrupt::seconds(d.time_ns.saturating_sub(t0) as f64 * 1e-9 / args.rate);
        let wait = due.checked_sub(start.elapsed()).unwrap_or_default();
        if let Some(sig) = crate::interrupt::sleep(wait) {
            break Some(sig);
        }
        socket
            .send_to(&d.payload, args.to)
            .with_context(|| format!("{}: cannot send to {}", args.path.display(), args.to))?;
        sent += 1;
        bytes += d.payload.len() as u64;
    };
    if let Some(sig) = interrupted {
        eprintln!("interrupted by signal {sig} after {sent} datagrams");
        return Ok(crate::interrupt::exit_status(sig));
    }
    if sent == 0 {
        bail!("{}: no datagrams to port {port}", args.path.display());
    }
    if !args.quiet {
        let secs = first.map_or(0.0, |(_, s)| s.elapsed().as_secs_f64());
        println!(
            "sent {sent} datagrams ({bytes} bytes, port {port} of the recording) to {} in {secs:.2} s",
            args.to
        );
    }
    Ok(0)
}
