//! Cortex-A53 (QEMU `virt`, EL1, MMU off) startup: park secondary cores, set the stack, turn on
//! FP/SIMD (rustc emits it for `aarch64-unknown-none`), install a vector table whose every
//! entry exits 99, zero .bss, start the PMU cycle counter. Under `-icount shift=0` QEMU makes
//! that counter the exact retired-instruction count.

use semihosting::process;

core::arch::global_asm!(
    r#"
    .section .text._start, "ax"
    .global _start
_start:
    mrs   x0, mpidr_el1
    tst   x0, #0xff
    b.ne  .Lpark
    ldr   x1, =__stack_top
    mov   sp, x1
    mov   x1, #(3 << 20)          // CPACR_EL1.FPEN = 0b11: no FP/SIMD traps
    msr   cpacr_el1, x1
    ldr   x1, =kiss_vectors
    msr   vbar_el1, x1
    isb
    ldr   x1, =__bss_start
    ldr   x2, =__bss_end
.Lzero:
    cmp   x1, x2
    b.hs  .Lrun
    stp   xzr, xzr, [x1], #16
    b     .Lzero
.Lrun:
    bl    kiss_main
.Lpark:
    wfe
    b     .Lpark

    .section .text.kiss_vectors, "ax"
    .balign 2048
kiss_vectors:
    .irp n, 0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15
    .balign 128
    mov   x0, #\n
    b     kiss_exception_entry
    .endr
kiss_exception_entry:
    mrs   x1, esr_el1
    mrs   x2, elr_el1
    mrs   x3, far_el1
    bl    kiss_exception
"#
);

extern "C" {
    static __stack_bottom: u64;
    static __stack_top: u64;
}

fn insns() -> Option<u64> {
    let v: u64;
    // SAFETY: reads a PMU register that `kiss_main` enabled for EL1.
    unsafe { core::arch::asm!("isb", "mrs {}, pmccntr_el0", out(reg) v) };
    Some(v)
}

#[no_mangle]
extern "C" fn kiss_main() -> ! {
    // SAFETY: PMCR_EL0.E enables the counters, PMCNTENSET_EL0 bit 31 the cycle counter.
    unsafe {
        core::arch::asm!(
            "msr pmcr_el0, {e}",
            "msr pmcntenset_el0, {c}",
            "isb",
            e = in(reg) 1u64,
            c = in(reg) 1u64 << 31
        );
    }
    let lo = core::ptr::addr_of!(__stack_bottom) as usize;
    let top = core::ptr::addr_of!(__stack_top) as usize;
    let code = crate::app(Some((lo, top)), insns, "pmccntr");
    process::exit(code)
}

/// An undefined instruction: synchronous exception, vector 4.
#[cfg(feature = "fault-probe")]
pub fn fault() {
    // SAFETY: deliberately faults; the vector exits.
    unsafe { core::arch::asm!("udf #0") };
}

#[no_mangle]
extern "C" fn kiss_exception(vector: u64, esr: u64, elr: u64, far: u64) -> ! {
    semihosting::println!(
        "error exception vector={} esr={:#x} elr={:#x} far={:#x}",
        vector,
        esr,
        elr,
        far
    );
    process::exit(99)
}
