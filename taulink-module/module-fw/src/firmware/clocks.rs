//! The clocks and the main regulator, settled before `embassy_nrf::init` is given its
//! configuration.
//!
//! - **Crystals.** embassy-nrf's init waits for HFCLKSTARTED and LFCLKSTARTED without a
//!   limit (`lib.rs`: `while r.events_hfclkstarted().read() == 0 {}`, the same for the LFCLK),
//!   before the watchdog exists: a module whose 32 MHz or 32.768 kHz crystal does not start
//!   would hang at power-up for good. [`probe`] starts each crystal itself and waits a bounded
//!   time (nRF52840 PS, HFXO t_START 0.36 ms typical, LFXO t_START 0.25 s typical). A running
//!   HFXO stays on and embassy is told `Internal` (it then leaves the HF clock alone); a dead
//!   one falls back to the 64 MHz HFINT (±1.5 %: UART baud rates and the link's slot timing
//!   suffer, so the status says so). The LFXO is stopped again after its probe (the LF source
//!   may only change while the LF clock is stopped) and embassy starts the source chosen:
//!   the LFXO, or when it is dead the LFCLK synthesised from a running HFXO (the crystal's
//!   accuracy), or the LFRC without one (±2 % uncalibrated: embassy-time runs that far off).
//! - **REGOUT0.** On a board powered through VDDH (POWER.MAINREGSTATUS = high voltage, the
//!   nice!nano's case) the first regulator stage sets the GPIO voltage from UICR.REGOUT0. A
//!   chip-erased UICR (the documented SWD recovery erases it) reads 0b111: 1.8 V, at which
//!   the RFM22B and the HM-10 do not work and their 3.3 V outputs exceed the nRF's absolute
//!   maximum (VDD + 0.3 V). Only then does [`probe`] ask embassy-nrf for 3.3 V
//!   (`DcdcConfig::reg0_voltage`), which writes the word through the NVMC and resets once; a
//!   value someone programmed is left as it is.

use cortex_m::peripheral::{DCB, DWT};
use embassy_nrf::config::{self, HfclkSource, LfclkSource, Reg0Voltage};
use embassy_nrf::pac;

/// HFXO start-up limit, ms (PS: 0.36 ms typical).
const HFXO_WAIT_MS: u32 = 10;
/// LFXO start-up limit, ms (PS: 0.25 s typical).
const LFXO_WAIT_MS: u32 = 1_000;
/// The CPU's clock during the probe (HFINT or HFXO, both 64 MHz).
const CPU_HZ: u32 = 64_000_000;
/// UICR.REGOUT0 (nRF52840 PS, UICR registers).
const UICR_REGOUT0: *const u32 = 0x1000_1304 as *const u32;
/// REGOUT0.VOUT of an erased UICR: the 1.8 V default.
const VOUT_ERASED: u32 = 0b111;

/// The 64 MHz clock's source.
#[derive(Debug, Clone, Copy, PartialEq, Eq, defmt::Format)]
pub enum HighClock {
    /// The 32 MHz crystal (HFXO).
    Crystal,
    /// HFXO did not start: the internal HFINT.
    Internal,
}

/// The 32.768 kHz clock's source (embassy-time's RTC1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, defmt::Format)]
pub enum LowClock {
    /// The 32.768 kHz crystal (LFXO).
    Crystal,
    /// LFXO did not start: synthesised from the HFXO.
    Synthesized,
    /// Neither crystal: the LFRC.
    Rc,
}

/// What the probe found and chose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, defmt::Format)]
pub struct Clocks {
    /// The HF clock.
    pub high: HighClock,
    /// The LF clock.
    pub low: LowClock,
    /// UICR.REGOUT0 was erased on a VDDH-powered board: 3.3 V is written now (the init then
    /// resets the chip once).
    pub regout0_written: bool,
}

/// Starts the crystals with bounded waits and checks REGOUT0; returns what to tell
/// `embassy_nrf::init` besides `base` and what was found.
pub fn probe(mut base: config::Config) -> (config::Config, Clocks) {
    count_cycles();
    let high = start_hfxo();
    let low = if lfxo_starts() {
        LowClock::Crystal
    } else if high == HighClock::Crystal {
        LowClock::Synthesized
    } else {
        LowClock::Rc
    };
    // The HFXO, if it runs, was started here and stays on; embassy must not wait for it.
    base.hfclk_source = HfclkSource::Internal;
    base.lfclk_source = match low {
        LowClock::Crystal => LfclkSource::ExternalXtal,
        LowClock::Synthesized => LfclkSource::Synthesized,
        LowClock::Rc => LfclkSource::InternalRC,
    };
    let regout0_written = regout0_erased_on_vddh();
    if regout0_written {
        base.dcdc.reg0_voltage = Some(Reg0Voltage::_3V3);
    }
    (
        base,
        Clocks {
            high,
            low,
            regout0_written,
        },
    )
}

/// Waits up to `limit_ms` for `ready`, timed on the core's cycle counter: a delay loop's
/// cycles per pass depend on the flash and the pipeline, and one that assumed a cycle each
/// waited four times its limit in the PIL (a dead LFXO held the boot 4 s, not 1 s).
fn wait(limit_ms: u32, ready: impl Fn() -> bool) -> bool {
    let start = DWT::cycle_count();
    while DWT::cycle_count().wrapping_sub(start) < CPU_HZ / 1_000 * limit_ms {
        if ready() {
            return true;
        }
    }
    ready()
}

/// Turns the cycle counter on (DEMCR.TRCENA, DWT_CTRL.CYCCNTENA; ARMv7-M ARM C1.6.5,
/// C1.8.7) for [`wait`].
fn count_cycles() {
    // SAFETY: read-modify-writes of two debug registers before anything else runs; nothing
    // else in the firmware uses the trace block.
    unsafe {
        (*DCB::PTR).demcr.modify(|w| w | 1 << 24);
        (*DWT::PTR).ctrl.modify(|w| w | 1);
    }
}

fn start_hfxo() -> HighClock {
    let clock = pac::CLOCK;
    clock.events_hfclkstarted().write_value(0);
    clock.tasks_hfclkstart().write_value(1);
    if wait(HFXO_WAIT_MS, || clock.events_hfclkstarted().read() != 0) {
        HighClock::Crystal
    } else {
        clock.tasks_hfclkstop().write_value(1);
        HighClock::Internal
    }
}

/// Starts the LFXO, waits for it, and stops it again either way.
fn lfxo_starts() -> bool {
    let clock = pac::CLOCK;
    clock
        .lfclksrc()
        .write(|w| w.set_src(pac::clock::vals::Lfclksrc::Xtal));
    clock.events_lfclkstarted().write_value(0);
    clock.tasks_lfclkstart().write_value(1);
    let started = wait(LFXO_WAIT_MS, || clock.events_lfclkstarted().read() != 0);
    clock.tasks_lfclkstop().write_value(1);
    // The source may be changed (and the clock started again) only once it has stopped.
    wait(HFXO_WAIT_MS, || !clock.lfclkstat().read().state());
    clock.events_lfclkstarted().write_value(0);
    started
}

/// VDDH supplies the chip and UICR.REGOUT0 still holds its erased value.
fn regout0_erased_on_vddh() -> bool {
    let high_voltage =
        pac::POWER.mainregstatus().read().mainregstatus() == pac::power::vals::Mainregstatus::High;
    // SAFETY: UICR.REGOUT0 is a readable word of the UICR (nRF52840 PS), always mapped.
    let regout0 = unsafe { UICR_REGOUT0.read_volatile() };
    high_voltage && regout0 & VOUT_ERASED == VOUT_ERASED
}
