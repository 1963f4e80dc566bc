//! Minimal OpenLRSng-compatible receiver with PPM output, for an STM32F405 board with an
//! RFM22B on SPI3 (SCK PC10, MISO PC11, MOSI PC12, nSEL PA15, nIRQ PB7 — BrushedSparky).
//! PPM (8 channels, 22.5 ms frames, positive) comes out on PB6.
//!
//! Build: `cargo build -p openlrs-ng --example openlrs_rx
//! --target thumbv7em-none-eabihf --release` (link arguments come from build.rs).
//! It listens for a 3.8 TX on 435 MHz at every boot (nothing is persisted here; real
//! firmware stores `RxEvent::Bound` data in flash and passes it to `Receiver::new`).
//!
//! On the host (e.g. `cargo clippy --all-features --all-targets`) it is an empty `main`.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod app {
    use core::cell::Cell;

    use defmt::{info, warn};
    use embassy_executor::Spawner;
    use embassy_stm32::exti::ExtiInput;
    use embassy_stm32::gpio::{Level, Output, Pull, Speed};
    use embassy_stm32::spi::{self, Spi};
    use embassy_stm32::time::Hertz;
    use embassy_stm32::{bind_interrupts, dma, exti, interrupt, peripherals};
    use embassy_sync::blocking_mutex::Mutex;
    use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
    use embassy_time::{Delay, Instant, Timer};
    use embedded_hal_bus::spi::ExclusiveDevice;
    use openlrs::channels::bits_to_us;
    use openlrs::radio::Radio;
    use openlrs::roles::{RxEvent, run_receiver};
    use openlrs::rx::{Config, Receiver};
    use openlrs::{BindingVersion, RfmType};
    use {defmt_rtt as _, panic_probe as _};

    bind_interrupts!(struct Irqs {
        EXTI9_5 => exti::InterruptHandler<interrupt::typelevel::EXTI9_5>;
        DMA1_STREAM7 => dma::InterruptHandler<peripherals::DMA1_CH7>;
        DMA1_STREAM0 => dma::InterruptHandler<peripherals::DMA1_CH0>;
    });

    const PPM_CHANNELS: usize = 8;
    /// PPM frame period and the low separator pulse before each channel (µs).
    const PPM_FRAME_US: u64 = 22_500;
    const PPM_SEPARATOR_US: u64 = 300;

    /// Latest channel values in µs, shared between the radio loop and the PPM task.
    static CHANNELS_US: Mutex<CriticalSectionRawMutex, Cell<[u16; PPM_CHANNELS]>> =
        Mutex::new(Cell::new([1500; PPM_CHANNELS]));

    fn now_us() -> u64 {
        Instant::now().as_micros()
    }

    #[embassy_executor::main]
    async fn main(spawner: Spawner) {
        let p = embassy_stm32::init(Default::default());
        let mut spi_config = spi::Config::default();
        spi_config.frequency = Hertz(4_000_000); // Si4432: SPI mode 0, ≤ 10 MHz
        spi_config.mode = spi::MODE_0;
        let spi = Spi::new(
            p.SPI3, p.PC10, p.PC12, p.PC11, p.DMA1_CH7, p.DMA1_CH0, Irqs, spi_config,
        );
        let Ok(device) =
            ExclusiveDevice::new_no_delay(spi, Output::new(p.PA15, Level::High, Speed::VeryHigh));
        let nirq = ExtiInput::new(p.PB7, p.EXTI7, Pull::Up, Irqs);
        match ppm_output(Output::new(p.PB6, Level::High, Speed::Low)) {
            Ok(token) => spawner.spawn(token),
            Err(e) => warn!("PPM task not started: {}", e),
        }

        let (version, band) = (BindingVersion::V38, RfmType::Mhz433);
        let mut radio = Radio::new(device, nirq, Delay, now_us as fn() -> u64, version, band);
        let mut rx = Receiver::new(Config::new(version, band), None);
        let mut failsafe_us = [0u16; PPM_CHANNELS]; // 0 = hold the last value
        loop {
            let error = run_receiver(&mut radio, &mut rx, |event| match event {
                RxEvent::Bound(data) => info!("bound: magic {=u32:08x}", data.rf_magic),
                RxEvent::Channels {
                    channels_bits,
                    save_failsafe,
                    ..
                } => {
                    let mut us = [1500u16; PPM_CHANNELS];
                    for (slot, &bits) in us.iter_mut().zip(channels_bits.iter()) {
                        *slot = bits_to_us(bits);
                    }
                    if save_failsafe {
                        failsafe_us = us;
                    }
                    CHANNELS_US.lock(|c| c.set(us));
                }
                RxEvent::Serial(bytes) => info!("serial: {=[u8]}", bytes.as_slice()),
                RxEvent::FailsafeStarted => {
                    warn!("link lost: failsafe");
                    CHANNELS_US.lock(|c| {
                        let mut us = c.get();
                        for (slot, &fs) in us.iter_mut().zip(failsafe_us.iter()) {
                            if fs != 0 {
                                *slot = fs;
                            }
                        }
                        c.set(us);
                    });
                }
            })
            .await;
            warn!("radio error: {}", defmt::Debug2Format(&error));
            Timer::after_millis(100).await;
        }
    }

    /// Positive PPM: a 300 µs low separator, then high for the rest of each channel's width,
    /// then a sync gap filling the frame. Timer-driven, so it jitters by the executor latency;
    /// production firmware uses a timer's output compare instead.
    #[embassy_executor::task]
    async fn ppm_output(mut pin: Output<'static>) {
        loop {
            let channels = CHANNELS_US.lock(Cell::get);
            let mut used_us = 0;
            for width_us in channels.iter().map(|&us| u64::from(us)).chain([0]) {
                pin.set_low();
                Timer::after_micros(PPM_SEPARATOR_US).await;
                pin.set_high();
                let rest = if width_us == 0 {
                    PPM_FRAME_US.saturating_sub(used_us + PPM_SEPARATOR_US) // sync gap
                } else {
                    width_us.saturating_sub(PPM_SEPARATOR_US)
                };
                used_us += width_us;
                Timer::after_micros(rest).await;
            }
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
