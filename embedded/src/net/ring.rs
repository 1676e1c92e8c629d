//! The receive ring: Ethernet frames the interrupt handler took from the controller, waiting for
//! the network stack. Fixed slots in one `static`, filled by the handler and emptied by the main
//! loop, each under a critical section.
//!
//! Size: registering a sweep holds the CPU for up to 43 M instructions (RESULTS.md, VLP-16,
//! `TINY`), 72 ms at 600 MHz at one instruction a cycle, during which a VLP-16 sends 54 packets
//! (754 a second). `SLOTS` holds 0.68 s of them, 9x that, so a slower part or a sweep at the
//! work budget still loses nothing, and the ring, the sweep buffer and the arena together fit a
//! part with 2 MiB of SRAM. A frame that finds the ring full is counted, never waited for.

/// Bytes a slot holds: a VLP-16 data packet's frame (1,248 bytes with its headers) and its
/// CRC, rounded up. Longer frames cannot carry a sensor packet: they are counted and dropped.
pub const SLOT: usize = 1_280;
/// Slots: 0.68 s of a VLP-16's 754 packets a second.
pub const SLOTS: usize = 512;

/// Frames in arrival order.
pub struct Ring {
    data: [[u8; SLOT]; SLOTS],
    len: [u16; SLOTS],
    head: usize,
    used: usize,
    dropped: u32,
    too_long: u32,
    high_water: usize,
}

impl Ring {
    /// An empty ring (all zero: it lives in `.bss`).
    pub const fn new() -> Self {
        Self {
            data: [[0; SLOT]; SLOTS],
            len: [0; SLOTS],
            head: 0,
            used: 0,
            dropped: 0,
            too_long: 0,
            high_water: 0,
        }
    }

    /// The next free slot, to be filled and then [`Self::commit`]ted; `None` when full.
    pub fn slot(&mut self) -> Option<&mut [u8; SLOT]> {
        if self.used == SLOTS {
            return None;
        }
        let at = (self.head + self.used) % SLOTS;
        self.data.get_mut(at)
    }

    /// Makes the slot [`Self::slot`] gave a frame of `len` bytes.
    pub fn commit(&mut self, len: usize) {
        if self.used == SLOTS {
            return;
        }
        let at = (self.head + self.used) % SLOTS;
        if let Some(l) = self.len.get_mut(at) {
            *l = len.min(SLOT) as u16;
        }
        self.used += 1;
        self.high_water = self.high_water.max(self.used);
    }

    /// Counts a frame dropped because the ring was full.
    pub fn count_drop(&mut self) {
        self.dropped = self.dropped.wrapping_add(1);
    }

    /// Counts a frame dropped because it was longer than a slot or damaged.
    pub fn count_too_long(&mut self) {
        self.too_long = self.too_long.wrapping_add(1);
    }

    /// Copies the oldest frame into `out` and frees its slot; its length, or `None` if empty.
    pub fn pop_into(&mut self, out: &mut [u8; SLOT]) -> Option<usize> {
        if self.used == 0 {
            return None;
        }
        let len = usize::from(*self.len.get(self.head)?);
        out[..len].copy_from_slice(self.data.get(self.head)?.get(..len)?);
        self.head = (self.head + 1) % SLOTS;
        self.used -= 1;
        Some(len)
    }

    /// Whether a frame waits.
    pub fn is_empty(&self) -> bool {
        self.used == 0
    }

    /// Frames dropped at a full ring so far.
    pub fn dropped(&self) -> u32 {
        self.dropped
    }

    /// Frames dropped as too long or damaged so far.
    pub fn too_long(&self) -> u32 {
        self.too_long
    }

    /// The most frames that waited at once.
    pub fn high_water(&self) -> usize {
        self.high_water
    }
}
