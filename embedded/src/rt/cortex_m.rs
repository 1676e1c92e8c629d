//! Cortex-M4F (QEMU `mps2-an386`) startup: cortex-m-rt's reset handler (which also enables
//! the FPU on `eabihf`), stack bounds from its linker script, fault handlers that exit 99.
//! QEMU models no cycle counter here, so instructions are counted outside the guest by the TCG
//! plugin in `plugin/insncount.c` (see `run.sh`).

use cortex_m_rt::{entry, exception, ExceptionFrame};
use semihosting::process;

extern "C" {
    /// End of .bss/.uninit: the stack may grow down to here.
    static __sheap: u32;
    /// Initial stack pointer (top of RAM).
    static _stack_start: u32;
}

#[entry]
fn main() -> ! {
    let lo = core::ptr::addr_of!(__sheap) as usize;
    let top = core::ptr::addr_of!(_stack_start) as usize;
    let code = crate::app(Some((lo, top)), || None, "qemu-plugin");
    process::exit(code)
}

/// An undefined instruction: with UsageFault disabled it escalates to HardFault.
#[cfg(feature = "fault-probe")]
pub fn fault() {
    // SAFETY: deliberately faults; the handler exits.
    unsafe { core::arch::asm!("udf #0") };
}

#[exception]
unsafe fn HardFault(ef: &ExceptionFrame) -> ! {
    semihosting::println!("error HardFault pc={:#010x} lr={:#010x}", ef.pc(), ef.lr());
    process::exit(99)
}

/// The 100 Hz tick of the network firmware: it only wakes the loop, which keeps the time.
#[cfg(feature = "net")]
#[exception]
fn SysTick() {}

#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    #[cfg(feature = "net")]
    if irqn == crate::net::IRQ as i16 {
        crate::net::on_irq();
        return;
    }
    semihosting::println!("error unexpected exception {}", irqn);
    process::exit(99)
}
