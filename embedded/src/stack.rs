//! Stack high-water mark by painting: fill the unused stack with a pattern before the
//! workload, then find the deepest word the workload overwrote. Works the same on hardware.

const PATTERN: u32 = 0x5EED_57AC;
/// Bytes below the current stack pointer left unpainted (this function's own frame).
const MARGIN: usize = 512;

/// Paints `[lo, sp - MARGIN)`.
///
/// # Safety
/// `lo` must be the 4-byte-aligned bottom of the current stack, with nothing else living
/// between it and the stack pointer.
#[inline(never)]
pub unsafe fn paint(lo: usize) {
    let here = 0u8;
    let sp = core::ptr::addr_of!(here) as usize;
    let end = (sp - MARGIN) & !3;
    let mut p = lo as *mut u32;
    while (p as usize) < end {
        p.write_volatile(PATTERN);
        p = p.add(1);
    }
}

/// Bytes of `[lo, top)` used since [`paint`]: `top` minus the lowest overwritten word.
/// Equal to `top - lo` when even the bottom word was overwritten (an overflow).
///
/// # Safety
/// `[lo, top)` must be the region given to [`paint`].
pub unsafe fn high_water(lo: usize, top: usize) -> usize {
    let mut p = lo as *const u32;
    while (p as usize) < top && p.read_volatile() == PATTERN {
        p = p.add(1);
    }
    top - p as usize
}
