//! The only file that names pins and interrupts. Mirrors `hardware/taulink-module/README.md`
//! (the nice!nano-class pin map proposed in hardware.md §5).

use embassy_nrf::gpio::{Input, Level, Output, OutputDrive, Pull};
use embassy_nrf::spim::{self, Spim};
use embassy_nrf::wdt::{self, Watchdog, WatchdogHandle};
use embassy_nrf::{Peripherals, bind_interrupts, config, peripherals};

bind_interrupts!(pub struct Irqs {
    SPIM3 => spim::InterruptHandler<peripherals::SPI3>;
});

/// Watchdog period in 32 768 Hz ticks (250 ms).
const WATCHDOG_TICKS: u32 = 32_768 / 4;

/// HFXO for the radio-grade 64 MHz clock and accurate UART baud rates; LFXO for the RTC
/// that drives embassy-time. DC/DC on (the nice!nano fits the inductor).
pub fn clocks() -> config::Config {
    let mut config = config::Config::default();
    config.hfclk_source = config::HfclkSource::ExternalXtal;
    config.lfclk_source = config::LfclkSource::ExternalXtal;
    config.dcdc.reg1 = true;
    config
}

/// The RFM22B on SPIM3: SCK P0.17, MOSI P0.20, MISO P0.22, nSEL P0.24, nIRQ P0.11, SDN P1.00.
pub struct Radio {
    /// SPIM3 at 8 MHz, mode 0.
    pub spim: Spim<'static>,
    /// nSEL, idle high.
    pub nsel: Output<'static>,
    /// nIRQ, active low (GPIOTE port event), internal pull-up.
    pub nirq: Input<'static>,
    /// SDN: high holds the radio in shutdown (hard reset); a 10 k pull-down keeps it on.
    pub sdn: Output<'static>,
}

/// Everything the tasks own.
pub struct Board {
    /// On-board LED P0.15, active high.
    pub status_led: Output<'static>,
    /// Watchdog handle, `None` if the WDT was already running with another setup.
    pub watchdog: Option<WatchdogHandle>,
    /// The radio module.
    pub radio: Radio,
}

impl Board {
    /// Claims the pins and starts the watchdog (the nRF52 WDT cannot be configured later:
    /// it starts on configuration, so the supervisor must be spawned right after this).
    pub fn new(p: Peripherals) -> Self {
        let mut spi_config = spim::Config::default();
        // Si4432 limit is 10 MHz; 8 MHz is the nearest SPIM rate below it.
        spi_config.frequency = spim::Frequency::M8;
        spi_config.mode = spim::MODE_0;
        let spim = Spim::new(p.SPI3, Irqs, p.P0_17, p.P0_22, p.P0_20, spi_config);

        let mut wdt_config = wdt::Config::default();
        wdt_config.timeout_ticks = WATCHDOG_TICKS;
        // Counting on while a debugger halts the CPU would reset under every breakpoint.
        wdt_config.action_during_debug_halt = wdt::HaltConfig::Pause;
        let watchdog = match Watchdog::try_new::<_, 1>(p.WDT, wdt_config) {
            Ok((_wdt, [handle])) => Some(handle),
            Err(_) => None,
        };

        Self {
            status_led: Output::new(p.P0_15, Level::Low, OutputDrive::Standard),
            watchdog,
            radio: Radio {
                spim,
                nsel: Output::new(p.P0_24, Level::High, OutputDrive::Standard),
                nirq: Input::new(p.P0_11, Pull::Up),
                sdn: Output::new(p.P1_00, Level::Low, OutputDrive::Standard),
            },
        }
    }
}
