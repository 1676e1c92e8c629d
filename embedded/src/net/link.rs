//! The network side of the firmware: the stack's one socket on the sensor's port, the clock
//! smoltcp keeps time by, and the counts of what came in and what was refused.

use super::device::{Nic, RING};
use super::ring::SLOT;
use super::{lan9118, FLUSH, GATEWAY, IDLE, PACKET_LEN};
use crate::frames;
use kiss_odom_sensors::pose_datagram::{Counters, PoseDatagram};
use smoltcp::iface::{Interface, PollIngressSingleResult, SocketHandle, SocketSet};
use smoltcp::socket::udp;
use smoltcp::time::Instant;
use smoltcp::wire::{IpAddress, IpEndpoint};

/// Microseconds from the controller's 25 MHz free-running counter, its wraps unfolded.
#[derive(Default)]
pub struct Clock {
    last: u32,
    ticks: u64,
}

impl Clock {
    pub fn now(&mut self, nic: &Nic) -> Instant {
        let t = nic.hw().free_run();
        self.ticks += u64::from(t.wrapping_sub(self.last));
        self.last = t;
        Instant::from_micros((self.ticks * 1_000_000 / lan9118::FREE_RUN_HZ) as i64)
    }
}

/// What the receive loop found.
pub enum Next {
    /// A sensor datagram of this many bytes, in the caller's buffer.
    Packet(usize),
    /// Nothing for [`IDLE`].
    Idle,
}

/// The network side: the controller, the stack, its one socket, and what was counted.
pub struct Net<'s> {
    pub nic: Nic,
    pub iface: Interface,
    pub sockets: SocketSet<'s>,
    pub udp: SocketHandle,
    pub clock: Clock,
    pub sensor: Option<IpEndpoint>,
    pub counters: Counters,
}

/// Sleeps until the next interrupt (a frame, or the 100 Hz tick) unless a frame already waits.
fn sleep() {
    // Interrupts stay masked between the check and the wait; a pending one still wakes it.
    critical_section::with(|cs| {
        if RING.borrow_ref(cs).is_empty() {
            cortex_m::asm::wfi();
        }
    });
}

impl Net<'_> {
    /// Receives until a sensor datagram is in `buf`, or, when `idle_ends`, until the port has
    /// been silent for [`IDLE`].
    pub fn next(&mut self, buf: &mut [u8; SLOT], idle_ends: bool) -> Next {
        let mut last = self.clock.now(&self.nic);
        loop {
            match self
                .sockets
                .get_mut::<udp::Socket>(self.udp)
                .recv_slice(buf)
            {
                // The sensor is the first sender of a datagram of its packets' length.
                Ok((len, meta)) => {
                    if self.sensor.is_some_and(|s| s != meta.endpoint) {
                        self.counters.foreign += 1;
                    } else if len != PACKET_LEN {
                        self.counters.wrong_size += 1;
                    } else {
                        self.sensor = Some(meta.endpoint);
                        self.counters.packets += 1;
                        return Next::Packet(len);
                    }
                    continue;
                }
                // Longer than any frame: cannot be a sensor packet.
                Err(udp::RecvError::Truncated) => {
                    self.counters.wrong_size += 1;
                    continue;
                }
                Err(udp::RecvError::Exhausted) => {}
            }
            let now = self.clock.now(&self.nic);
            let moved = self
                .iface
                .poll_ingress_single(now, &mut self.nic, &mut self.sockets);
            self.iface
                .poll_egress(now, &mut self.nic, &mut self.sockets);
            if moved != PollIngressSingleResult::None {
                last = now;
                continue;
            }
            if idle_ends && now - last >= IDLE {
                return Next::Idle;
            }
            sleep();
        }
    }

    /// The counters with the ring's and the device's own counts folded in.
    pub fn counters(&self) -> Counters {
        let (full, long) = critical_section::with(|cs| {
            let r = RING.borrow_ref(cs);
            (r.dropped(), r.too_long())
        });
        Counters {
            overflow: full,
            wrong_size: self.counters.wrong_size + self.nic.fragments + long,
            unsent: self.counters.unsent + self.nic.tx_full,
            ..self.counters
        }
    }

    /// Queues a pose datagram for the host and pushes it out.
    pub fn send(&mut self, d: &PoseDatagram) {
        let to = IpEndpoint::new(IpAddress::Ipv4(GATEWAY), frames::POSE_PORT);
        let socket = self.sockets.get_mut::<udp::Socket>(self.udp);
        if socket.send_slice(&d.encode(), to).is_err() {
            self.counters.unsent += 1;
        }
        let now = self.clock.now(&self.nic);
        self.iface
            .poll_egress(now, &mut self.nic, &mut self.sockets);
    }

    /// Polls until every queued pose has left, or [`FLUSH`] has passed.
    pub fn flush(&mut self) {
        let start = self.clock.now(&self.nic);
        loop {
            let now = self.clock.now(&self.nic);
            self.iface.poll(now, &mut self.nic, &mut self.sockets);
            let queued = self.sockets.get::<udp::Socket>(self.udp).send_queue();
            if queued == 0 || now - start >= FLUSH {
                return;
            }
            sleep();
        }
    }
}
