//! The only file that names pins, DMA streams and interrupts. Mirrors
//! `hardware/brushedsparky/README.md` (and the Sparky2 column there).

use embassy_stm32::exti::ExtiInput;
use embassy_stm32::gpio::{Level, Output, Pull, Speed};
use embassy_stm32::mode::Async;
use embassy_stm32::peripherals::IWDG;
use embassy_stm32::spi::{self, Spi};
use embassy_stm32::time::Hertz;
use embassy_stm32::wdg::IndependentWatchdog;
use embassy_stm32::{
    Config, Peri, Peripherals, bind_interrupts, dma, exti, interrupt, peripherals,
};

/// Board name for the boot log.
#[cfg(not(feature = "sparky2"))]
pub const BOARD: &str = "BrushedSparky";
/// Board name for the boot log.
#[cfg(feature = "sparky2")]
pub const BOARD: &str = "Sparky2";

/// Independent watchdog timeout (Tau Labs used 250 ms).
pub const WATCHDOG_TIMEOUT_US: u32 = 250_000;

#[cfg(not(feature = "sparky2"))]
bind_interrupts!(pub struct Irqs {
    EXTI9_5 => exti::InterruptHandler<interrupt::typelevel::EXTI9_5>;
    DMA1_STREAM7 => dma::InterruptHandler<peripherals::DMA1_CH7>;
    DMA1_STREAM0 => dma::InterruptHandler<peripherals::DMA1_CH0>;
});
#[cfg(feature = "sparky2")]
bind_interrupts!(pub struct Irqs {
    EXTI2 => exti::InterruptHandler<interrupt::typelevel::EXTI2>;
    DMA1_STREAM7 => dma::InterruptHandler<peripherals::DMA1_CH7>;
    DMA1_STREAM0 => dma::InterruptHandler<peripherals::DMA1_CH0>;
});

/// HSE 8 MHz → PLL (M 8, N 336, P 2, Q 7): SYSCLK 168 MHz, USB 48 MHz; APB1 42 MHz
/// (timers 84 MHz), APB2 84 MHz (timers 168 MHz). The board has a ceramic resonator, so the
/// HSE runs as an oscillator, not in bypass.
pub fn clocks() -> Config {
    use embassy_stm32::rcc::{
        AHBPrescaler, APBPrescaler, Hse, HseMode, Pll, PllMul, PllPDiv, PllPreDiv, PllQDiv,
        PllSource, Sysclk, mux,
    };
    let mut config = Config::default();
    config.rcc.hse = Some(Hse {
        freq: Hertz(8_000_000),
        mode: HseMode::Oscillator,
    });
    config.rcc.pll_src = PllSource::HSE;
    config.rcc.pll = Some(Pll {
        prediv: PllPreDiv::DIV8,
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

/// The RFM22B on SPI3 (SCK PC10, MISO PC11, MOSI PC12), nSEL PA15, nIRQ on EXTI.
/// SDN is tied to GND on both boards: the only reset is the software one.
pub struct Radio {
    /// SPI3 with DMA1 stream 7 (TX) and stream 0 (RX).
    pub spi: Spi<'static, Async, spi::mode::Master>,
    /// nSEL, idle high.
    pub nsel: Output<'static>,
    /// nIRQ: PB7 (BrushedSparky) or PD2 (Sparky2), falling edge.
    pub nirq: ExtiInput<'static, Async>,
}

/// Everything the tasks own, split out of the peripheral singletons.
pub struct Board {
    /// Blue STAT/HEARTBEAT LED on PB5, active low.
    pub heartbeat_led: Output<'static>,
    /// The independent watchdog, not yet started.
    pub watchdog: IndependentWatchdog<'static, IWDG>,
    /// The radio module.
    pub radio: Radio,
}

impl Board {
    /// Claims the pins. Nothing is started here.
    pub fn new(p: Peripherals) -> Self {
        let mut spi_config = spi::Config::default();
        // Si4432: SPI mode 0, ≤ 10 MHz; APB1 42 MHz / 8 = 5.25 MHz as Tau Labs ran it.
        spi_config.frequency = Hertz(5_250_000);
        spi_config.mode = spi::MODE_0;
        let spi = Spi::new(
            p.SPI3, p.PC10, p.PC12, p.PC11, p.DMA1_CH7, p.DMA1_CH0, Irqs, spi_config,
        );
        Self {
            heartbeat_led: Output::new(p.PB5, Level::High, Speed::Low),
            watchdog: IndependentWatchdog::new(p.IWDG, WATCHDOG_TIMEOUT_US),
            radio: Radio {
                spi,
                nsel: Output::new(p.PA15, Level::High, Speed::VeryHigh),
                nirq: radio_irq(p.PB7, p.EXTI7, p.PD2, p.EXTI2),
            },
        }
    }
}

#[cfg(not(feature = "sparky2"))]
fn radio_irq(
    pb7: Peri<'static, peripherals::PB7>,
    exti7: Peri<'static, peripherals::EXTI7>,
    _pd2: Peri<'static, peripherals::PD2>,
    _exti2: Peri<'static, peripherals::EXTI2>,
) -> ExtiInput<'static, Async> {
    // BrushedSparky rev 0x22 moved nIRQ to PB7 (PD2 carries S.Bus there).
    ExtiInput::new(pb7, exti7, Pull::Up, Irqs)
}

#[cfg(feature = "sparky2")]
fn radio_irq(
    _pb7: Peri<'static, peripherals::PB7>,
    _exti7: Peri<'static, peripherals::EXTI7>,
    pd2: Peri<'static, peripherals::PD2>,
    exti2: Peri<'static, peripherals::EXTI2>,
) -> ExtiInput<'static, Async> {
    ExtiInput::new(pd2, exti2, Pull::Up, Irqs)
}
