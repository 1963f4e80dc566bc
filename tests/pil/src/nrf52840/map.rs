//! The nRF52840's memory map and interrupt numbers (nRF52840 Product Specification v1.7,
//! "Memory" and "Instantiation" tables; register offsets cross-checked against Nordic's SVD
//! as `nrf-pac` 0.4.0 carries it). Every address the model decodes is declared here once.

/// Code flash: 1 MiB from 0 (256 pages of 4 KiB).
pub const FLASH_BASE: u32 = 0x0000_0000;
/// Flash size in bytes.
pub const FLASH_SIZE: u32 = 0x10_0000;
/// Flash page (erase unit) size in bytes (FICR.CODEPAGESIZE).
pub const FLASH_PAGE: u32 = 0x1000;
/// The Data RAM seen on the code bus (instruction fetches from RAM).
pub const CODE_RAM_BASE: u32 = 0x0080_0000;
/// Data RAM: 256 KiB.
pub const RAM_BASE: u32 = 0x2000_0000;
/// RAM size in bytes.
pub const RAM_SIZE: u32 = 0x4_0000;
/// Factory information configuration registers.
pub const FICR_BASE: u32 = 0x1000_0000;
/// User information configuration registers (one flash page written through the NVMC).
pub const UICR_BASE: u32 = 0x1000_1000;
/// Size of the FICR and UICR pages.
pub const INFO_PAGE_SIZE: u32 = 0x1000;
/// The AHB peripherals' window (one 4 KiB slot per peripheral ID).
pub const PERIPH_BASE: u32 = 0x4000_0000;
/// Past the last peripheral slot the model decodes (ID 0x3F).
pub const PERIPH_END: u32 = 0x4004_0000;
/// GPIO ports P0 and P1 (AHB, not on the event bus).
pub const GPIO_BASE: u32 = 0x5000_0000;
/// Past the GPIO window.
pub const GPIO_END: u32 = 0x5000_1000;

/// Peripheral base addresses (PS "Instantiation"). The peripheral ID is address bits 17:12
/// and is also its interrupt number.
pub mod base {
    /// CLOCK and POWER (one ID, one interrupt).
    pub const CLOCK_POWER: u32 = 0x4000_0000;
    /// UARTE0.
    pub const UARTE0: u32 = 0x4000_2000;
    /// SPIM0 (shares its ID with SPIS0, TWIM0, TWIS0).
    pub const SPIM0: u32 = 0x4000_3000;
    /// SPIM1.
    pub const SPIM1: u32 = 0x4000_4000;
    /// GPIOTE.
    pub const GPIOTE: u32 = 0x4000_6000;
    /// SAADC.
    pub const SAADC: u32 = 0x4000_7000;
    /// TIMER0.
    pub const TIMER0: u32 = 0x4000_8000;
    /// TIMER1.
    pub const TIMER1: u32 = 0x4000_9000;
    /// TIMER2.
    pub const TIMER2: u32 = 0x4000_A000;
    /// RTC0.
    pub const RTC0: u32 = 0x4000_B000;
    /// TEMP.
    pub const TEMP: u32 = 0x4000_C000;
    /// RNG.
    pub const RNG: u32 = 0x4000_D000;
    /// WDT.
    pub const WDT: u32 = 0x4001_0000;
    /// RTC1 (embassy-time's driver).
    pub const RTC1: u32 = 0x4001_1000;
    /// TIMER3.
    pub const TIMER3: u32 = 0x4001_A000;
    /// TIMER4.
    pub const TIMER4: u32 = 0x4001_B000;
    /// PWM0.
    pub const PWM0: u32 = 0x4001_C000;
    /// NVMC (shares its ID with ACL).
    pub const NVMC: u32 = 0x4001_E000;
    /// PPI.
    pub const PPI: u32 = 0x4001_F000;
    /// SPIM2.
    pub const SPIM2: u32 = 0x4002_3000;
    /// RTC2.
    pub const RTC2: u32 = 0x4002_4000;
    /// UARTE1.
    pub const UARTE1: u32 = 0x4002_8000;
    /// SPIM3.
    pub const SPIM3: u32 = 0x4002_F000;
}

/// The 4 KiB slot of a peripheral address.
pub const fn slot(addr: u32) -> u32 {
    addr & !0xFFF
}

/// A peripheral's interrupt number: its ID, address bits 17:12 (PS "Peripheral interface").
pub const fn irq_of(base: u32) -> u32 {
    (base >> 12) & 0x3F
}

/// The core clock: the CPU always runs at 64 MHz from HFCLK (HFINT or HFXO).
pub const CORE_HZ: u32 = 64_000_000;

/// `PSEL` registers: pin number bits 4:0, port bit 5, CONNECT bit 31 (1 = disconnected).
pub mod psel {
    use crate::wire::Pin;

    /// The pin a `PSEL` value connects, if any.
    pub const fn pin(value: u32) -> Option<Pin> {
        if value & (1 << 31) != 0 {
            return None;
        }
        let port = ((value >> 5) & 1) as u8;
        let number = (value & 0x1F) as u8;
        if port == 1 && number >= super::P1_PINS {
            return None;
        }
        Some(Pin::new(port, number))
    }

    /// The reset value of every `PSEL` register: disconnected.
    pub const DISCONNECTED: u32 = 0xFFFF_FFFF;
}

/// Pins of port P1 (P1.00–P1.15); P0 has 32.
pub const P1_PINS: u8 = 16;
