//! The driver wired on an embassy board: an STM32F405 (BrushedSparky pinout: SPI3 on
//! PC10/PC11/PC12, nSEL PA15, nIRQ PB7), transmitting a counter every 100 ms. Builds only for
//! the MCU: `cargo build -p radio-rfm22b --example embassy_stm32f4 --target thumbv7em-none-eabihf`
//! (on the host it is an empty `main`).
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod app {
    use defmt::{info, warn};
    use embassy_stm32::exti::ExtiInput;
    use embassy_stm32::gpio::{Level, Output, Pull, Speed};
    use embassy_stm32::spi::{self, Spi};
    use embassy_stm32::time::Hertz;
    use embassy_stm32::{bind_interrupts, dma, exti, interrupt, peripherals};
    use embassy_time::{Delay, Timer};
    use embedded_hal_bus::spi::ExclusiveDevice;
    use radio_rfm22b::{Carrier, Config, ModemConfig, PacketConfig, Rfm22b};
    use {defmt_rtt as _, panic_probe as _};

    bind_interrupts!(struct Irqs {
        EXTI9_5 => exti::InterruptHandler<interrupt::typelevel::EXTI9_5>;
        DMA1_STREAM7 => dma::InterruptHandler<peripherals::DMA1_CH7>;
        DMA1_STREAM0 => dma::InterruptHandler<peripherals::DMA1_CH0>;
    });

    /// Checked at compile time.
    const MODEM: ModemConfig = ModemConfig::new(57_600, 28_800);

    #[embassy_executor::main]
    async fn main(_spawner: embassy_executor::Spawner) {
        let p = embassy_stm32::init(Default::default());
        let mut spi_config = spi::Config::default();
        spi_config.frequency = Hertz(5_250_000);
        let spi = Spi::new(
            p.SPI3, p.PC10, p.PC12, p.PC11, p.DMA1_CH7, p.DMA1_CH0, Irqs, spi_config,
        );
        let nsel = Output::new(p.PA15, Level::High, Speed::VeryHigh);
        let nirq = ExtiInput::new(p.PB7, p.EXTI7, Pull::Up, Irqs);
        let Ok(device) = ExclusiveDevice::new_no_delay(spi, nsel);
        let mut radio = Rfm22b::new_without_sdn(device, nirq, Delay);

        let config = Config::new(MODEM, PacketConfig::new(), Carrier::new(434_000_000));
        match radio.init(config).await {
            Ok(chip) => info!("Si4432 {}", defmt::Debug2Format(&chip.version)),
            Err(e) => warn!("radio init: {}", defmt::Debug2Format(&e)),
        }
        let mut counter = 0u32;
        loop {
            if let Err(e) = radio.transmit(&counter.to_le_bytes(), 20_000).await {
                warn!("tx: {}", defmt::Debug2Format(&e));
            }
            counter = counter.wrapping_add(1);
            Timer::after_millis(100).await;
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
