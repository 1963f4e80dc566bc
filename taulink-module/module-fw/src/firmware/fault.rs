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
    /// A Rust panic.
    Panic,
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
            1 => Some(Fault::Panic),
            2 => Some(Fault::HardFault(address)),
            _ => None,
        }
    })
}

#[panic_handler]
fn panic(info: &PanicInfo) -> ! {
    cortex_m::interrupt::disable();
    defmt::error!("panic: {}", defmt::Display2Format(info));
    write(1, 0);
    cortex_m::peripheral::SCB::sys_reset()
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    write(2, frame.pc());
    cortex_m::peripheral::SCB::sys_reset()
}
