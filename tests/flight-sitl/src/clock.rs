//! Time on the chip simulator's virtual clock: each board's clock (si4432-sim's `SimClock`,
//! booted with its board and a crystal a few ppm off) and the sleeps the simulated tasks wait
//! with.

use si4432_sim::{Medium, SimDelay};

/// Virtual time now, µs.
pub(crate) fn virtual_us(medium: &Medium) -> u64 {
    medium.now().as_micros() as u64
}

/// Sleeps `ms` of virtual time.
pub(crate) async fn sleep_ms(delay: &SimDelay, ms: u64) {
    delay.sleep_ns(ms * 1_000_000).await;
}
