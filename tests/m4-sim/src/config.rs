//! The implementation choices a chip vendor makes when it builds a Cortex-M4F into a SoC,
//! which the SoC model passes to [`crate::Cpu::new`].

/// How the core is configured inside its chip.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Config {
    /// Implemented priority bits (the top bits of each 8-bit priority field): 4 on the
    /// STM32F405, 3 on the nRF52840.
    pub prio_bits: u8,
    /// External interrupt lines the NVIC implements (at most 240).
    pub irqs: u16,
    /// SysTick's external reference clock as a divider of the core clock (the STM32F405
    /// feeds HCLK/8), or `None` when there is none (CALIB.NOREF reads 1).
    pub systick_ref_div: Option<u32>,
    /// CALIB.TENMS: the reload value for 10 ms on the reference clock (0: not known, and
    /// CALIB.SKEW reads 1).
    pub systick_tenms: u32,
    /// Whether the bit-band regions (0x2200_0000 and 0x4200_0000) are implemented.
    pub bitband: bool,
    /// A BKPT other than semihosting's stops [`crate::Cpu::run_until`] (as a debugger
    /// would); when false it escalates to HardFault, as on a chip with no debugger.
    pub halt_on_bkpt: bool,
    /// The core clock until the bus first reports one (Hz).
    pub initial_hz: u32,
}

impl Default for Config {
    /// A generic Cortex-M4F: 4 priority bits, 240 interrupts, no SysTick reference,
    /// bit-banding, BKPT halts, 16 MHz.
    fn default() -> Self {
        Config {
            prio_bits: 4,
            irqs: 240,
            systick_ref_div: None,
            systick_tenms: 0,
            bitband: true,
            halt_on_bkpt: true,
            initial_hz: 16_000_000,
        }
    }
}
