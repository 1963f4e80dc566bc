//! The driver on a Linux board (e.g. a Raspberry Pi): RFM22B on `/dev/spidev0.0`, nIRQ on
//! GPIO 25 of `/dev/gpiochip0`, SDN tied low. Sends a ping every second and listens for
//! an answer in between. Run on the Pi with `cargo run --example linux_spidev`.
//!
//! linux-embedded-hal is blocking; three small adapters make its SPI, pin and delay async,
//! and `embassy_futures::block_on` runs the driver. The pin and delay futures return
//! `Pending` (and ask to be polled again) instead of blocking, so the driver's nIRQ/deadline
//! race works.

use std::time::{Duration, Instant};

use embedded_hal::digital::InputPin;
use embedded_hal_async::spi::Operation;
use linux_embedded_hal::gpio_cdev::{Chip, LineRequestFlags};
use linux_embedded_hal::spidev::{SpiModeFlags, SpidevOptions};
use linux_embedded_hal::{CdevPin, SpidevDevice};
use radio_rfm22b::{Carrier, Config, ModemConfig, PacketConfig, Rfm22b, RxOutcome};

/// Blocking `SpiDevice` → async `SpiDevice`.
struct AsyncSpi(SpidevDevice);

impl embedded_hal_async::spi::ErrorType for AsyncSpi {
    type Error = <SpidevDevice as embedded_hal::spi::ErrorType>::Error;
}

impl embedded_hal_async::spi::SpiDevice for AsyncSpi {
    async fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Self::Error> {
        embedded_hal::spi::SpiDevice::transaction(&mut self.0, ops)
    }
}

/// A polled input pin as an async `Wait` (only the level waits the driver uses).
struct PolledIrq(CdevPin);

impl embedded_hal::digital::ErrorType for PolledIrq {
    type Error = <CdevPin as embedded_hal::digital::ErrorType>::Error;
}

impl PolledIrq {
    async fn until(
        &mut self,
        low: bool,
    ) -> Result<(), <Self as embedded_hal::digital::ErrorType>::Error> {
        std::future::poll_fn(|cx| match self.0.is_low() {
            Ok(level) if level == low => std::task::Poll::Ready(Ok(())),
            Ok(_) => {
                std::thread::sleep(Duration::from_micros(50));
                cx.waker().wake_by_ref();
                std::task::Poll::Pending
            }
            Err(e) => std::task::Poll::Ready(Err(e)),
        })
        .await
    }
}

impl embedded_hal_async::digital::Wait for PolledIrq {
    async fn wait_for_high(&mut self) -> Result<(), Self::Error> {
        self.until(false).await
    }
    async fn wait_for_low(&mut self) -> Result<(), Self::Error> {
        self.until(true).await
    }
    async fn wait_for_rising_edge(&mut self) -> Result<(), Self::Error> {
        self.until(true).await?;
        self.until(false).await
    }
    async fn wait_for_falling_edge(&mut self) -> Result<(), Self::Error> {
        self.until(false).await?;
        self.until(true).await
    }
    async fn wait_for_any_edge(&mut self) -> Result<(), Self::Error> {
        let start = self.0.is_low()?;
        self.until(!start).await
    }
}

/// A non-blocking delay on the monotonic clock.
struct ClockDelay;

impl embedded_hal_async::delay::DelayNs for ClockDelay {
    async fn delay_ns(&mut self, ns: u32) {
        let end = Instant::now() + Duration::from_nanos(u64::from(ns));
        std::future::poll_fn(|cx| {
            if Instant::now() >= end {
                std::task::Poll::Ready(())
            } else {
                cx.waker().wake_by_ref();
                std::task::Poll::Pending
            }
        })
        .await
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut spi = SpidevDevice::open("/dev/spidev0.0")?;
    spi.configure(
        &SpidevOptions::new()
            .bits_per_word(8)
            .max_speed_hz(4_000_000)
            .mode(SpiModeFlags::SPI_MODE_0)
            .build(),
    )?;
    let line = Chip::new("/dev/gpiochip0")?.get_line(25)?;
    let nirq = CdevPin::new(line.request(LineRequestFlags::INPUT, 0, "rfm22b-nirq")?)?;

    let config = Config::new(
        ModemConfig::new(57_600, 28_800),
        PacketConfig::new(),
        Carrier::new(434_000_000),
    );
    let mut radio = Rfm22b::new_without_sdn(AsyncSpi(spi), PolledIrq(nirq), ClockDelay);
    embassy_futures::block_on(async {
        let chip = radio.init(config).await?;
        println!("Si4432 rev {:?}", chip.version);
        let mut buf = [0u8; 255];
        loop {
            radio.transmit(b"ping", 100_000).await?;
            match radio.receive(&mut buf, 1_000_000).await? {
                RxOutcome::Packet(p) => println!(
                    "{:02x?} at {} dBm, AFC {} Hz",
                    buf.get(..p.len).unwrap_or_default(),
                    p.signal.rssi_dbm,
                    p.signal.afc_offset_hz
                ),
                other => println!("{other:?}"),
            }
        }
    })
}
