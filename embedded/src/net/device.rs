//! The controller as smoltcp sees it: received frames come from the [`Ring`] the interrupt
//! handler fills, transmitted ones go straight to the controller's FIFO. IPv4 fragments are
//! taken out here and counted: a sensor packet never needs fragmenting, so a fragment is an
//! oversized datagram on its way in (smoltcp is built without reassembly).

use super::lan9118::Lan9118;
use super::ring::{Ring, SLOT};
use core::cell::RefCell;
use critical_section::Mutex;
use smoltcp::phy::{self, DeviceCapabilities, Medium};
use smoltcp::time::Instant;

/// Where received frames wait.
pub static RING: Mutex<RefCell<Ring>> = Mutex::new(RefCell::new(Ring::new()));

/// The device: the controller and one frame's worth of buffer each way.
pub struct Nic {
    hw: Lan9118,
    rx: [u8; SLOT],
    tx: [u8; SLOT],
    /// IPv4 fragments taken out (oversized datagrams).
    pub fragments: u32,
    /// Frames the controller's transmit FIFO had no room for.
    pub tx_full: u32,
}

impl Nic {
    /// The device over a brought-up controller.
    pub fn new(hw: Lan9118) -> Self {
        Self {
            hw,
            rx: [0; SLOT],
            tx: [0; SLOT],
            fragments: 0,
            tx_full: 0,
        }
    }

    /// The controller.
    pub fn hw(&self) -> &Lan9118 {
        &self.hw
    }
}

/// Whether an Ethernet frame carries an IPv4 fragment (more-fragments set or an offset).
fn is_fragment(frame: &[u8]) -> bool {
    const ETHERTYPE: core::ops::Range<usize> = 12..14;
    const FLAGS_OFFSET: core::ops::Range<usize> = 20..22;
    let ipv4 = frame.get(ETHERTYPE) == Some(&[0x08, 0x00]);
    let flags = frame
        .get(FLAGS_OFFSET)
        .map_or(0, |b| u16::from_be_bytes([b[0], b[1]]));
    ipv4 && flags & 0x3fff != 0
}

/// A received frame, lent to smoltcp.
pub struct Rx<'a>(&'a [u8]);

/// Room for one frame to send.
pub struct Tx<'a> {
    hw: &'a Lan9118,
    buf: &'a mut [u8; SLOT],
    full: &'a mut u32,
}

impl phy::RxToken for Rx<'_> {
    fn consume<R, F: FnOnce(&[u8]) -> R>(self, f: F) -> R {
        f(self.0)
    }
}

impl phy::TxToken for Tx<'_> {
    fn consume<R, F: FnOnce(&mut [u8]) -> R>(self, len: usize, f: F) -> R {
        let n = len.min(SLOT);
        let r = f(&mut self.buf[..n]);
        if !self.hw.transmit(&self.buf[..n]) {
            *self.full = self.full.wrapping_add(1);
        }
        r
    }
}

impl phy::Device for Nic {
    type RxToken<'a> = Rx<'a>;
    type TxToken<'a> = Tx<'a>;

    fn receive(&mut self, _: Instant) -> Option<(Rx<'_>, Tx<'_>)> {
        loop {
            let len = critical_section::with(|cs| RING.borrow_ref_mut(cs).pop_into(&mut self.rx))?;
            if is_fragment(&self.rx[..len]) {
                self.fragments = self.fragments.wrapping_add(1);
                continue;
            }
            let tx = Tx {
                hw: &self.hw,
                buf: &mut self.tx,
                full: &mut self.tx_full,
            };
            return Some((Rx(&self.rx[..len]), tx));
        }
    }

    fn transmit(&mut self, _: Instant) -> Option<Tx<'_>> {
        Some(Tx {
            hw: &self.hw,
            buf: &mut self.tx,
            full: &mut self.tx_full,
        })
    }

    fn capabilities(&self) -> DeviceCapabilities {
        let mut caps = DeviceCapabilities::default();
        caps.medium = Medium::Ethernet;
        caps.max_transmission_unit = SLOT - 4;
        caps
    }
}
