//! A board's clock on the medium's virtual time: the one clock every simulation of a board
//! reads (taulink-sim's link ends, flight-sitl's boards, the module's chip tests). It counts
//! from the board's own epoch (booted now, or an offset like a separately booted MCU) and
//! runs `drift_ppm` fast or slow like its crystal; with the `telemetry` feature it is the
//! link's `telemetry::link::LinkClock`.

use crate::{Medium, SimDelay};

/// A board's clock: `(virtual time − boot) × (1 + drift_ppm·10⁻⁶) + offset_us`.
#[derive(Clone)]
pub struct SimClock {
    medium: Medium,
    delay: SimDelay,
    boot_ns: u64,
    offset_us: u64,
    drift_ppm: f64,
}

impl SimClock {
    /// A clock reading (virtual time × (1 + drift_ppm·10⁻⁶)) + `offset_us`: a board booted
    /// `offset_us` before the simulation started.
    pub fn new(medium: Medium, delay: SimDelay, offset_us: u64, drift_ppm: f64) -> Self {
        Self {
            medium,
            delay,
            boot_ns: 0,
            offset_us,
            drift_ppm,
        }
    }

    /// The clock of a board booting now: it reads 0 at this instant.
    pub fn booting_now(medium: Medium, delay: SimDelay, drift_ppm: f64) -> Self {
        let boot_ns = medium.now().as_nanos() as u64;
        Self {
            medium,
            delay,
            boot_ns,
            offset_us: 0,
            drift_ppm,
        }
    }

    /// The sleeps of this board's tasks.
    pub fn delay(&self) -> &SimDelay {
        &self.delay
    }

    /// Virtual time without epoch or drift (the common reference for measurements), µs.
    pub fn virtual_us(&self) -> u64 {
        self.medium.now().as_micros() as u64
    }

    /// This board's time, µs.
    pub fn now_us(&self) -> u64 {
        let v = (self.medium.now().as_nanos() as u64).saturating_sub(self.boot_ns) as f64 / 1e3;
        (v * (1.0 + self.drift_ppm * 1e-6)) as u64 + self.offset_us
    }

    /// Milliseconds of this board's clock (wrapping, as a firmware's `now_ms`).
    pub fn now_ms(&self) -> u32 {
        (self.now_us() / 1000) as u32
    }

    /// Sleeps until this board's clock reads `deadline_us`.
    pub async fn sleep_until_us(&mut self, deadline_us: u64) {
        let local_wait_us = deadline_us.saturating_sub(self.now_us());
        if local_wait_us > 0 {
            // Local µs → virtual ns, rounded up so we never wake early.
            let virtual_ns =
                (local_wait_us as f64 * 1e3 / (1.0 + self.drift_ppm * 1e-6)).ceil() as u64;
            self.delay.sleep_ns(virtual_ns).await;
        }
    }
}

#[cfg(feature = "telemetry")]
impl telemetry::link::LinkClock for SimClock {
    fn now_us(&self) -> u64 {
        SimClock::now_us(self)
    }

    async fn sleep_until_us(&mut self, deadline_us: u64) {
        SimClock::sleep_until_us(self, deadline_us).await;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Simulation;

    #[test]
    fn epochs_and_drift_read_as_separate_boards() {
        let sim = Simulation::new(1);
        let medium = sim.medium();
        let delay = sim.delay();
        let mut offset = SimClock::new(medium.clone(), delay.clone(), 5_000, 0.0);
        let fast = SimClock::new(medium.clone(), delay.clone(), 0, 100.0);
        sim.spawn(async move { offset.sleep_until_us(1_005_000).await });
        sim.run_for(core::time::Duration::from_secs(2));
        assert_eq!(fast.virtual_us(), 2_000_000);
        assert_eq!(fast.now_us(), 2_000_200);
        let booted = SimClock::booting_now(medium.clone(), delay, 0.0);
        assert_eq!(booted.now_us(), 0);
        assert_eq!(booted.now_ms(), 0);
    }
}
