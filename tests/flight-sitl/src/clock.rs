//! Time on the chip simulator's virtual clock: each board's `LinkClock` (its own epoch since
//! boot and a crystal a few ppm off) and the sleeps the simulated tasks wait with.

use si4432_sim::{Medium, SimDelay};
use telemetry::link::LinkClock;

/// A board's clock: time since its boot on a crystal `drift_ppm` off, like a separately
/// booted MCU.
#[derive(Clone)]
pub(crate) struct BoardClock {
    medium: Medium,
    delay: SimDelay,
    boot_ns: u64,
    drift_ppm: f64,
}

impl BoardClock {
    /// The clock of a board booting now.
    pub(crate) fn booting_now(medium: Medium, delay: SimDelay, drift_ppm: f64) -> Self {
        let boot_ns = medium.now().as_nanos() as u64;
        Self {
            medium,
            delay,
            boot_ns,
            drift_ppm,
        }
    }

    /// The sleeps of this board's tasks.
    pub(crate) fn delay(&self) -> &SimDelay {
        &self.delay
    }

    /// Milliseconds of this board's clock (wrapping, as the firmware's `now_ms`).
    pub(crate) fn now_ms(&self) -> u32 {
        (self.now_us() / 1000) as u32
    }
}

impl LinkClock for BoardClock {
    fn now_us(&self) -> u64 {
        let v = (self.medium.now().as_nanos() as u64).saturating_sub(self.boot_ns) as f64 / 1e3;
        (v * (1.0 + self.drift_ppm * 1e-6)) as u64
    }

    async fn sleep_until_us(&mut self, deadline_us: u64) {
        let local_wait_us = deadline_us.saturating_sub(self.now_us());
        if local_wait_us > 0 {
            // Local µs → virtual ns, rounded up so we never wake early.
            let virtual_ns =
                (local_wait_us as f64 * 1e3 / (1.0 + self.drift_ppm * 1e-6)).ceil() as u64;
            self.delay.sleep_ns(virtual_ns).await;
        }
    }
}

/// Virtual time now, µs.
pub(crate) fn virtual_us(medium: &Medium) -> u64 {
    medium.now().as_micros() as u64
}

/// Sleeps `ms` of virtual time.
pub(crate) async fn sleep_ms(delay: &SimDelay, ms: u64) {
    delay.sleep_ns(ms * 1_000_000).await;
}
