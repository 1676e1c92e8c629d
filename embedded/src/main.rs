//! kiss-odom-core on bare metal: registers a few real KITTI frames embedded in the binary, with
//! all storage in `static`s and no heap, and prints poses and reports over semihosting.
//!
//! One source, four builds: `thumbv7em-none-eabihf` (QEMU `mps2-an386`, Cortex-M4F; with
//! `-C target-cpu=cortex-m7` also QEMU `mps2-an500`, Cortex-M7), `aarch64-unknown-none` (QEMU
//! `virt`, Cortex-A53), `riscv32imac-unknown-none-elf` (QEMU `virt`), and the host twin (any `std` target) that prints the same lines to stdout so
//! `compare.sh` can diff them. Exit status: 0 ok, 2 frame error, 3 configuration error,
//! 98 stack overflow, 99 fault or trap, 101 panic.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

/// One text line to the program's output: semihosting stdout on bare metal, stdout on the host,
/// a preformatted defmt string with the `defmt` feature.
#[cfg(all(target_os = "none", not(feature = "defmt")))]
macro_rules! out {
    ($($t:tt)*) => { semihosting::println!($($t)*) };
}
#[cfg(all(target_os = "none", feature = "defmt"))]
macro_rules! out {
    ($($t:tt)*) => { $crate::logger::line(format_args!($($t)*)) };
}
#[cfg(not(target_os = "none"))]
macro_rules! out {
    ($($t:tt)*) => { std::println!($($t)*) };
}

mod frames;
#[cfg_attr(feature = "defmt", allow(dead_code))]
mod lines;
#[cfg(all(feature = "net", target_arch = "arm", target_os = "none"))]
mod net;
mod profile;
#[cfg(all(feature = "net", not(all(target_arch = "arm", target_os = "none"))))]
compile_error!(
    "`net` is firmware for the MPS2 boards' LAN9118: build it for thumbv7em-none-eabihf"
);
#[cfg(feature = "imu")]
mod imu;
#[cfg(feature = "localize")]
mod localize;
#[cfg(feature = "packets")]
mod stream;
mod workload;

#[cfg(all(target_os = "none", feature = "defmt"))]
mod logger;
#[cfg(target_os = "none")]
mod stack;

#[cfg_attr(all(target_arch = "arm", target_os = "none"), path = "rt/cortex_m.rs")]
#[cfg_attr(
    all(target_arch = "aarch64", target_os = "none"),
    path = "rt/aarch64.rs"
)]
#[cfg_attr(
    all(target_arch = "riscv32", target_os = "none"),
    path = "rt/riscv32.rs"
)]
#[cfg_attr(not(target_os = "none"), path = "rt/host.rs")]
mod rt;

#[cfg(not(target_os = "none"))]
fn main() {
    rt::main()
}

use kiss_odom_core::Words;
use profile::ARENA_WORDS;
use static_cell::ConstStaticCell;

/// Exit status when the painted stack was used up (the stack ran into whatever lies below).
pub const EXIT_STACK_OVERFLOW: i32 = 98;

/// All of the odometry's storage, in one `static`: `Words` is const-constructed (zero words,
/// sized at compile time by `Capacities::arena_words`) and `ConstStaticCell` hands it out once,
/// so neither `static mut` nor `unsafe` is needed. On the Cortex-M4F a full-scale state goes to
/// the PSRAM (external RAM on a real board, whose startup code must zero it like `.bss`; QEMU
/// starts it zeroed).
#[cfg_attr(
    all(target_arch = "arm", target_os = "none", feature = "full"),
    link_section = ".psram"
)]
static STATE: ConstStaticCell<Words<ARENA_WORDS>> = ConstStaticCell::new(Words::new());

// The capacities are checked against the board at compile time (`arena_words` is a const fn):
// on the M4F the SRAM also holds the stack, so leave it 256 KiB.
#[cfg(all(target_arch = "arm", target_os = "none", not(feature = "full")))]
const _: () = assert!(
    ARENA_WORDS * 8 <= (4 << 20) - (256 << 10),
    "arena does not fit the 4 MiB SRAM"
);
#[cfg(all(target_arch = "arm", target_os = "none", feature = "full"))]
const _: () = assert!(
    ARENA_WORDS * 8 <= 16 << 20,
    "arena does not fit the 16 MiB PSRAM"
);

/// The program, after the target's startup code: paints the stack `[lo, top)` if given, runs
/// the workload, reports the stack high-water mark. Returns the exit status.
#[allow(unused_variables, unused_mut)]
fn app(stack: Option<(usize, usize)>, insns: fn() -> Option<u64>, counter: &str) -> i32 {
    #[cfg(target_os = "none")]
    if let Some((lo, _)) = stack {
        // SAFETY: [lo, top) is the stack region from the linker script; paint stays below SP.
        unsafe { stack::paint(lo) };
    }
    #[cfg(feature = "alloc-probe")]
    probe::alloc();
    #[cfg(feature = "panic-probe")]
    probe::panic();
    #[cfg(feature = "fault-probe")]
    rt::fault();

    let mut code = match STATE.try_take() {
        Some(state) => workload::run(state, insns, counter),
        None => profile::EXIT_CONFIG_ERROR,
    };

    #[cfg(target_os = "none")]
    if let Some((lo, top)) = stack {
        // SAFETY: as for `paint`.
        let used = unsafe { stack::high_water(lo, top) };
        out!("stack high_water={} region={}", used, top - lo);
        if used >= top - lo {
            out!("error stack overflow");
            code = EXIT_STACK_OVERFLOW;
        }
    }
    out!("exit {}", code);
    code
}

/// Negative controls: each must fail (see `run.sh --probes`).
#[cfg(any(feature = "alloc-probe", feature = "panic-probe"))]
mod probe {
    #[cfg(feature = "alloc-probe")]
    extern crate alloc;

    /// Needs a global allocator: a bare-metal build must fail to link.
    #[cfg(feature = "alloc-probe")]
    pub fn alloc() {
        let v = alloc::vec![1u8; core::hint::black_box(3)];
        core::hint::black_box(&v);
    }

    /// Must exit with 101 through the semihosting panic handler.
    #[cfg(feature = "panic-probe")]
    pub fn panic() {
        if core::hint::black_box(true) {
            panic!("panic-probe: deliberate panic");
        }
    }
}
