//! The panic and HardFault handlers: the reason and the faulting address kept in RAM the
//! start-up code does not clear (`.uninit`), then a reset. panic-probe's `udf` loop left the
//! module dead until the watchdog, or for good before it runs; the record says at the next
//! boot why the module restarted ([`take`]).

use core::mem::MaybeUninit;
use core::panic::PanicInfo;

use cortex_m_rt::{ExceptionFrame, exception};

/// "TMF1": a record of a fault is present.
const MAGIC: u32 = 0x544D_4631;

/// Why the last boot ended, if a handler recorded it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, defmt::Format)]
pub enum Fault {
    /// A Rust panic; the handler's return address.
    Panic(u32),
    /// A HardFault at this address.
    HardFault(u32),
}

/// Magic, reason (1 panic, 2 HardFault), address, and the complement of the three's XOR.
#[unsafe(link_section = ".uninit.taulink.fault")]
static mut RECORD: MaybeUninit<[u32; 4]> = MaybeUninit::uninit();

fn write(reason: u32, address: u32) {
    let words = [MAGIC, reason, address, !(MAGIC ^ reason ^ address)];
    // SAFETY: called with interrupts masked (the handlers, `take` at boot): the only access.
    unsafe { (&raw mut RECORD).write(MaybeUninit::new(words)) };
}

/// The fault that ended the last boot, if one was recorded; the record is cleared.
pub fn take() -> Option<Fault> {
    cortex_m::interrupt::free(|_| {
        // SAFETY: interrupts are masked; any bit pattern is a valid `[u32; 4]` (power-up
        // garbage fails the magic and check word).
        let [magic, reason, address, check] = unsafe { (&raw const RECORD).read().assume_init() };
        write(0, 0);
        if magic != MAGIC || check != !(magic ^ reason ^ address) {
            return None;
        }
        match reason {
            1 => Some(Fault::Panic(address)),
            2 => Some(Fault::HardFault(address)),
            _ => None,
        }
    })
}

/// The handler's return address: where core's panic entry called it (the site is its caller,
/// found from the image's `.elf`). Read before the handler's first call overwrites LR.
#[inline(always)]
fn return_address() -> u32 {
    let lr: u32;
    // SAFETY: reads a register, touches nothing.
    unsafe { core::arch::asm!("mov {}, lr", out(reg) lr, options(nostack, preserves_flags)) };
    lr
}

/// Never reads the `PanicInfo`: formatting it kept every panic site's message and location
/// and `core::fmt` in flash (11 KB); the return address goes to the record.
#[panic_handler]
fn panic(_info: &PanicInfo) -> ! {
    let address = return_address();
    cortex_m::interrupt::disable();
    defmt::error!("panic, returning to {=u32:#x}", address);
    write(1, address);
    cortex_m::peripheral::SCB::sys_reset()
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    write(2, frame.pc());
    cortex_m::peripheral::SCB::sys_reset()
}
