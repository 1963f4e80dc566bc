//! The link's clock on embassy-time. The radio side is the driver's own adapter,
//! `radio_rfm22b::link::LinkRadio` (feature `telemetry`), shared with the module firmware
//! and the host simulations so both ends always set the chip up the same way.

use embassy_time::{Instant, Timer};
use telemetry::link::LinkClock;

pub use radio_rfm22b::link::LinkRadio;

/// The link's clock: embassy-time's 1 MHz tick.
pub struct EmbassyClock;

impl LinkClock for EmbassyClock {
    fn now_us(&self) -> u64 {
        Instant::now().as_micros()
    }

    async fn sleep_until_us(&mut self, deadline_us: u64) {
        Timer::at(Instant::from_micros(deadline_us)).await;
    }
}
