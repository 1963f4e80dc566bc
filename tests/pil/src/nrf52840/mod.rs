//! The nRF52840 of the TauLink module image, register by register ([`Nrf52840`], an
//! `m4_sim::Bus`): flash, RAM, FICR/UICR, CLOCK/POWER, NVMC, GPIO/GPIOTE, PPI, RTC, TIMER,
//! SPIM, UARTE, SAADC, WDT, RNG, PWM and TEMP's calibration registers, each as much as the
//! image and embassy-nrf 0.11 use, on the virtual time of the board around it
//! (`crate::wire::Outside`). What each block models, what not, and the numbers with their
//! sources: `README.md` in this folder.

mod boot;
mod clock;
mod events;
mod ficr;
mod gpio;
mod gpiote;
pub mod map;
mod memory;
mod nvmc;
mod parts;
mod ppi;
mod pwm;
mod records;
mod rng;
mod rtc;
mod saadc;
mod soc;
mod spim;
mod temp;
mod timer;
mod uarte;
mod wdt;

pub use boot::{BOOTLOADER, FORWARD_WORD, REGOUT0_3V3};
pub use clock::{ClockFaults, Supply, resetreas};
pub use ficr::Variant;
pub use memory::{Anomaly198, Anomaly198Hit, Anomaly198Mode, Master, regout0_volts, uicr};
pub use nvmc::FlashTiming;
pub use records::{DmaFault, Note, Records, Unmodelled};
pub use soc::{Config, LoadError, Nrf52840, ResetRecord};
pub use uarte::{bit_ps as uarte_bit_ps, resample as uarte_resample};
pub use wdt::RELOAD as WDT_RELOAD;

#[cfg(test)]
mod tests;
