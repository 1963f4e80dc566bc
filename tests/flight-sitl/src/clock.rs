//! Time on the simulators' one virtual time: each board's clock (`SimClock`, from sim-exec,
//! booted with its board and a crystal a few ppm off) and the sleeps the simulated tasks wait
//! with.

use si4432_sim::{Medium, VirtualTime};

/// Virtual time now, µs.
pub(crate) fn virtual_us(medium: &Medium) -> u64 {
    medium.now().as_micros() as u64
}

/// Sleeps `ms` of virtual time.
pub(crate) async fn sleep_ms(time: &VirtualTime, ms: u64) {
    time.sleep_ns(ms * 1_000_000).await;
}
