//! Faults and resets: the panic and HardFault handlers, the reset's cause, and the record
//! kept across a reset for a resumed flight (`flight_app::app::resume`: what it holds and
//! the decision are there).
//!
//! - **Handlers.** A panic (every `unwrap!`/`assert!` of the HAL ends here too) or a
//!   HardFault first drives every motor pin low as a GPIO (`board::motors_off`: register
//!   writes, no HAL state, at once — the timers would keep their last duty until the IWDG),
//!   then records the reason, the time and the faulting address (a panic's: the handler's
//!   return address), then resets. panic-probe's
//!   `udf` loop left the motors at their last duty until the watchdog, and before the
//!   watchdog runs, for good.
//! - **The record** ([`Record`]) lives in `.uninit`, RAM the start-up code neither zeroes nor
//!   initialises, so a reset (not a power cycle) leaves it as it was. The IMU task keeps the
//!   flight state and gains in it, the supervisor its feeds, the handlers their fault. At
//!   boot [`take`] copies it out and invalidates it, so it resumes one boot at most.

use core::mem::MaybeUninit;
use core::panic::PanicInfo;

use cortex_m_rt::{ExceptionFrame, exception};
use embassy_stm32::pac;
use flight_app::app::resume::{
    FAULT_WORDS, FEED_WORDS, Fault, FaultReason, GAINS_WORDS, ResetCause, STATE_WORDS, encode_feed,
};

use super::board;
use super::shared::now_ms;

/// The blocks `flight_app::app::resume` encodes, as the firmware keeps them.
#[repr(C)]
pub struct Record {
    /// The flight state (the IMU task, every few ms).
    pub state: [u32; STATE_WORDS],
    /// The gains and the settings they came from (when they change).
    pub gains: [u32; GAINS_WORDS],
    /// The handler's fault.
    pub fault: [u32; FAULT_WORDS],
    /// The last watchdog feed.
    pub feed: [u32; FEED_WORDS],
}

#[unsafe(link_section = ".uninit.taulink.resume")]
static mut RECORD: MaybeUninit<Record> = MaybeUninit::uninit();

/// Runs `f` on the record, interrupts masked (the IMU task, the supervisor and the handlers
/// write it).
pub fn with_record<R>(f: impl FnOnce(&mut Record) -> R) -> R {
    cortex_m::interrupt::free(|_| {
        // SAFETY: interrupts are masked, so this is the only reference; every bit pattern is
        // a valid `Record` (words only), and the section holds what the last boot wrote, or
        // power-up garbage that no block's magic and CRC accept.
        let record = unsafe { &mut *(&raw mut RECORD).cast::<Record>() };
        f(record)
    })
}

/// The feed the supervisor just made.
pub fn keep_feed(now_ms: u32) {
    with_record(|r| r.feed = encode_feed(now_ms));
}

/// What reset the MCU (RCC_CSR), its flags then cleared for the next boot.
pub fn reset_cause() -> ResetCause {
    let rcc = pac::RCC;
    let csr = rcc.csr().read();
    rcc.csr().modify(|w| w.set_rmvf(true));
    if csr.borrstf() || csr.porrstf() {
        ResetCause::PowerOn
    } else if csr.wdgrstf() {
        ResetCause::Watchdog
    } else if csr.sftrstf() {
        ResetCause::Software
    } else if csr.padrstf() {
        // Every internal reset also pulses NRST, so the pin's flag comes last.
        ResetCause::Pin
    } else {
        ResetCause::Other
    }
}

/// The record as the last boot left it; the live one is invalidated (its magic words
/// cleared), so it can resume this boot only.
pub fn take() -> Record {
    with_record(|r| {
        let kept = Record {
            state: r.state,
            gains: r.gains,
            fault: r.fault,
            feed: r.feed,
        };
        r.state = [0; STATE_WORDS];
        r.fault = [0; FAULT_WORDS];
        r.feed = [0; FEED_WORDS];
        kept
    })
}

/// Motors off, the fault kept, reset.
fn fail(reason: FaultReason, address: u32) -> ! {
    cortex_m::interrupt::disable();
    if cfg!(pil_fault_halts) {
        halt();
    }
    board::motors_off();
    let fault = Fault {
        reason,
        at_ms: now_ms(),
        address,
    };
    with_record(|r| r.fault = fault.encode());
    cortex_m::peripheral::SCB::sys_reset()
}

/// The PIL's `fault-halts` variant (flight-fw `build.rs`): spin as panic-probe's handler
/// did, the motors at their last duty until the watchdog resets the board.
fn halt() -> ! {
    loop {
        cortex_m::asm::nop();
    }
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
/// and `core::fmt` in flash (17.6 KB on Sparky2); the return address goes to the record.
#[panic_handler]
fn panic(_info: &PanicInfo) -> ! {
    let address = return_address();
    if cfg!(pil_fault_halts) {
        halt();
    }
    // The motors first: logging waits for nothing, but it is not free.
    board::motors_off();
    defmt::error!("panic, returning to {=u32:#x}", address);
    fail(FaultReason::Panic, address)
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    fail(FaultReason::HardFault, frame.pc())
}
