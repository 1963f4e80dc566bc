//! The only file that names pins and interrupts. Mirrors `hardware/taulink-module/README.md`
//! (the nice!nano-class pin map it describes); change both together.

use embassy_nrf::gpio::{Input, Level, Output, OutputDrive, Pull};
use embassy_nrf::peripherals::{
    GPIOTE_CH0, NVMC, P0_02, P0_06, P0_08, P1_04, P1_06, P1_11, P1_13, PPI_CH0, PPI_CH1, PPI_CH2,
    PPI_CH3, PPI_CH4, PWM0, RNG, SAADC, TIMER1, TIMER2, TIMER3, UARTE0, UARTE1,
};
use embassy_nrf::spim::{self, Spim};
use embassy_nrf::wdt::{self, Watchdog, WatchdogHandle};
use embassy_nrf::{Peri, Peripherals, bind_interrupts, config, peripherals, saadc, uarte};

bind_interrupts!(pub struct Irqs {
    SPI2 => spim::InterruptHandler<peripherals::SPI2>;
    UARTE0 => uarte::InterruptHandler<peripherals::UARTE0>;
    UARTE1 => uarte::InterruptHandler<peripherals::UARTE1>;
    SAADC => saadc::InterruptHandler;
});

/// Watchdog period in 32 768 Hz ticks (module-core's `WATCHDOG_TIMEOUT_MS`, 300 ms).
const WATCHDOG_TICKS: u32 = 32_768 * module_core::watchdog::WATCHDOG_TIMEOUT_MS / 1_000;

/// Settings area in flash: 8 pages of 4 KiB below the UF2 bootloader (build.rs keeps the
/// image out of it in both layouts).
pub const SETTINGS_FLASH: core::ops::Range<u32> = 0xEC000..0xF4000;

/// The configuration besides the clock sources (`clocks::probe` chooses those: HFXO for
/// accurate UART baud rates, LFXO for the RTC that drives embassy-time, each with a fallback)
/// and REGOUT0: DC/DC on (the nice!nano fits the inductor).
pub fn config() -> config::Config {
    let mut config = config::Config::default();
    config.dcdc.reg1 = true;
    config
}

/// The RFM22B on SPIM2: SCK P0.17, MOSI P0.20, MISO P0.22, nSEL P0.24, nIRQ P0.11, SDN P1.00.
///
/// Not SPIM3: nRF52840 errata, anomaly 198 ("SPIM: SPIM3 transmit data might be corrupted",
/// Rev 1–3): SPIM3's EasyDMA reads wrong transmit bytes when the CPU or another master
/// touches the RAM block of its TXD buffer at the same time — with the radio task's buffers
/// in the same RAM as every other task's, that is any time. The errata's workaround is a
/// RAM block of its own for the buffer; SPIM0–2 are not affected at all, and their 8 MHz
/// limit is the rate the Si4432 runs at anyway (its limit is 10 MHz). SPIM2 shares its
/// peripheral ID only with SPIS2, both otherwise unused, so both TWI instances stay free.
pub struct Radio {
    /// SPIM2 at 8 MHz, mode 0.
    pub spim: Spim<'static>,
    /// nSEL, idle high.
    pub nsel: Output<'static>,
    /// nIRQ, active low (GPIOTE port event), internal pull-up.
    pub nirq: Input<'static>,
    /// SDN: high holds the radio in shutdown (hard reset); a 10 k pull-down keeps it on.
    pub sdn: Output<'static>,
    /// Hardware RNG: the bind ID of a new link.
    pub rng: Peri<'static, RNG>,
}

/// PPM input on JR pin 1 (P1.04): GPIOTE CH0 → PPI CH0 → TIMER1 CAPTURE[0].
pub struct PpmIn {
    /// Free-running 1 MHz time base.
    pub timer: Peri<'static, TIMER1>,
    /// The GPIOTE channel watching the pin.
    pub edge_channel: Peri<'static, GPIOTE_CH0>,
    /// The PPI channel from the edge event to the capture task.
    pub capture_channel: Peri<'static, PPI_CH0>,
    /// P1.04.
    pub pin: Peri<'static, P1_04>,
}

/// PPM output (receiver role) on P1.06 from PWM0 channel 0.
pub struct PpmOut {
    /// PWM0.
    pub pwm: Peri<'static, PWM0>,
    /// P1.06.
    pub pin: Peri<'static, P1_06>,
}

/// The half-duplex JR pin 5 line on UARTE0 behind the XOR and the tri-state buffer.
pub struct JrLine {
    /// UARTE0, re-created per direction.
    pub uarte: Peri<'static, UARTE0>,
    /// P0.06, UARTE0 TXD.
    pub tx: Peri<'static, P0_06>,
    /// P0.08, UARTE0 RXD.
    pub rx: Peri<'static, P0_08>,
    /// Idle-line detection for received frames: TIMER2 with PPI CH1/CH2.
    pub idle_timer: Peri<'static, TIMER2>,
    /// First PPI channel of the idle detection.
    pub idle_ppi_start: Peri<'static, PPI_CH1>,
    /// Second PPI channel of the idle detection.
    pub idle_ppi_stop: Peri<'static, PPI_CH2>,
    /// P0.09: buffer output enable, high only while sending.
    pub driver_enable: Output<'static>,
    /// P0.10: XOR control, high = inverted line.
    pub invert: Output<'static>,
}

/// The HM-10 on UARTE1: P1.11 to its RXD, P1.13 from its TXD.
pub struct Hm10 {
    /// UARTE1.
    pub uarte: Peri<'static, UARTE1>,
    /// P1.11, UARTE1 TXD.
    pub tx: Peri<'static, P1_11>,
    /// P1.13, UARTE1 RXD.
    pub rx: Peri<'static, P1_13>,
    /// Idle-line detection: TIMER3 with PPI CH3/CH4.
    pub idle_timer: Peri<'static, TIMER3>,
    /// First PPI channel of the idle detection.
    pub idle_ppi_start: Peri<'static, PPI_CH3>,
    /// Second PPI channel of the idle detection.
    pub idle_ppi_stop: Peri<'static, PPI_CH4>,
}

impl JrLine {
    /// UARTE0 receiving at `baud` with idle-line detection (the buffer must be off).
    pub fn receiver(&mut self, baud: u32) -> uarte::UarteRxWithIdle<'_> {
        uarte::UarteRx::new(
            self.uarte.reborrow(),
            Irqs,
            self.rx.reborrow(),
            jr_line_config(baud),
        )
        .with_idle(
            self.idle_timer.reborrow(),
            self.idle_ppi_start.reborrow(),
            self.idle_ppi_stop.reborrow(),
        )
    }

    /// Sends `bytes` (if any) at `baud` with the buffer enabled only for them; dropping the
    /// transmitter afterwards disables UARTE0 and frees the pins for the next direction.
    pub async fn send(&mut self, baud: u32, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        self.driver_enable.set_high();
        {
            let mut tx = uarte::UarteTx::new(
                self.uarte.reborrow(),
                Irqs,
                self.tx.reborrow(),
                jr_line_config(baud),
            );
            if tx.write(bytes).await.is_err() {
                defmt::warn!("JR line write failed");
            }
            // ENDTX comes when the last byte is loaded, not sent: wait two byte times before
            // the drop disables the UARTE and the buffer lets go of the line.
            embassy_time::Timer::after_micros(u64::from(2 * 10 * 1_000_000 / baud) + 1).await;
        }
        self.driver_enable.set_low();
    }
}

/// UARTE BAUDRATE register for `baud` (`module_core::handset::uarte_baudrate`: 0x0666_6000
/// ≈ 399 994 Bd for CRSF); a rate beyond the UARTE falls back to 400 kBd (the settings offer
/// none).
const fn baud_register(baud: u32) -> uarte::Baudrate {
    match module_core::handset::uarte_baudrate(baud) {
        Some(bits) => uarte::Baudrate::from_bits(bits),
        None => uarte::Baudrate::from_bits(0x0666_6000),
    }
}

fn jr_line_config(baud: u32) -> uarte::Config {
    let mut config = uarte::Config::default();
    config.baudrate = baud_register(baud);
    config
}

impl Hm10 {
    /// UARTE1 at `baud` (9600 or else 115 200, the HM-10's rates), split, receiving with
    /// idle-line detection.
    pub fn open(&mut self, baud: u32) -> (uarte::UarteTx<'_>, uarte::UarteRxWithIdle<'_>) {
        let mut config = uarte::Config::default();
        config.baudrate = if baud == 9_600 {
            uarte::Baudrate::Baud9600
        } else {
            uarte::Baudrate::Baud115200
        };
        uarte::Uarte::new(
            self.uarte.reborrow(),
            self.rx.reborrow(),
            self.tx.reborrow(),
            Irqs,
            config,
        )
        .split_with_idle(
            self.idle_timer.reborrow(),
            self.idle_ppi_start.reborrow(),
            self.idle_ppi_stop.reborrow(),
        )
    }
}

/// Radio battery sense on P0.02 (AIN0) behind the 100 k / 22 k divider.
pub struct Battery {
    /// The SAADC.
    pub saadc: Peri<'static, SAADC>,
    /// P0.02 = AIN0.
    pub pin: Peri<'static, P0_02>,
}

/// Everything the tasks own.
pub struct Board {
    /// On-board LED P0.15, active high.
    pub status_led: Output<'static>,
    /// Bind button P1.15 to GND, internal pull-up.
    pub bind_button: Input<'static>,
    /// Watchdog handle, `None` if the WDT was already running with another setup.
    pub watchdog: Option<WatchdogHandle>,
    /// The radio module.
    pub radio: Radio,
    /// PPM input.
    pub ppm_in: PpmIn,
    /// PPM output.
    pub ppm_out: PpmOut,
    /// JR pin 5 line.
    pub jr_line: JrLine,
    /// HM-10 UART.
    pub hm10: Hm10,
    /// Battery sense.
    pub battery: Battery,
    /// Flash controller for the settings.
    pub nvmc: Peri<'static, NVMC>,
}

impl Board {
    /// Claims the pins and starts the watchdog (the nRF52 WDT cannot be configured later:
    /// it starts on configuration, so the supervisor must be spawned right after this).
    pub fn new(p: Peripherals) -> Self {
        let mut spi_config = spim::Config::default();
        // Si4432 limit is 10 MHz; 8 MHz is the nearest SPIM rate below it (and SPIM2's top).
        spi_config.frequency = spim::Frequency::M8;
        spi_config.mode = spim::MODE_0;
        let spim = Spim::new(p.SPI2, Irqs, p.P0_17, p.P0_22, p.P0_20, spi_config);

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
            bind_button: Input::new(p.P1_15, Pull::Up),
            watchdog,
            radio: Radio {
                spim,
                nsel: Output::new(p.P0_24, Level::High, OutputDrive::Standard),
                nirq: Input::new(p.P0_11, Pull::Up),
                sdn: Output::new(p.P1_00, Level::Low, OutputDrive::Standard),
                rng: p.RNG,
            },
            ppm_in: PpmIn {
                timer: p.TIMER1,
                edge_channel: p.GPIOTE_CH0,
                capture_channel: p.PPI_CH0,
                pin: p.P1_04,
            },
            ppm_out: PpmOut {
                pwm: p.PWM0,
                pin: p.P1_06,
            },
            jr_line: JrLine {
                uarte: p.UARTE0,
                tx: p.P0_06,
                rx: p.P0_08,
                idle_timer: p.TIMER2,
                idle_ppi_start: p.PPI_CH1,
                idle_ppi_stop: p.PPI_CH2,
                // Buffer off (line released) and non-inverted until the line task decides.
                driver_enable: Output::new(p.P0_09, Level::Low, OutputDrive::Standard),
                invert: Output::new(p.P0_10, Level::Low, OutputDrive::Standard),
            },
            hm10: Hm10 {
                uarte: p.UARTE1,
                tx: p.P1_11,
                rx: p.P1_13,
                idle_timer: p.TIMER3,
                idle_ppi_start: p.PPI_CH3,
                idle_ppi_stop: p.PPI_CH4,
            },
            battery: Battery {
                saadc: p.SAADC,
                pin: p.P0_02,
            },
            nvmc: p.NVMC,
        }
    }
}
