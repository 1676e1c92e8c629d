//! defmt over semihosting (feature `defmt`): a global logger that writes the encoded frames to
//! the host's stdout, one semihosting write per log call. Decode with `defmt-print -e ELF`.
//! Frames and poses go through `defmt::info!` with their own format strings (deferred
//! formatting: only the arguments cross the link); the few summary lines are formatted on the
//! target and sent as one `{=str}` each.

use core::fmt::Write as _;
use core::sync::atomic::{AtomicBool, Ordering};
use semihosting::io::Write as _;

#[defmt::global_logger]
struct SemihostingLogger;

static TAKEN: AtomicBool = AtomicBool::new(false);
static mut ENCODER: defmt::Encoder = defmt::Encoder::new();
static mut BUF: Buffer = Buffer {
    bytes: [0; 256],
    len: 0,
};

/// Bytes of the frame being encoded, flushed when full and at the end of the frame.
struct Buffer {
    bytes: [u8; 256],
    len: usize,
}

impl Buffer {
    fn push(&mut self, mut data: &[u8]) {
        while !data.is_empty() {
            let n = data.len().min(self.bytes.len() - self.len);
            self.bytes[self.len..self.len + n].copy_from_slice(&data[..n]);
            self.len += n;
            data = &data[n..];
            if self.len == self.bytes.len() {
                self.flush();
            }
        }
    }

    fn flush(&mut self) {
        if self.len > 0 {
            if let Ok(mut out) = semihosting::io::stdout() {
                let _ = out.write_all(&self.bytes[..self.len]);
            }
            self.len = 0;
        }
    }
}

fn push(bytes: &[u8]) {
    // SAFETY: only called between acquire and release, which TAKEN makes exclusive.
    unsafe { (*core::ptr::addr_of_mut!(BUF)).push(bytes) }
}

// SAFETY: single core, no interrupt handler logs; TAKEN rejects re-entry.
unsafe impl defmt::Logger for SemihostingLogger {
    fn acquire() {
        if TAKEN.swap(true, Ordering::Acquire) {
            panic!("defmt logger re-entered");
        }
        // SAFETY: exclusive after the swap above.
        unsafe { (*core::ptr::addr_of_mut!(ENCODER)).start_frame(push) }
    }

    unsafe fn flush() {
        // SAFETY: exclusive between acquire and release.
        unsafe { (*core::ptr::addr_of_mut!(BUF)).flush() }
    }

    unsafe fn release() {
        // SAFETY: exclusive between acquire and release.
        unsafe {
            (*core::ptr::addr_of_mut!(ENCODER)).end_frame(push);
            (*core::ptr::addr_of_mut!(BUF)).flush();
        }
        TAKEN.store(false, Ordering::Release);
    }

    unsafe fn write(bytes: &[u8]) {
        // SAFETY: exclusive between acquire and release.
        unsafe { (*core::ptr::addr_of_mut!(ENCODER)).write(bytes, push) }
    }
}

/// A line formatted on the target (longer lines are cut at 160 bytes).
struct Line {
    bytes: [u8; 160],
    len: usize,
}

impl core::fmt::Write for Line {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        let n = s.len().min(self.bytes.len() - self.len);
        self.bytes[self.len..self.len + n].copy_from_slice(&s.as_bytes()[..n]);
        self.len += n;
        Ok(())
    }
}

/// Logs one preformatted line (what `out!` does with the `defmt` feature).
pub fn line(args: core::fmt::Arguments<'_>) {
    let mut l = Line {
        bytes: [0; 160],
        len: 0,
    };
    let _ = l.write_fmt(args);
    // Cutting may split a UTF-8 sequence; the lines are ASCII.
    let s = core::str::from_utf8(&l.bytes[..l.len]).unwrap_or("<non-ASCII line>");
    defmt::info!("{=str}", s);
}

defmt::timestamp!("{=u32}", 0);
