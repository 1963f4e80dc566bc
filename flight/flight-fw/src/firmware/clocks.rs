//! The clock tree and the flash accelerator: what `embassy_stm32::init` is given and what it
//! leaves undone.
//!
//! - **HSE probe.** embassy-stm32's RCC init waits for HSERDY without a limit
//!   (`rcc/f247.rs`: `while !RCC.cr().read().hserdy() {}`), before any watchdog runs: a
//!   cracked or missing 8 MHz resonator would hang the board at power-up for good. [`probe`]
//!   starts the HSE itself and waits at most [`HSE_WAIT_MS`] (DS8626: t_SU(HSE) 2 ms typical);
//!   without it the board runs the same tree from the 16 MHz HSI ([`Clocks::HsiFallback`]:
//!   every bus clock identical, USB's 48 MHz only HSI-accurate, ±1 % against USB's ±0.25 %,
//!   so the console may not enumerate) and says so in `status`.
//! - **Flash accelerator.** The init writes `FLASH_ACR` whole with the latency (5 wait
//!   states at 168 MHz), which leaves prefetch, I-cache and D-cache off: every instruction
//!   fetch past a 128-bit line waits 5 cycles. [`accelerate_flash`] resets and enables both
//!   caches and the prefetch (RM0090 §3.5.2 "Adaptive real-time memory accelerator"); on
//!   revision A silicon (REV_ID 0x1000) the prefetch stays off, as ST's HAL configuration
//!   requires ("RevA (prefetch must be off)").
//! - **Flash writes.** A sector erase or a program changes flash that the D-cache may hold:
//!   [`DataCacheOff`] keeps the D-cache off over a settings write and resets it before
//!   turning it back on (RM0090 `FLASH_ACR.DCRST`: "written only when the data cache is
//!   disabled"), as embassy-stm32 does itself only on dual-bank parts.

use embassy_stm32::pac;
use embassy_stm32::time::Hertz;
use embassy_stm32::{Config, rcc};

/// The HSE's start-up limit, ms (DS8626 t_SU(HSE): 2 ms typical for an 8 MHz crystal; the
/// board's ceramic resonator starts faster).
pub const HSE_WAIT_MS: u32 = 20;
/// The HSI's frequency, which runs the CPU until the clock tree is set up.
const HSI_HZ: u32 = 16_000_000;
/// DEMCR.TRCENA: the DWT and ITM blocks on (ARMv7-M ARM C1.6.5).
const DEMCR_TRCENA: u32 = 1 << 24;
/// DWT_CTRL.CYCCNTENA: the cycle counter counts (ARMv7-M ARM C1.8.7).
const DWT_CYCCNTENA: u32 = 1;
/// DBGMCU_IDCODE.REV_ID of revision A silicon (ES0182 table 1).
const REV_A: u16 = 0x1000;

/// What the clock tree runs from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, defmt::Format)]
pub enum Clocks {
    /// The 8 MHz HSE, as designed.
    Hse,
    /// The HSE never became ready within [`HSE_WAIT_MS`]: the same tree from the HSI.
    HsiFallback,
}

/// Starts the HSE and waits for it at most [`HSE_WAIT_MS`], counted on the core's cycle
/// counter (the CPU still runs from the HSI after reset, 16 MHz): a delay loop's cycles per
/// pass depend on the flash and the pipeline, and one that assumed a cycle each waited
/// 80 ms in the PIL. A running HSE stays on for `embassy_stm32::init`, whose own wait then
/// ends at once; a dead one is switched off.
pub fn probe() -> Clocks {
    use cortex_m::peripheral::{DCB, DWT};
    // SAFETY: sets DEMCR.TRCENA and DWT_CTRL.CYCCNTENA, read-modify-write before anything
    // else runs; nothing owns the trace block yet (the seeds read the counter later).
    unsafe {
        (*DCB::PTR).demcr.modify(|w| w | DEMCR_TRCENA);
        (*DWT::PTR).ctrl.modify(|w| w | DWT_CYCCNTENA);
    }
    let rcc = pac::RCC;
    rcc.cr().modify(|w| {
        w.set_hsebyp(false);
        w.set_hseon(true);
    });
    let start = DWT::cycle_count();
    while DWT::cycle_count().wrapping_sub(start) < HSI_HZ / 1_000 * HSE_WAIT_MS {
        if rcc.cr().read().hserdy() {
            return Clocks::Hse;
        }
    }
    rcc.cr().modify(|w| w.set_hseon(false));
    Clocks::HsiFallback
}

/// 8 MHz (HSE, or HSI ÷ 2 at the PLL input) → PLL (N 336, P 2, Q 7): SYSCLK 168 MHz, USB
/// 48 MHz; APB1 42 MHz (timers 84 MHz), APB2 84 MHz (timers 168 MHz). The board has a
/// ceramic resonator, so the HSE runs as an oscillator, not in bypass. Both sources give
/// the PLL the same 1 MHz input, so every peripheral clock is the same either way.
pub fn config(clocks: Clocks) -> Config {
    use rcc::{
        AHBPrescaler, APBPrescaler, Hse, HseMode, Pll, PllMul, PllPDiv, PllPreDiv, PllQDiv,
        PllSource, Sysclk, mux,
    };
    let mut config = Config::default();
    let (source, prediv) = match clocks {
        Clocks::Hse => {
            config.rcc.hse = Some(Hse {
                freq: Hertz(8_000_000),
                mode: HseMode::Oscillator,
            });
            (PllSource::HSE, PllPreDiv::DIV8)
        }
        Clocks::HsiFallback => (PllSource::HSI, PllPreDiv::DIV16),
    };
    config.rcc.pll_src = source;
    config.rcc.pll = Some(Pll {
        prediv,
        mul: PllMul::MUL336,
        divp: Some(PllPDiv::DIV2),
        divq: Some(PllQDiv::DIV7),
        divr: None,
    });
    config.rcc.sys = Sysclk::PLL1_P;
    config.rcc.ahb_pre = AHBPrescaler::DIV1;
    config.rcc.apb1_pre = APBPrescaler::DIV4;
    config.rcc.apb2_pre = APBPrescaler::DIV2;
    config.rcc.mux.clk48sel = mux::Clk48sel::PLL1_Q;
    config
}

/// Turns the flash accelerator on after `embassy_stm32::init` set the wait states: both
/// caches reset, then enabled, and the prefetch unless the silicon is revision A.
pub fn accelerate_flash() {
    let flash = pac::FLASH;
    let prefetch = pac::DBGMCU.idcode().read().rev_id() != REV_A;
    // The reset bits may only be written while the caches are off (they are: the init
    // wrote the register whole).
    flash.acr().modify(|w| {
        w.set_icen(false);
        w.set_dcen(false);
    });
    flash.acr().modify(|w| {
        w.set_icrst(true);
        w.set_dcrst(true);
    });
    flash.acr().modify(|w| {
        w.set_icrst(false);
        w.set_dcrst(false);
    });
    flash.acr().modify(|w| {
        w.set_icen(true);
        w.set_dcen(true);
        w.set_prften(prefetch);
    });
}

/// Keeps the D-cache off while it lives (around a settings write: sector erase and
/// programming) and resets the cache before enabling it again, so no line it held of the
/// rewritten flash survives. A guard rather than a wrapper future: wrapping the write's
/// future would store it twice in the task's state.
pub struct DataCacheOff(());

impl DataCacheOff {
    /// The D-cache off from now until the guard drops.
    pub fn new() -> Self {
        pac::FLASH.acr().modify(|w| w.set_dcen(false));
        Self(())
    }
}

impl Drop for DataCacheOff {
    fn drop(&mut self) {
        let flash = pac::FLASH;
        flash.acr().modify(|w| w.set_dcrst(true));
        flash.acr().modify(|w| w.set_dcrst(false));
        flash.acr().modify(|w| w.set_dcen(true));
    }
}
