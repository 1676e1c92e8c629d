//! The SMSC LAN9118 Ethernet controller of the MPS2 boards (QEMU `-nic user,model=lan9118`), by
//! its datasheet's register interface: 32-bit registers at `BASE`, frames moved through its
//! receive and transmit FIFOs by the CPU (no DMA).
//!
//! Receiving is interrupt-driven: the odometry holds the CPU for a whole sweep's registration,
//! far longer than the controller's receive FIFO (about 10 KB, eight sensor packets) lasts at
//! a sensor's packet rate, so the interrupt handler moves each frame into the [`Ring`] in RAM
//! as it arrives and the network stack takes it from there when the loop comes round.
//! Transmitting is polled: poses are small and rare.

use super::ring::{Ring, SLOT};
use core::cell::RefCell;
use critical_section::Mutex;

/// The controller's registers on the MPS2 AN385/AN386 boards (Cortex-M3/M4).
const BASE_AN386: usize = 0x4020_0000;
/// ... and on the AN500 (Cortex-M7).
const BASE_AN500: usize = 0xa000_0000;
/// Its interrupt line on the NVIC, on all three.
pub const IRQ: u16 = 13;

/// The board's controller address, told by the core it runs on (`CPUID` part number 0xC27
/// is a Cortex-M7, so the AN500).
fn base() -> usize {
    let cpuid = cortex_m::peripheral::CPUID::PTR;
    // SAFETY: CPUID is the architectural, always-readable identification register of every
    // Armv7-M core; reading it has no side effect.
    let id = unsafe { &*cpuid }.base.read();
    if (id >> 4) & 0xfff == 0xc27 {
        BASE_AN500
    } else {
        BASE_AN386
    }
}

/// Register offsets (datasheet section 5).
mod reg {
    pub const RX_DATA_FIFO: usize = 0x00;
    pub const TX_DATA_FIFO: usize = 0x20;
    pub const RX_STATUS_FIFO: usize = 0x40;
    pub const TX_STATUS_FIFO: usize = 0x48;
    pub const ID_REV: usize = 0x50;
    pub const IRQ_CFG: usize = 0x54;
    pub const INT_STS: usize = 0x58;
    pub const INT_EN: usize = 0x5c;
    pub const BYTE_TEST: usize = 0x64;
    pub const TX_CFG: usize = 0x70;
    pub const HW_CFG: usize = 0x74;
    pub const RX_FIFO_INF: usize = 0x7c;
    pub const TX_FIFO_INF: usize = 0x80;
    pub const PMT_CTRL: usize = 0x84;
    pub const FREE_RUN: usize = 0x9c;
    pub const MAC_CSR_CMD: usize = 0xa4;
    pub const MAC_CSR_DATA: usize = 0xa8;
}

/// MAC registers behind `MAC_CSR_CMD`.
mod mac {
    pub const CR: u32 = 1;
    pub const ADDRH: u32 = 2;
    pub const ADDRL: u32 = 3;
    pub const CR_FDPX: u32 = 1 << 20;
    pub const CR_TXEN: u32 = 1 << 3;
    pub const CR_RXEN: u32 = 1 << 2;
}

/// `BYTE_TEST` reads this on a controller wired the right way round.
const BYTE_TEST: u32 = 0x8765_4321;
/// `IRQ_CFG`: output enabled, active high, push-pull (the NVIC input is active high).
const IRQ_ENABLE_HIGH: u32 = 0x111;
/// `INT_STS`/`INT_EN`: the receive status FIFO passed its level (0: any frame).
const RSFL_INT: u32 = 1 << 3;
/// `TX_CFG`: transmitter on; status FIFO may overrun (we never need the statuses).
const TX_ON_SAO: u32 = (1 << 1) | (1 << 2);
/// Receive status: the frame had an error (CRC, runt, too long).
const RX_ERROR: u32 = 1 << 15;
/// `FREE_RUN` counts at 25 MHz.
pub const FREE_RUN_HZ: u64 = 25_000_000;

/// Why the controller could not be brought up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NicError {
    /// `BYTE_TEST` did not read back: no LAN9118 at the board's address (QEMU started without `-nic`?).
    Absent,
    /// It did not leave reset.
    Reset,
}

/// The register window. The only place that touches the controller.
struct Regs {
    base: usize,
}

impl Regs {
    fn read(&self, offset: usize) -> u32 {
        debug_assert!(offset < 0x100 && offset % 4 == 0);
        let addr = (self.base + (offset & 0xfc)) as *const u32;
        // SAFETY: base..base+0x100 is the LAN9118's register window in the board's memory map
        // (device memory, 32-bit aligned, side effects only on the controller); offset is
        // masked into it.
        unsafe { core::ptr::read_volatile(addr) }
    }
    fn write(&self, offset: usize, value: u32) {
        let addr = (self.base + (offset & 0xfc)) as *mut u32;
        // SAFETY: as for `read`.
        unsafe { core::ptr::write_volatile(addr, value) }
    }
    fn mac_read(&self, index: u32) -> u32 {
        self.write(reg::MAC_CSR_CMD, (1 << 31) | (1 << 30) | index);
        self.mac_wait();
        self.read(reg::MAC_CSR_DATA)
    }
    fn mac_write(&self, index: u32, value: u32) {
        self.write(reg::MAC_CSR_DATA, value);
        self.write(reg::MAC_CSR_CMD, (1 << 31) | index);
        self.mac_wait();
    }
    fn mac_wait(&self) {
        for _ in 0..100_000 {
            if self.read(reg::MAC_CSR_CMD) & (1 << 31) == 0 {
                return;
            }
        }
    }
}

/// The controller, brought up.
pub struct Lan9118 {
    regs: Regs,
    mac: [u8; 6],
}

impl Lan9118 {
    /// Resets the controller and starts the MAC. The PHY is left as it comes out of reset
    /// (QEMU's link is up at once; a real board resets it and waits for autonegotiation here).
    pub fn bring_up() -> Result<Self, NicError> {
        let regs = Regs { base: base() };
        if regs.read(reg::BYTE_TEST) != BYTE_TEST || regs.read(reg::ID_REV) >> 16 != 0x0118 {
            return Err(NicError::Absent);
        }
        regs.write(reg::HW_CFG, 1);
        let ready = (0..100_000)
            .any(|_| regs.read(reg::HW_CFG) & 1 == 0 && regs.read(reg::PMT_CTRL) & 1 == 1);
        if !ready {
            return Err(NicError::Reset);
        }
        let lo = regs.mac_read(mac::ADDRL).to_le_bytes();
        let hi = regs.mac_read(mac::ADDRH).to_le_bytes();
        let addr = [lo[0], lo[1], lo[2], lo[3], hi[0], hi[1]];
        // Exact address filtering (reset leaves it promiscuous), broadcast accepted.
        regs.mac_write(mac::CR, mac::CR_FDPX | mac::CR_TXEN | mac::CR_RXEN);
        regs.write(reg::TX_CFG, TX_ON_SAO);
        regs.write(reg::INT_STS, u32::MAX);
        regs.write(reg::INT_EN, RSFL_INT);
        regs.write(reg::IRQ_CFG, IRQ_ENABLE_HIGH);
        Ok(Self { regs, mac: addr })
    }

    /// The station address (QEMU's `-nic ...,mac=` or its default).
    pub fn mac(&self) -> [u8; 6] {
        self.mac
    }

    /// The 25 MHz free-running counter (wraps every 172 s).
    pub fn free_run(&self) -> u32 {
        self.regs.read(reg::FREE_RUN)
    }

    /// Sends one frame (without its CRC, which the controller appends); false if the transmit
    /// FIFO has no room for it or it is too long.
    pub fn transmit(&self, frame: &[u8]) -> bool {
        let len = frame.len();
        let free = (self.regs.read(reg::TX_FIFO_INF) & 0xffff) as usize;
        if len > SLOT - 4 || free < len + 8 {
            return false;
        }
        // Command A: first and last segment, buffer size; command B: packet length.
        self.regs
            .write(reg::TX_DATA_FIFO, (1 << 13) | (1 << 12) | len as u32);
        self.regs.write(reg::TX_DATA_FIFO, len as u32);
        for word in frame.chunks(4) {
            let mut w = [0u8; 4];
            w[..word.len()].copy_from_slice(word);
            self.regs.write(reg::TX_DATA_FIFO, u32::from_le_bytes(w));
        }
        while (self.regs.read(reg::TX_FIFO_INF) >> 16) & 0xff != 0 {
            self.regs.read(reg::TX_STATUS_FIFO);
        }
        true
    }
}

/// Moves every frame waiting in the controller into `ring` (the interrupt handler's work);
/// a frame that finds the ring full, or is damaged or too long, is dropped and counted.
pub fn drain_into(ring: &Mutex<RefCell<Ring>>) {
    let regs = Regs { base: base() };
    critical_section::with(|cs| {
        let mut ring = ring.borrow_ref_mut(cs);
        while (regs.read(reg::RX_FIFO_INF) >> 16) & 0xff != 0 {
            let status = regs.read(reg::RX_STATUS_FIFO);
            let len = ((status >> 16) & 0x3fff) as usize;
            let words = len.div_ceil(4);
            if status & RX_ERROR != 0 || len > SLOT {
                ring.count_too_long();
                skip(&regs, words);
                continue;
            }
            match ring.slot() {
                Some(buf) => {
                    for k in 0..words {
                        let w = regs.read(reg::RX_DATA_FIFO).to_le_bytes();
                        let at = 4 * k;
                        let n = (len - at).min(4);
                        buf[at..at + n].copy_from_slice(&w[..n]);
                    }
                    // The length the controller counts includes the 4-byte CRC.
                    ring.commit(len.saturating_sub(4));
                }
                None => {
                    ring.count_drop();
                    skip(&regs, words);
                }
            }
        }
        regs.write(reg::INT_STS, RSFL_INT);
    });
}

/// Discards a frame of `words` words from the receive data FIFO by reading them (the
/// controller's fast-forward is not used: QEMU's model of it loses FIFO space).
fn skip(regs: &Regs, words: usize) {
    for _ in 0..words {
        regs.read(reg::RX_DATA_FIFO);
    }
}
