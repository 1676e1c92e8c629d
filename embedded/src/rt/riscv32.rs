//! RV32IMAC (QEMU `virt`, M-mode, `-bios none`) startup: park other harts, set the stack,
//! point `mtvec` at a handler that exits 99, zero .bss. Under `-icount shift=0` `minstret` is
//! the exact retired-instruction count. No FPU: f32 and f64 are both soft-float.

use semihosting::process;

core::arch::global_asm!(
    r#"
    .section .text._start, "ax"
    .global _start
_start:
    csrr  t0, mhartid
    bnez  t0, 3f
    la    sp, __stack_top
    la    t0, kiss_trap_entry
    csrw  mtvec, t0
    la    t0, __bss_start
    la    t1, __bss_end
1:  bgeu  t0, t1, 2f
    sw    zero, 0(t0)
    addi  t0, t0, 4
    j     1b
2:  call  kiss_main
3:  wfi
    j     3b

    .balign 4
kiss_trap_entry:
    csrr  a0, mcause
    csrr  a1, mepc
    csrr  a2, mtval
    call  kiss_trap
"#
);

extern "C" {
    static __stack_bottom: u32;
    static __stack_top: u32;
}

fn insns() -> Option<u64> {
    loop {
        let (hi, lo, hi2): (u32, u32, u32);
        // SAFETY: reads M-mode counters.
        unsafe {
            core::arch::asm!(
                "csrr {0}, minstreth",
                "csrr {1}, minstret",
                "csrr {2}, minstreth",
                out(reg) hi,
                out(reg) lo,
                out(reg) hi2
            )
        };
        if hi == hi2 {
            return Some(((hi as u64) << 32) | lo as u64);
        }
    }
}

#[no_mangle]
extern "C" fn kiss_main() -> ! {
    let lo = core::ptr::addr_of!(__stack_bottom) as usize;
    let top = core::ptr::addr_of!(__stack_top) as usize;
    let code = crate::app(Some((lo, top)), insns, "minstret");
    process::exit(code)
}

/// An illegal instruction: trap.
#[cfg(feature = "fault-probe")]
pub fn fault() {
    // SAFETY: deliberately traps; the handler exits.
    unsafe { core::arch::asm!("unimp") };
}

#[no_mangle]
extern "C" fn kiss_trap(cause: usize, epc: usize, tval: usize) -> ! {
    semihosting::println!(
        "error trap mcause={:#x} mepc={:#x} mtval={:#x}",
        cause,
        epc,
        tval
    );
    process::exit(99)
}
