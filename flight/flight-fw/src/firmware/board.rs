//! The only file that names pins, DMA streams and interrupts. Mirrors
//! `hardware/brushedsparky/README.md` (and the Sparky2 column there).

use embassy_stm32::adc::{Adc, AdcChannel};
use embassy_stm32::dac::DacChannel;
use embassy_stm32::exti::ExtiInput;
use embassy_stm32::flash::{Bank1Region1, Blocking, Flash};
#[cfg(not(feature = "sparky2"))]
use embassy_stm32::gpio::OutputOpenDrain;
use embassy_stm32::gpio::{Flex, Level, Output, OutputType, Pull, Speed};
use embassy_stm32::i2c::{self, I2c};
use embassy_stm32::peripherals::{TIM3, TIM9};
use embassy_stm32::timer::Channel;
use embassy_stm32::timer::low_level::Timer;
use embassy_stm32::timer::simple_pwm::PwmPin;
use embassy_stm32::usb::{self, Driver};
use flight_app::alerts::{DAC_SAMPLES_PER_CYCLE, sine_table};
use flight_app::outputs::{OutputError, Protocol};
use static_cell::StaticCell;

use super::outputs::MotorTimer;
use super::tasks::alerts::Speaker;
use super::tasks::battery::BatterySense;
use super::tasks::motors::{MotorPins, Motors};
use embassy_stm32::mode::{self, Async};
use embassy_stm32::peripherals::IWDG;
use embassy_stm32::spi::{self, Spi};
use embassy_stm32::time::Hertz;
#[cfg(feature = "sparky2")]
use embassy_stm32::usart;
use embassy_stm32::{Peri, Peripherals, bind_interrupts, dma, exti, interrupt, peripherals};

/// Board name for the boot log.
#[cfg(not(feature = "sparky2"))]
pub const BOARD: &str = "BrushedSparky";
/// Board name for the boot log.
#[cfg(feature = "sparky2")]
pub const BOARD: &str = "Sparky2";

// DMA streams (RM0090 tables 42/43): DAC1 on DMA1 S5; I2C1 (baro) TX S6, RX S0 (channel
// 1); SPI1 (IMU) TX DMA2 S3, RX DMA2 S0 (channel 3); SPI3 (radio) polls, without DMA.
// EXTI9_5 serves the IMU's data-ready (EXTI5) and, on the BrushedSparky, the radio's nIRQ
// (EXTI7).
bind_interrupts!(pub struct Irqs {
    #[cfg(feature = "sparky2")]
    USART1 => usart::InterruptHandler<peripherals::USART1>;
    #[cfg(feature = "sparky2")]
    DMA2_STREAM2 => dma::InterruptHandler<peripherals::DMA2_CH2>;
    #[cfg(feature = "sparky2")]
    DMA2_STREAM7 => dma::InterruptHandler<peripherals::DMA2_CH7>;
    #[cfg(feature = "sparky2")]
    EXTI2 => exti::InterruptHandler<interrupt::typelevel::EXTI2>;
    EXTI9_5 => exti::InterruptHandler<interrupt::typelevel::EXTI9_5>;
    DMA1_STREAM5 => dma::InterruptHandler<peripherals::DMA1_CH5>;
    OTG_FS => usb::InterruptHandler<peripherals::USB_OTG_FS>;
    DMA1_STREAM6 => dma::InterruptHandler<peripherals::DMA1_CH6>;
    DMA1_STREAM0 => dma::InterruptHandler<peripherals::DMA1_CH0>;
    DMA2_STREAM3 => dma::InterruptHandler<peripherals::DMA2_CH3>;
    DMA2_STREAM0 => dma::InterruptHandler<peripherals::DMA2_CH0>;
    I2C1_EV => i2c::EventInterruptHandler<peripherals::I2C1>;
    I2C1_ER => i2c::ErrorInterruptHandler<peripherals::I2C1>;
});

/// MPU9250 clock for configuration registers (≤ 1 MHz): APB2 84 MHz / 128.
pub const IMU_SPI_SLOW_HZ: u32 = 656_250;
/// MPU9250 clock for sensor reads (≤ 20 MHz): APB2 84 MHz / 8, as Tau Labs ran it.
pub const IMU_SPI_FAST_HZ: u32 = 10_500_000;

/// The MS5611's I²C address (CSB to GND).
pub const BARO_ADDRESS: u8 = 0x77;

/// MPU9250 axes → body FRD. The chip's z points up out of the board (it reads +1 g lying
/// flat) and the board mounts it "top, 180°" (Tau Labs
/// `flight/targets/sparky2/fw/pios_board.c`, `hardware/brushedsparky/README.md`): chip x points
/// aft, chip y to the right, so body = (−x, y, −z). A proper rotation: accelerometer, gyro and
/// magnetometer vectors all map the same way.
pub fn imu_to_body(v: [f32; 3]) -> [f32; 3] {
    let [x, y, z] = v;
    [-x, y, -z]
}

/// The MPU9250 on SPI1 (SCK PA5, MISO PA6, MOSI PA7), CS PC4, data-ready PC5 (EXTI5).
pub struct Imu {
    /// SPI1 with DMA2 streams 3 (TX) and 0 (RX).
    pub spi: Spi<'static, Async, spi::mode::Master>,
    /// Chip select, idle high.
    pub cs: Output<'static>,
    /// INT, rising edge at each new sample.
    pub int: ExtiInput<'static, Async>,
}

/// The MS5611 on I2C1 (SCL PB8, SDA PB9, 10 k pull-ups on the board), 400 kHz, with DMA1
/// streams 6 (TX) and 0 (RX). Kept as parts: the bus clear drives the pins as GPIO before
/// each (re-)initialisation of the driver.
pub struct Baro {
    i2c: Peri<'static, peripherals::I2C1>,
    scl: Peri<'static, peripherals::PB8>,
    sda: Peri<'static, peripherals::PB9>,
    tx_dma: Peri<'static, peripherals::DMA1_CH6>,
    rx_dma: Peri<'static, peripherals::DMA1_CH0>,
}

impl Baro {
    /// Clears the bus (`i2c_bus::recover`); whether SDA was released.
    pub fn recover_bus(&mut self) -> bool {
        let mut scl = Flex::new(self.scl.reborrow());
        let mut sda = Flex::new(self.sda.reborrow());
        super::i2c_bus::recover(&mut scl, &mut sda)
    }

    /// I2C1 at 400 kHz, initialised afresh (dropping it disables the peripheral).
    pub fn driver(&mut self) -> I2c<'_, Async, i2c::Master> {
        let mut config = i2c::Config::default();
        config.frequency = Hertz(400_000);
        I2c::new(
            self.i2c.reborrow(),
            self.scl.reborrow(),
            self.sda.reborrow(),
            self.tx_dma.reborrow(),
            self.rx_dma.reborrow(),
            Irqs,
            config,
        )
    }
}

/// The RFM22B on SPI3 (SCK PC10, MISO PC11, MOSI PC12), nSEL PA15, nIRQ on EXTI.
/// SDN is tied to GND on both boards: the only reset is the software one.
pub struct Radio {
    /// SPI3, polled, without DMA (why: `tasks/link.rs`).
    pub spi: Spi<'static, mode::Blocking, spi::mode::Master>,
    /// nSEL, idle high.
    pub nsel: Output<'static>,
    /// nIRQ: PB7 (BrushedSparky) or PD2 (Sparky2), falling edge.
    pub nirq: ExtiInput<'static, Async>,
}

/// Drives motor outputs 1–4 low as GPIO, at once, by register: for the fault handlers,
/// which cannot trust the timers' state or any HAL object. Low is off for every protocol
/// (no pulse; the brushed FETs off).
pub fn motors_off() {
    use embassy_stm32::pac;
    use embassy_stm32::pac::gpio::regs::Bsrr;
    // Output 1 PB0, 2 PB1, 3 PA3, 4 PA2 (`MotorParts::start`), as masks: straight-line
    // register writes (the metapac's per-pin setters assert the pin number, a panic path
    // inside the panic handler).
    const ON_B: u32 = (1 << 0) | (1 << 1);
    const ON_A: u32 = (1 << 3) | (1 << 2);
    for (port, pins, (mask, output)) in [
        (pac::GPIOB, ON_B, const { mode_bits(ON_B) }),
        (pac::GPIOA, ON_A, const { mode_bits(ON_A) }),
    ] {
        // The output level first (no effect while in AF mode), then the mode: the pin goes
        // low the moment it becomes a GPIO.
        port.bsrr().write_value(Bsrr(pins << 16));
        port.moder().modify(|w| w.0 = (w.0 & !mask) | output);
    }
}

/// MODER's two-bit fields of the pins set in `pins`: their mask, and 0b01 (output) in each.
const fn mode_bits(pins: u32) -> (u32, u32) {
    let (mut mask, mut output, mut pin) = (0, 0, 0);
    while pin < 16 {
        if pins & (1 << pin) != 0 {
            mask |= 0b11 << (2 * pin);
            output |= 0b01 << (2 * pin);
        }
        pin += 1;
    }
    (mask, output)
}

/// Motor outputs 1–4 before the protocol is known: the pins are already in their timer
/// function and driven low (the FET gates have pull-downs too), so motors are stopped from
/// power-on.
pub struct MotorParts {
    tim3: Peri<'static, TIM3>,
    tim9: Peri<'static, TIM9>,
    // Held so the pins stay in their timer function.
    _pins: MotorPins,
}

impl MotorParts {
    /// Starts both banks with `protocol`, every motor stopped. Output 1 = TIM3 CH3 (PB0),
    /// 2 = TIM3 CH4 (PB1), 3 = TIM9 CH2 (PA3), 4 = TIM9 CH1 (PA2).
    pub fn start(self, protocol: Protocol) -> Result<Motors, OutputError> {
        Ok(Motors {
            bank0: MotorTimer::new(
                Timer::new(self.tim3),
                &[Channel::Ch3, Channel::Ch4],
                protocol,
            )?,
            bank1: MotorTimer::new(
                Timer::new(self.tim9),
                &[Channel::Ch2, Channel::Ch1],
                protocol,
            )?,
            _pins: self._pins,
        })
    }
}

/// Everything the tasks own, split out of the peripheral singletons.
pub struct Board {
    /// Blue STAT/HEARTBEAT LED on PB5, active low.
    pub heartbeat_led: Output<'static>,
    /// The independent watchdog, not yet started (the supervisor task programs it).
    pub watchdog: Peri<'static, IWDG>,
    /// The radio module.
    pub radio: Radio,
    /// Gyro/accelerometer/magnetometer.
    pub imu: Imu,
    /// Barometer.
    pub baro: Baro,
    /// Motor outputs 1–4.
    pub motors: MotorParts,
    /// Battery voltage and current sense.
    pub battery: BatterySense,
    /// DAC tones into the VTX audio.
    pub speaker: Speaker,
    /// USB FS for the console.
    pub usb: Driver<'static, peripherals::USB_OTG_FS>,
    /// Flash sectors 0–3 (16 KiB each); settings use sectors 2–3.
    pub settings_flash: Bank1Region1<'static, Blocking>,
    /// The GPS receiver (Sparky2 only: the BrushedSparky's PA9/PA10 select the VTX band).
    #[cfg(feature = "sparky2")]
    pub gps: Option<Gps>,
    /// The VTX's band and channel select (BrushedSparky only: PA9/PA10 are the Sparky2's GPS).
    #[cfg(not(feature = "sparky2"))]
    pub vtx: VtxPins,
    /// The true RNG (clocked from the 48 MHz PLL Q the USB uses): the boot's seeds
    /// (`seeds`).
    pub rng: Peri<'static, peripherals::RNG>,
    /// Orange ALARM/ERR LED on PB4, active low.
    pub alarm_led: Output<'static>,
    /// Blue LINK/RF LED on PB6, active low.
    pub link_led: Output<'static>,
}

/// The u-blox receiver on the Sparky2's Main port: USART1, TX PA9, RX PA10
/// (`hardware/brushedsparky/README.md`). Receive by DMA into a 512-byte ring (DMA2 stream 2,
/// channel 4: 5 NAV-PVTs, 44 ms of bytes at 115 200 Bd; no interrupt per byte, so neither the
/// flight loop's priority nor a busy executor can make it overrun), transmit by DMA (DMA2
/// stream 7, channel 4).
#[cfg(feature = "sparky2")]
pub struct Gps {
    /// USART1 TX, 8N1, at the first of `GPS_BOOT_BAUDS` until the task reconfigures it.
    pub tx: usart::UartTx<'static, Async>,
    /// USART1 RX into the ring (the baud rate is the port's, set through either half).
    pub rx: usart::RingBufferedUartRx<'static>,
}

/// The SM215T VTX's select pins (`../shared/reference/hardware.md`): band RF_S1 PA9 (bit 0),
/// RF_S2 PA10 (bit 1); channel RF_CH1 PB12 (bit 2), RF_CH2 PB13 (bit 1), RF_CH3 PB14 (bit 0).
/// Open-drain without a pull: a 1 is released (the module pulls it up), a 0 driven low.
#[cfg(not(feature = "sparky2"))]
pub struct VtxPins {
    rf_s1: OutputOpenDrain<'static>,
    rf_s2: OutputOpenDrain<'static>,
    rf_ch1: OutputOpenDrain<'static>,
    rf_ch2: OutputOpenDrain<'static>,
    rf_ch3: OutputOpenDrain<'static>,
}

#[cfg(not(feature = "sparky2"))]
impl VtxPins {
    /// Drives the levels `flight_app::vtx` chose (`true` = released).
    pub fn set(&mut self, levels: flight_app::vtx::VtxPins) {
        for (pin, released) in [
            (&mut self.rf_s1, levels.rf_s1),
            (&mut self.rf_s2, levels.rf_s2),
            (&mut self.rf_ch1, levels.rf_ch1),
            (&mut self.rf_ch2, levels.rf_ch2),
            (&mut self.rf_ch3, levels.rf_ch3),
        ] {
            pin.set_level(Level::from(released));
        }
    }
}

#[cfg(feature = "sparky2")]
static GPS_RING: StaticCell<[u8; 512]> = StaticCell::new();

/// Keeps the M25P16's chip select driven for the life of the firmware (a dropped `Output`
/// would float the pin again).
static FLASH_CS: StaticCell<Output<'static>> = StaticCell::new();
static SINE: StaticCell<[u16; DAC_SAMPLES_PER_CYCLE]> = StaticCell::new();
static USB_OUT_BUFFER: StaticCell<[u8; 256]> = StaticCell::new();

impl Board {
    /// Claims the pins. Nothing is started here.
    pub fn new(p: Peripherals) -> Self {
        // The Sparky2's M25P16 flash shares SPI3 with the RFM22B; its chip select (PB3) floats
        // from reset unless the firmware drives it, so it goes high before SPI3 starts
        // clocking, or the flash may answer the radio's traffic. PB3 is unconnected on the
        // BrushedSparky, so driving it there is harmless.
        FLASH_CS.init(Output::new(p.PB3, Level::High, Speed::Low));
        let mut spi_config = spi::Config::default();
        // Si4432: SPI mode 0, ≤ 10 MHz; APB1 42 MHz / 8 = 5.25 MHz as Tau Labs ran it.
        spi_config.frequency = Hertz(5_250_000);
        spi_config.mode = spi::MODE_0;
        let spi = Spi::new_blocking(p.SPI3, p.PC10, p.PC12, p.PC11, spi_config);
        // MPU9250: SPI mode 3, starting slow for the configuration (imu_bus.rs switches to
        // the fast clock for sensor reads).
        let mut imu_config = spi::Config::default();
        imu_config.frequency = Hertz(IMU_SPI_SLOW_HZ);
        imu_config.mode = spi::MODE_3;
        let imu = Imu {
            spi: Spi::new(
                p.SPI1, p.PA5, p.PA7, p.PA6, p.DMA2_CH3, p.DMA2_CH0, Irqs, imu_config,
            ),
            cs: Output::new(p.PC4, Level::High, Speed::VeryHigh),
            int: ExtiInput::new(p.PC5, p.EXTI5, Pull::None, Irqs),
        };
        let baro = Baro {
            i2c: p.I2C1,
            scl: p.PB8,
            sda: p.PB9,
            tx_dma: p.DMA1_CH6,
            rx_dma: p.DMA1_CH0,
        };
        let motors = MotorParts {
            tim3: p.TIM3,
            tim9: p.TIM9,
            _pins: (
                PwmPin::new(p.PB0, OutputType::PushPull),
                PwmPin::new(p.PB1, OutputType::PushPull),
                PwmPin::new(p.PA3, OutputType::PushPull),
                PwmPin::new(p.PA2, OutputType::PushPull),
            ),
        };

        let battery = BatterySense {
            adc: Adc::new(p.ADC1),
            voltage: p.PC3.degrade_adc(),
            current: p.PC2.degrade_adc(),
        };

        // Tau Labs' tone: 0.4 Vpp around 0.5 V, 130 samples a cycle, DMA1 stream 5.
        let table = SINE.init([0; DAC_SAMPLES_PER_CYCLE]);
        sine_table(table, 500.0, 200.0);
        let pacer = Timer::new(p.TIM6);
        // TRGO on every update event: one DAC conversion per TIM6 period.
        pacer
            .regs_basic()
            .cr2()
            .modify(|w| w.set_mms(embassy_stm32::pac::timer::vals::Mms::UPDATE));
        pacer.start();
        let speaker = Speaker {
            dac: DacChannel::new_triggered(
                p.DAC1,
                p.DMA1_CH5,
                embassy_stm32::triggers::TIM6_TRGO,
                Irqs,
                p.PA4,
            ),
            pacer,
            table,
            // Output 8 (PC8): BrushedSparky's JP9 "external LEDs or buzzer" FET, Sparky2's
            // CONN7 pin 4. Low = off, also while the MCU is in reset (gate pull-down).
            buzzer: Output::new(p.PC8, Level::Low, Speed::Low),
        };

        let mut usb_config = usb::Config::default();
        // VBUS sense on PA8 is through a divider the OTG block does not watch: off.
        usb_config.vbus_detection = false;
        let usb = Driver::new_fs(
            p.USB_OTG_FS,
            Irqs,
            p.PA12,
            p.PA11,
            USB_OUT_BUFFER.init([0; 256]),
            usb_config,
        );

        let settings_flash = Flash::new_blocking(p.FLASH)
            .into_blocking_regions()
            .bank1_region1;

        #[cfg(feature = "sparky2")]
        let gps = {
            let mut config = usart::Config::default();
            config.baudrate = flight_app::app::GPS_BOOT_BAUDS[0];
            match usart::Uart::new(
                p.USART1, p.PA10, p.PA9, p.DMA2_CH7, p.DMA2_CH2, Irqs, config,
            ) {
                Ok(uart) => {
                    let (tx, rx) = uart.split();
                    Some(Gps {
                        tx,
                        rx: rx.into_ring_buffered(GPS_RING.init([0; 512])),
                    })
                }
                // 9600 Bd from an 84 MHz APB2 is always reachable; should the driver still
                // refuse, the board flies without GPS.
                Err(_) => None,
            }
        };

        // Released until the app's first levels (the task sets them at once).
        #[cfg(not(feature = "sparky2"))]
        let vtx = VtxPins {
            rf_s1: OutputOpenDrain::new(p.PA9, Level::High, Speed::Low),
            rf_s2: OutputOpenDrain::new(p.PA10, Level::High, Speed::Low),
            rf_ch1: OutputOpenDrain::new(p.PB12, Level::High, Speed::Low),
            rf_ch2: OutputOpenDrain::new(p.PB13, Level::High, Speed::Low),
            rf_ch3: OutputOpenDrain::new(p.PB14, Level::High, Speed::Low),
        };

        Self {
            #[cfg(feature = "sparky2")]
            gps,
            #[cfg(not(feature = "sparky2"))]
            vtx,
            imu,
            baro,
            motors,
            battery,
            speaker,
            usb,
            settings_flash,
            rng: p.RNG,
            heartbeat_led: Output::new(p.PB5, Level::High, Speed::Low),
            alarm_led: Output::new(p.PB4, Level::High, Speed::Low),
            link_led: Output::new(p.PB6, Level::High, Speed::Low),
            watchdog: p.IWDG,
            radio: Radio {
                spi,
                nsel: Output::new(radio_nsel(p.PA15, p.PC13), Level::High, Speed::VeryHigh),
                nirq: radio_irq(p.PB7, p.EXTI7, p.PD2, p.EXTI2),
            },
        }
    }
}

/// nSEL on PA15 (both boards), or PC13 in the PIL's `radio-cs-pc13` test variant
/// (build.rs): a board wired wrong, which must never link.
#[cfg(not(pil_radio_cs_pc13))]
fn radio_nsel(
    pa15: Peri<'static, peripherals::PA15>,
    _pc13: Peri<'static, peripherals::PC13>,
) -> Peri<'static, embassy_stm32::gpio::AnyPin> {
    pa15.into()
}

#[cfg(pil_radio_cs_pc13)]
fn radio_nsel(
    _pa15: Peri<'static, peripherals::PA15>,
    pc13: Peri<'static, peripherals::PC13>,
) -> Peri<'static, embassy_stm32::gpio::AnyPin> {
    pc13.into()
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
