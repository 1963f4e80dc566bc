//! Minimal OpenLRSng-compatible transmitter reading PPM, for an STM32F405 board with an
//! RFM22B on SPI3 (SCK PC10, MISO PC11, MOSI PC12, nSEL PA15, nIRQ PB7). PPM input (from a
//! handset trainer port, positive, rising edges) on PB6.
//!
//! Build: `cargo build -p openlrs-ng --example openlrs_tx
//! --target thumbv7em-none-eabihf --release` (link arguments come from build.rs).
//! At boot it offers binding for 10 s (like a TX started with the bind button), then flies:
//! 8 channels + serial telemetry at 19200 bps, 40 Hz, 3.8 format.
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
    use embassy_stm32::mode::Async;
    use embassy_stm32::spi::{self, Spi};
    use embassy_stm32::time::Hertz;
    use embassy_stm32::{bind_interrupts, dma, exti, interrupt, peripherals};
    use embassy_sync::blocking_mutex::Mutex;
    use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
    use embassy_time::{Delay, Instant, Timer};
    use embedded_hal_bus::spi::ExclusiveDevice;
    use openlrs::channels::CENTER_BITS;
    use openlrs::ppm::{DEFAULT_MIN_CHANNELS, PPM_CHANNELS, PpmDecoder, Pulse};
    use openlrs::radio::Radio;
    use openlrs::random::bind_randomize;
    use openlrs::roles::{TxEvent, tx_bind, tx_start, tx_step};
    use openlrs::tx::{Received, Transmitter};
    use openlrs::{BindData, BindingVersion, RfmType};
    use {defmt_rtt as _, panic_probe as _};

    bind_interrupts!(struct Irqs {
        EXTI9_5 => exti::InterruptHandler<interrupt::typelevel::EXTI9_5>;
        DMA1_STREAM7 => dma::InterruptHandler<peripherals::DMA1_CH7>;
        DMA1_STREAM0 => dma::InterruptHandler<peripherals::DMA1_CH0>;
    });

    /// Seeds the link identity. Real firmware seeds from `micros()` once and stores the result.
    const LINK_SEED: u32 = 0x5EED_1234;
    const BIND_WINDOW_US: u64 = 10_000_000;

    /// Latest decoded PPM frame (10-bit values) and a count of frames decoded so far.
    static CHANNELS: Mutex<CriticalSectionRawMutex, Cell<(u32, [u16; PPM_CHANNELS])>> =
        Mutex::new(Cell::new((0, [CENTER_BITS; PPM_CHANNELS])));

    fn now_us() -> u64 {
        Instant::now().as_micros()
    }

    #[embassy_executor::main]
    async fn main(spawner: Spawner) {
        let p = embassy_stm32::init(Default::default());
        let mut spi_config = spi::Config::default();
        spi_config.frequency = Hertz(4_000_000);
        spi_config.mode = spi::MODE_0;
        let spi = Spi::new(
            p.SPI3, p.PC10, p.PC12, p.PC11, p.DMA1_CH7, p.DMA1_CH0, Irqs, spi_config,
        );
        let Ok(device) =
            ExclusiveDevice::new_no_delay(spi, Output::new(p.PA15, Level::High, Speed::VeryHigh));
        let nirq = ExtiInput::new(p.PB7, p.EXTI7, Pull::Up, Irqs);
        match ppm_input(ExtiInput::new(p.PB6, p.EXTI6, Pull::None, Irqs)) {
            Ok(token) => spawner.spawn(token),
            Err(e) => warn!("PPM task not started: {}", e),
        }

        let (version, band) = (BindingVersion::V38, RfmType::Mhz433);
        let defaults = BindData::defaults(version, band);
        let mut data = defaults;
        bind_randomize(
            &mut data,
            LINK_SEED,
            true,
            band.max_frequency_hz(),
            &defaults,
        );
        let mut radio = Radio::new(device, nirq, Delay, now_us as fn() -> u64, version, band);
        match tx_bind(&mut radio, &data, now_us() + BIND_WINDOW_US).await {
            Ok(true) => info!("receiver bound"),
            Ok(false) => info!("no receiver answered; flying with the stored identity"),
            Err(e) => warn!("bind failed: {}", defmt::Debug2Format(&e)),
        }
        let Ok(tx) = Transmitter::new(data, now_us()) else {
            warn!("unusable bind data");
            return;
        };
        // Like OpenLRSng with minch ≠ 0: no PPM for 8 packets → stop sending → RX failsafe.
        let mut tx = tx.with_stale_input_stop();
        info!("link: {=u32} µs interval", tx.interval_us());
        if let Err(e) = tx_start(&mut radio, &tx).await {
            warn!("radio setup failed: {}", defmt::Debug2Format(&e));
        }
        let mut frames_seen = 0;
        let mut set_channels = |tx: &mut Transmitter| {
            let (frames, channels) = CHANNELS.lock(Cell::get);
            if frames != frames_seen {
                frames_seen = frames;
                tx.set_channels(&channels);
            }
        };
        let mut on_event = |event| match event {
            TxEvent::Downlink {
                received: Received::LinkInfo(info),
                rssi,
            } => {
                info!(
                    "RX rssi {} lq {}, TX rssi {}",
                    info.rssi, info.link_quality, rssi
                );
            }
            TxEvent::Downlink { .. } => {}
            TxEvent::ReplyMissed => warn!("no telemetry reply"),
        };
        loop {
            if let Err(e) = tx_step(&mut radio, &mut tx, &mut set_channels, &mut on_event).await {
                warn!("radio error: {}", defmt::Debug2Format(&e));
                Timer::after_millis(10).await;
            }
        }
    }

    /// Measures rising edge to rising edge and feeds OpenLRSng's PPM decoder.
    #[embassy_executor::task]
    async fn ppm_input(mut pin: ExtiInput<'static, Async>) {
        let mut decoder = PpmDecoder::new(DEFAULT_MIN_CHANNELS);
        let mut last = Instant::now();
        loop {
            pin.wait_for_rising_edge().await;
            let now = Instant::now();
            let width_us = u16::try_from((now - last).as_micros()).unwrap_or(u16::MAX);
            last = now;
            if let Pulse::FrameAccepted { .. } = decoder.pulse(width_us) {
                CHANNELS.lock(|c| c.set((c.get().0.wrapping_add(1), *decoder.channels())));
            }
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
