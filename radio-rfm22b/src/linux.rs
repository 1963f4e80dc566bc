//! Linux adapters (feature `linux`, needs `std`): the driver on a Raspberry Pi or any board
//! with a spidev and a GPIO character device, through [`linux_embedded_hal`].
//!
//! linux-embedded-hal is blocking; the driver is async. Three small adapters bridge them:
//! - [`AsyncSpi`]: any blocking `embedded_hal::spi::SpiDevice` as an async one (the
//!   transfer blocks for its few microseconds, which is what spidev does anyway);
//! - [`PolledIrq`]: any blocking `InputPin` as an async `Wait`, polling the level;
//! - [`StdDelay`]: an async `DelayNs` on the monotonic clock.
//!
//! The pin and delay futures return `Pending` (after a short sleep, and asking to be polled
//! again) instead of blocking until done. That is what lets the driver race nIRQ against
//! its deadline with `select`, and it is why they suit a single-future executor such as
//! `embassy_futures::block_on` (each poll may sleep up to [`POLL_INTERVAL`]); on a
//! multi-task executor give the radio its own thread.
//!
//! [`open_spidev`] and [`open_nirq`] open and configure the two devices; [`monotonic_us`] is
//! the microsecond clock the OpenLRSng `Radio` wants.
//!
//! ```no_run
//! use radio_rfm22b::linux::{StdDelay, open_nirq, open_spidev};
//! use radio_rfm22b::{Carrier, Config, ModemConfig, PacketConfig, Rfm22b};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! // RFM22B on SPI0 CE0, nIRQ on GPIO 25, SDN tied to GND.
//! let spi = open_spidev("/dev/spidev0.0", 4_000_000)?;
//! let nirq = open_nirq("/dev/gpiochip0", 25)?;
//! let mut radio = Rfm22b::new_without_sdn(spi, nirq, StdDelay);
//! let config = Config::new(
//!     ModemConfig::new(57_600, 28_800),
//!     PacketConfig::new(),
//!     Carrier::new(434_000_000),
//! );
//! let chip = embassy_futures::block_on(radio.init(config))?;
//! println!("Si4432 rev {:?}", chip.version);
//! # Ok(())
//! # }
//! ```

extern crate std;

use std::boxed::Box;
use std::future::poll_fn;
use std::task::Poll;
use std::time::{Duration, Instant};

use embedded_hal::digital::InputPin;
use embedded_hal_async::spi::Operation;
pub use linux_embedded_hal;
use linux_embedded_hal::gpio_cdev::{Chip, LineRequestFlags};
use linux_embedded_hal::spidev::{SpiModeFlags, SpidevOptions};
use linux_embedded_hal::{CdevPin, SpidevDevice};

/// Longest sleep inside one poll of [`PolledIrq`] or [`StdDelay`]: the latency with which
/// nIRQ is noticed, and the resolution of the deadlines.
pub const POLL_INTERVAL: Duration = Duration::from_micros(50);

/// A blocking SPI device as an async `embedded_hal_async::spi::SpiDevice`.
#[derive(Debug)]
pub struct AsyncSpi<T>(pub T);

impl<T: embedded_hal::spi::SpiDevice> embedded_hal_async::spi::ErrorType for AsyncSpi<T> {
    type Error = T::Error;
}

impl<T: embedded_hal::spi::SpiDevice> embedded_hal_async::spi::SpiDevice for AsyncSpi<T> {
    async fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Self::Error> {
        self.0.transaction(ops)
    }
}

/// A blocking input pin as an async `embedded_hal_async::digital::Wait`, by polling its
/// level every [`POLL_INTERVAL`]. The driver only waits for nIRQ *low* (a level).
#[derive(Debug)]
pub struct PolledIrq<P>(pub P);

impl<P: InputPin> embedded_hal::digital::ErrorType for PolledIrq<P> {
    type Error = P::Error;
}

impl<P: InputPin> PolledIrq<P> {
    async fn until(&mut self, low: bool) -> Result<(), P::Error> {
        poll_fn(|cx| match self.0.is_low() {
            Ok(level) if level == low => Poll::Ready(Ok(())),
            Ok(_) => {
                std::thread::sleep(POLL_INTERVAL);
                cx.waker().wake_by_ref();
                Poll::Pending
            }
            Err(e) => Poll::Ready(Err(e)),
        })
        .await
    }
}

impl<P: InputPin> embedded_hal_async::digital::Wait for PolledIrq<P> {
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

/// An async `embedded_hal_async::delay::DelayNs` on [`Instant`], sleeping at most
/// [`POLL_INTERVAL`] per poll so that a raced nIRQ is still noticed.
#[derive(Debug, Clone, Copy, Default)]
pub struct StdDelay;

impl embedded_hal_async::delay::DelayNs for StdDelay {
    async fn delay_ns(&mut self, ns: u32) {
        let end = Instant::now() + Duration::from_nanos(u64::from(ns));
        poll_fn(|cx| {
            let now = Instant::now();
            if now >= end {
                return Poll::Ready(());
            }
            std::thread::sleep((end - now).min(POLL_INTERVAL));
            cx.waker().wake_by_ref();
            Poll::Pending
        })
        .await
    }
}

/// Why [`open_spidev`] or [`open_nirq`] failed (no such device, no permission, line busy …).
pub type OpenError = Box<dyn std::error::Error>;

/// Opens `path` (e.g. `/dev/spidev0.0`) in SPI mode 0, 8-bit words, at `max_speed_hz`
/// (the Si4432 allows up to 10 MHz; 4 MHz is plenty).
pub fn open_spidev(path: &str, max_speed_hz: u32) -> Result<AsyncSpi<SpidevDevice>, OpenError> {
    let mut spi = SpidevDevice::open(path)?;
    spi.configure(
        &SpidevOptions::new()
            .bits_per_word(8)
            .max_speed_hz(max_speed_hz)
            .mode(SpiModeFlags::SPI_MODE_0)
            .build(),
    )?;
    Ok(AsyncSpi(spi))
}

/// Requests `line` of the GPIO chip at `chip_path` (e.g. `/dev/gpiochip0`, line 25 for the
/// Pi's GPIO 25) as an input for nIRQ.
pub fn open_nirq(chip_path: &str, line: u32) -> Result<PolledIrq<CdevPin>, OpenError> {
    let line = Chip::new(chip_path)?.get_line(line)?;
    let handle = line.request(LineRequestFlags::INPUT, 0, "rfm22b-nirq")?;
    Ok(PolledIrq(CdevPin::new(handle)?))
}

/// Microseconds since the first call in this process: the clock for
/// `openlrs-ng`'s `openlrs::radio::Radio::new` (pass `radio_rfm22b::linux::monotonic_us`).
pub fn monotonic_us() -> u64 {
    static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    let start = *START.get_or_init(Instant::now);
    u64::try_from(start.elapsed().as_micros()).unwrap_or(u64::MAX)
}
