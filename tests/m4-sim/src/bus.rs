//! The boundary between the core and the chip around it.
//!
//! The core owns the System Control Space (0xE000_E000–0xE000_EFFF: NVIC, SCB, SysTick, MPU,
//! FPU registers), the debug blocks below it (ITM, DWT, FPB at 0xE000_0000–0xE000_DFFF) and
//! the TPIU (0xE004_0000–0xE004_0FFF); every
//! other address — flash, RAM, peripherals — goes to the [`Bus`]. Time is virtual
//! nanoseconds since power-on, derived by the core from the cycles it has executed at the
//! clock [`Bus::core_hz`] reports.

/// Width of a data access.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Width {
    /// 8 bits.
    Byte,
    /// 16 bits.
    Half,
    /// 32 bits.
    Word,
}

impl Width {
    /// Size in bytes.
    pub const fn bytes(self) -> u32 {
        match self {
            Width::Byte => 1,
            Width::Half => 2,
            Width::Word => 4,
        }
    }
}

/// An access the bus refused: nothing at the address, or a peripheral that errors the
/// transfer. The core raises a precise BusFault (escalated to HardFault when BusFault is
/// not enabled), as the silicon does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BusFault {
    /// The address of the access.
    pub addr: u32,
    /// A store (true) or a load or fetch (false).
    pub write: bool,
}

/// Why the chip asks for a reset of the core and itself.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ResetCause {
    /// A watchdog expired.
    Watchdog,
    /// Power was removed and restored (brown-out, power cycle).
    PowerOn,
    /// Anything else the SoC models (pin reset, …).
    Other,
}

/// Everything outside the core: the memories and peripherals of one chip (a SoC model).
///
/// The core calls `read`/`write` for every data access outside its own SCS, `fetch` for
/// instructions it has not decoded yet (it keeps decoded code until
/// [`Bus::code_generation`] changes or it stores to that code itself), and keeps the bus up
/// to date with time: before it lets virtual time pass [`Bus::next_event_ns`] it calls
/// [`Bus::advance`], and it calls `advance` at the end of every `run_until`. On entry to
/// `run_until` (the world may have driven the bus in between), after every `advance`, and
/// after every `read` or `write` at 0x4000_0000 or above (the peripheral, device and vendor
/// regions of the ARMv7-M memory map), it samples [`Bus::irq_lines`] and re-reads
/// [`Bus::next_event_ns`]; then and after such a write also [`Bus::core_hz`] and
/// [`Bus::code_generation`]. Accesses below 0x4000_0000 (the Code and SRAM regions) are
/// memory: nothing is re-read after them. Interrupt lines are levels: a line that is high
/// while its interrupt is not active sets it pending (the NVIC latches it), as on the
/// silicon; a rising edge while it is active pends it again.
pub trait Bus {
    /// The halfword of code at `addr` (2-aligned); `None` is a fetch fault (an instruction
    /// access violation on the core's side).
    fn fetch(&mut self, addr: u32) -> Option<u16>;

    /// Stall cycles the core waits for the instruction fetch at `addr` (flash wait states,
    /// accelerator or cache misses). Called once per executed instruction, with whether the
    /// fetch follows the previous one in sequence (false after a taken branch or exception).
    fn fetch_stall(&mut self, addr: u32, sequential: bool) -> u32 {
        let _ = (addr, sequential);
        0
    }

    /// A data load of `width` at `addr` at time `now_ns`.
    fn read(&mut self, addr: u32, width: Width, now_ns: u64) -> Result<u32, BusFault>;

    /// A data store of `width` (the low bits of `value`) at `addr` at time `now_ns`.
    fn write(&mut self, addr: u32, width: Width, value: u32, now_ns: u64) -> Result<(), BusFault>;

    /// Stall cycles for the data access just made at `addr` (flash data reads, bus bridges).
    fn access_stall(&mut self, addr: u32, write: bool) -> u32 {
        let _ = (addr, write);
        0
    }

    /// A counter that changes whenever code the core may have decoded changed (flash
    /// programmed or erased, code written to RAM); the core drops its decoded instructions
    /// when it differs from the last value it saw.
    fn code_generation(&self) -> u64 {
        0
    }

    /// External interrupt request lines, one bit per IRQ number n (word n / 32, bit n % 32).
    fn irq_lines(&self) -> [u32; 8];

    /// The earliest virtual time at which the bus changes state on its own (a timer match, a
    /// byte shifted out, an input edge); `u64::MAX` for never.
    fn next_event_ns(&self) -> u64;

    /// Brings the bus to `now_ns` (every event due at or before it has happened).
    fn advance(&mut self, now_ns: u64);

    /// The core clock in Hz; the core re-reads it after every write to a peripheral and
    /// every `advance` (the clock tree may have been reprogrammed) and counts time from then
    /// on at the new rate.
    fn core_hz(&self) -> u32;

    /// A reset the chip requests (watchdog, power): the core resets itself and calls
    /// [`Bus::reset`]. Polled after every `advance`.
    fn take_reset_request(&mut self) -> Option<ResetCause> {
        None
    }

    /// The core asked for a system reset (AIRCR.SYSRESETREQ) or took one the bus requested:
    /// peripherals go to their reset state; RAM keeps its contents.
    fn reset(&mut self, cause: ResetCause) {
        let _ = cause;
    }

    /// The program asked for a system reset (AIRCR.SYSRESETREQ); the core resets itself
    /// after this returns. Override to record the cause where the chip shows it (RCC_CSR
    /// SFTRSTF, RESETREAS.SREQ); the default resets the bus with [`ResetCause::Other`].
    fn sysresetreq(&mut self) {
        self.reset(ResetCause::Other);
    }

    /// The core went to sleep (WFI/WFE with nothing pending) or woke up, at `now_ns`; for the
    /// SoC's CPU-load accounting and its sleep-dependent peripherals.
    fn sleeping(&mut self, asleep: bool, now_ns: u64) {
        let _ = (asleep, now_ns);
    }
}
