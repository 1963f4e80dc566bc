//! The link's clock on embassy-time. The radio side is the driver's own adapters,
//! `radio_rfm22b::link::LinkRadio` and `openlrs::dual::DualRadio`, shared with the
//! module firmware and the host simulations so both ends always set the chip up the same way.

use embassy_time::{Instant, Timer};
use telemetry::link::LinkClock;

/// The link's clock: embassy-time's 1 MHz tick.
#[derive(Clone, Copy)]
pub struct EmbassyClock;

impl LinkClock for EmbassyClock {
    fn now_us(&self) -> u64 {
        Instant::now().as_micros()
    }

    async fn sleep_until_us(&mut self, deadline_us: u64) {
        Timer::at(Instant::from_micros(deadline_us)).await;
    }
}
