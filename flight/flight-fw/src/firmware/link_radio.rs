//! The link's clock on embassy-time. The radio side is the driver's own adapter,
//! `radio_rfm22b::link::LinkRadio` (feature `telemetry`), shared with the module firmware
//! and the host simulations so both ends always set the chip up the same way.

use embassy_futures::select::select;
use embassy_time::{Duration, Instant, Timer};
use telemetry::link::LinkClock;

use crate::firmware::shared::with_app;

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

/// Waits `d`, checking the link task in every 50 ms.
pub async fn idle(d: Duration) {
    let _ = select(Timer::after(d), keep_alive()).await;
}

/// Checks the link task in every 50 ms, forever (raced against a bounded wait).
pub async fn keep_alive() -> core::convert::Infallible {
    loop {
        with_app(|a| a.on_link_idle());
        Timer::after(Duration::from_millis(50)).await;
    }
}

/// Resolves when the link must restart: the console asked for a bind or changed the binding
/// phrase (`FlightApp::link_restart_due`, polled every 50 ms, checking in).
pub async fn restart_due() {
    loop {
        if with_app(|a| a.link_restart_due()).unwrap_or(false) {
            return;
        }
        with_app(|a| a.on_link_idle());
        Timer::after(Duration::from_millis(50)).await;
    }
}
