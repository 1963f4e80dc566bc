//! embassy-time as the link's `LinkClock` (the driver adapter is
//! `module_core::air::radio::LinkRadio`).

use embassy_time::{Instant, Timer};
use telemetry::link::LinkClock;

/// embassy-time in µs: the same clock the JR-line task stamps CRSF frames with, so the
/// link's slot times are directly the CRSF timing frame's phase.
pub struct EmbassyClock;

impl LinkClock for EmbassyClock {
    fn now_us(&self) -> u64 {
        Instant::now().as_micros()
    }

    async fn sleep_until_us(&mut self, deadline_us: u64) {
        Timer::at(Instant::from_micros(deadline_us)).await;
    }
}
