//! The network firmware: a VLP-16's UDP packets in over Ethernet, a pose datagram out per sweep.
//!
//! ```text
//! LAN9118 --IRQ--> ring --> smoltcp, UDP :2368 --> velodyne::Decoder --> sweep buffer
//!                                                                            |
//! host <-- UDP pose datagram <-- smoltcp <-- Odometry::register_frame <------+
//! ```
//!
//! Each sweep is registered whole, with its own time span, as `kiss-odom run` registers the
//! same recording (`--set capacities=tiny --set runtime.scalar=f32 --set runtime.map_storage=quantized`), so the poses
//! can be compared bit for bit. The sweep buffer (`scan_points` points, 640 KB) is the price;
//! the `packets` profile shows the streamed alternative, which needs none but deskews each
//! sweep with the previous sweep's span.
//!
//! Only the first sender of a datagram of the sensor's length is decoded. Datagrams of another length, from another
//! sender, refused by the decoder or dropped at a full ring are counted and sent with every
//! pose. A sweep the sensor never ends (it stopped, or its last packets were lost) is ended
//! after [`IDLE`] of silence: a lost packet is a counted gap, never a stall.

mod device;
mod lan9118;
mod link;
mod ring;

use crate::frames;
use crate::profile::{kiss_frame_mark, Scalar, CAPS, EXIT_CONFIG_ERROR};
use device::{Nic, RING};
use kiss_odom_core::{widen_pose, FrameError, FrameReport, Odometry, PointCodec, Storage};
use kiss_odom_sensors::pose_datagram::{field, Counters, Link, PoseDatagram};
use kiss_odom_sensors::velodyne::{self, Decoder};
use kiss_odom_sensors::{Chunk, Decode, Pushed, SweepSink, SweepStart, SweepStats};
use link::{Clock, Net, Next};
use ring::SLOT;
use smoltcp::iface::{Config, Interface, SocketSet};
use smoltcp::socket::udp;
use smoltcp::time::Duration;
use smoltcp::wire::{EthernetAddress, IpAddress, IpCidr, Ipv4Address};
use static_cell::ConstStaticCell;

/// This board's address on QEMU's user network.
const OWN: Ipv4Address = Ipv4Address::new(10, 0, 2, 15);
/// QEMU's user-network gateway, which is the host's loopback.
const GATEWAY: Ipv4Address = Ipv4Address::new(10, 0, 2, 2);
/// The sensor's data port.
const SENSOR_PORT: u16 = 2368;
/// A VLP-16 data packet.
const PACKET_LEN: usize = velodyne::wire::field::LEN;
/// Silence that ends an open sweep.
const IDLE: Duration = Duration::from_secs(1);
/// The longest the last poses may wait for the network (ARP) before the program stops.
const FLUSH: Duration = Duration::from_secs(3);
/// Datagrams the socket holds each way (the ring in front of it holds the backlog).
const SOCKET_SLOTS: usize = 4;

/// The controller's interrupt: frames into the ring.
pub fn on_irq() {
    lan9118::drain_into(&RING);
}

/// The controller's interrupt line.
pub const IRQ: u16 = lan9118::IRQ;

/// One sweep's points, as `run` hands them to the core: the first `scan_points`, in order.
struct SweepBuf {
    xyz: [[Scalar; 3]; CAPS.scan_points],
    times: [f64; CAPS.scan_points],
}

static SWEEP: ConstStaticCell<SweepBuf> = ConstStaticCell::new(SweepBuf {
    xyz: [[0.0; 3]; CAPS.scan_points],
    times: [0.0; CAPS.scan_points],
});

/// The decoder's sink: fills the sweep buffer.
struct Collect<'a> {
    buf: &'a mut SweepBuf,
    n: usize,
    open: bool,
    stats: Option<SweepStats>,
}

impl SweepSink for Collect<'_> {
    fn begin_sweep(&mut self, _: &SweepStart) {
        self.open = true;
    }
    fn points(&mut self, c: Chunk<'_>) {
        for (p, &t) in c.xyz.iter().zip(c.times) {
            let slot = self
                .buf
                .xyz
                .get_mut(self.n)
                .zip(self.buf.times.get_mut(self.n));
            if let Some((x, tt)) = slot {
                *x = p.map(|v| v as Scalar);
                *tt = t;
                self.n += 1;
            }
        }
    }
    fn end_sweep(&mut self, stats: &SweepStats) {
        self.stats = Some(*stats);
    }
}

/// The VLP-16 decoder, sweeps cut at azimuth 0 (`kiss-odom run input.cut_angle 0`).
fn decoder() -> Option<Decoder> {
    Decoder::new(velodyne::Config {
        model: Some(velodyne::Model::Vlp16),
        calibration: None,
        cut_angle_deg: Some(0.0),
    })
    .ok()
}

/// Starts the 100 Hz tick that wakes the loop to keep time, and the controller's interrupt.
fn start_interrupts() {
    let Some(mut p) = cortex_m::Peripherals::take() else {
        return;
    };
    // QEMU's MPS2 core clock is 25 MHz.
    p.SYST
        .set_clock_source(cortex_m::peripheral::syst::SystClkSource::Core);
    p.SYST.set_reload(250_000 - 1);
    p.SYST.clear_current();
    p.SYST.enable_interrupt();
    p.SYST.enable_counter();
    // SAFETY: the handler touches only the ring, under a critical section, which unmasking
    // cannot break.
    unsafe { cortex_m::peripheral::NVIC::unmask(EthIrq) };
}

#[derive(Clone, Copy)]
struct EthIrq;

// SAFETY: 13 is a device interrupt that exists on the MPS2 boards' NVIC: the LAN9118's line.
unsafe impl cortex_m::interrupt::InterruptNumber for EthIrq {
    fn number(self) -> u16 {
        lan9118::IRQ
    }
}

/// Receives, registers and answers sweeps until the port falls silent (the program's end
/// under `net.sh`; a deployed receiver would loop for ever). Returns the exit status on error.
/// Instructions are counted outside the guest (`net.sh`), so `insns` has nothing to give.
pub fn run<P: PointCodec<Scalar>, S: Storage>(
    odom: &mut Odometry<Scalar, P, S>,
    _insns: fn() -> Option<u64>,
    _counter: &str,
) -> Result<Option<u64>, i32> {
    let (Some(mut dec), Ok(hw)) = (decoder(), lan9118::Lan9118::bring_up()) else {
        out!("error: no LAN9118 (start QEMU with -nic user,model=lan9118)");
        return Err(EXIT_CONFIG_ERROR);
    };
    let Some(buf) = SWEEP.try_take() else {
        return Err(EXIT_CONFIG_ERROR);
    };
    let mac = hw.mac();
    let mut nic = Nic::new(hw);
    let mut clock = Clock::default();
    let now = clock.now(&nic);
    let mut iface = Interface::new(Config::new(EthernetAddress(mac).into()), &mut nic, now);
    iface.update_ip_addrs(|a| {
        let _ = a.push(IpCidr::new(IpAddress::Ipv4(OWN), 24));
    });
    let _ = iface.routes_mut().add_default_ipv4_route(GATEWAY);
    let mut rx_meta = [udp::PacketMetadata::EMPTY; SOCKET_SLOTS];
    let mut rx_data = [0u8; SOCKET_SLOTS * SLOT];
    let mut tx_meta = [udp::PacketMetadata::EMPTY; SOCKET_SLOTS];
    let mut tx_data = [0u8; SOCKET_SLOTS * field::LEN];
    let mut socket = udp::Socket::new(
        udp::PacketBuffer::new(&mut rx_meta[..], &mut rx_data[..]),
        udp::PacketBuffer::new(&mut tx_meta[..], &mut tx_data[..]),
    );
    if socket.bind(SENSOR_PORT).is_err() {
        return Err(EXIT_CONFIG_ERROR);
    }
    let mut storage = [smoltcp::iface::SocketStorage::EMPTY; 1];
    let mut sockets = SocketSet::new(&mut storage[..]);
    let udp = sockets.add(socket);
    let mut net = Net {
        nic,
        iface,
        sockets,
        udp,
        clock,
        sensor: None,
        counters: Counters::default(),
    };
    start_interrupts();
    out!(
        "net mac={:02x?} own={} port={} poses_to={}:{} ring_slots={} ring_bytes={} sweep_bytes={} socket_bytes={}",
        mac,
        OWN,
        SENSOR_PORT,
        GATEWAY,
        frames::POSE_PORT,
        ring::SLOTS,
        core::mem::size_of::<ring::Ring>(),
        core::mem::size_of::<SweepBuf>(),
        SOCKET_SLOTS * (SLOT + field::LEN)
    );

    let mut packet = [0u8; SLOT];
    let mut again: Option<usize> = None;
    let mut sweep = 0u32;
    loop {
        let before = net.counters();
        let mut sink = Collect {
            buf: &mut *buf,
            n: 0,
            open: false,
            stats: None,
        };
        let mut idle = false;
        if let Some(len) = again.take() {
            let _ = dec.push(&packet[..len], &mut sink);
        }
        while sink.stats.is_none() {
            match net.next(&mut packet, sink.open || net.sensor.is_some()) {
                Next::Packet(len) => {
                    if dec.push(&packet[..len], &mut sink) == Ok(Pushed::Again) {
                        if sink.stats.is_some() {
                            again = Some(len);
                        } else {
                            let _ = dec.push(&packet[..len], &mut sink);
                        }
                    }
                }
                Next::Idle => {
                    idle = true;
                    if sink.open {
                        dec.finish(&mut sink);
                    }
                    break;
                }
            }
        }
        let Some(stats) = sink.stats else {
            // Silence with no sweep open: the sender has stopped.
            break;
        };
        let n = sink.n;
        kiss_frame_mark();
        let result = odom.register_frame(&buf.xyz[..n], Some(&buf.times[..n]));
        kiss_frame_mark();
        let d = datagram(odom, &result, sweep, n, &stats, idle, &before, &mut net);
        out!(
            "input {} packets={} points={} lost={} bad={} idle={}",
            sweep,
            stats.packets,
            n,
            stats.lost_packets,
            refused(&stats),
            idle
        );
        if let Ok(r) = &result {
            out!("{}", crate::lines::FrameLine(sweep as usize, n, r));
            out!(
                "{}",
                crate::lines::PoseLine(sweep as usize, &widen_pose(&r.pose))
            );
        } else {
            out!("error sweep {}: {:?}", sweep, result.as_ref().err());
        }
        net.send(&d);
        sweep += 1;
        if idle {
            break;
        }
    }
    net.flush();
    let high = critical_section::with(|cs| RING.borrow_ref(cs).high_water());
    out!(
        "net sweeps={} {} ring_high_water={}",
        sweep,
        Named(&net.counters()),
        high
    );
    Ok(None)
}

/// Packets the decoder refused in a sweep: corrupt, late, or another sensor's.
fn refused(stats: &SweepStats) -> u32 {
    stats.bad_packets + stats.out_of_order + stats.other_sensor
}

/// The counters as `name=value` words, in the datagram's order.
struct Named<'a>(&'a Counters);

impl core::fmt::Display for Named<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        for (k, (name, n)) in self.0.named().iter().enumerate() {
            write!(f, "{}{name}={n}", if k > 0 { " " } else { "" })?;
        }
        Ok(())
    }
}

/// The sweep's pose datagram; counts the sweep's losses and a refused sweep.
#[allow(clippy::too_many_arguments)]
fn datagram<P: PointCodec<Scalar>, S: Storage>(
    odom: &mut Odometry<Scalar, P, S>,
    result: &Result<FrameReport<Scalar>, FrameError>,
    sweep: u32,
    points: usize,
    stats: &SweepStats,
    idle: bool,
    before: &Counters,
    net: &mut Net<'_>,
) -> PoseDatagram {
    let (pose, status, iterations) = match result {
        Ok(r) => (r.pose, r.status.bits(), r.iterations),
        Err(e) => {
            net.counters.frame_errors += 1;
            // An empty sweep advances on the motion model, as `run` does.
            let pose = if *e == FrameError::EmptyScan {
                odom.skip_frame()
            } else {
                *odom.pose()
            };
            (pose, 0, 0)
        }
    };
    net.counters.lost += stats.lost_packets;
    net.counters.bad += refused(stats);
    let now = net.counters();
    let bits = [
        (result.is_err(), Link::FrameError),
        (stats.lost_packets > 0, Link::Gap),
        (idle, Link::Idle),
        (now.foreign > before.foreign, Link::Foreign),
        (now.wrong_size > before.wrong_size, Link::WrongSize),
        (now.overflow > before.overflow, Link::Overflow),
        (now.bad > before.bad, Link::Bad),
    ];
    let link = bits
        .iter()
        .filter(|(on, _)| *on)
        .fold(0u16, |l, (_, b)| l | *b as u16);
    // As the host widens every f32 pose it writes, so the bits are `run`'s.
    let m = widen_pose(&pose).to_homogeneous();
    PoseDatagram {
        link,
        sweep,
        points: points as u32,
        start_ns: stats.start_ns,
        pose: core::array::from_fn(|k| m[(k / 4, k % 4)]),
        status,
        iterations: iterations.min(u32::from(u16::MAX)) as u16,
        sweep_lost: stats.lost_packets,
        counters: now,
    }
}
