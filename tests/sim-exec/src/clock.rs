//! A board's clock on virtual time: the one clock every simulated board reads (the link
//! ends of the packet mock and of the chip world, flight-sitl's boards, the module's tests).
//! It counts from the board's own epoch (booted now, or an offset like a separately booted
//! MCU) and runs `drift_ppm` fast or slow like its crystal; with `telemetry`'s `std` feature
//! it is the link's `telemetry::link::LinkClock`.

use crate::time::VirtualTime;

/// A board's clock: `(virtual time − boot) × (1 + drift_ppm·10⁻⁶) + offset_us`.
#[derive(Clone, Debug)]
pub struct SimClock {
    time: VirtualTime,
    boot_ns: u64,
    offset_us: u64,
    drift_ppm: f64,
}

impl SimClock {
    /// A clock reading (virtual time × (1 + drift_ppm·10⁻⁶)) + `offset_us`: a board booted
    /// `offset_us` before the simulation started.
    pub fn new(time: VirtualTime, offset_us: u64, drift_ppm: f64) -> Self {
        Self {
            time,
            boot_ns: 0,
            offset_us,
            drift_ppm,
        }
    }

    /// The clock of a board booting now: it reads 0 at this instant.
    pub fn booting_now(time: VirtualTime, drift_ppm: f64) -> Self {
        let boot_ns = time.now_ns();
        Self {
            time,
            boot_ns,
            offset_us: 0,
            drift_ppm,
        }
    }

    /// The virtual time this clock reads (and its board's tasks sleep on).
    pub fn time(&self) -> &VirtualTime {
        &self.time
    }

    /// Virtual time without epoch or drift (the common reference for measurements), µs.
    pub fn virtual_us(&self) -> u64 {
        self.time.now_us()
    }

    /// This board's time, µs.
    pub fn now_us(&self) -> u64 {
        let v = self.time.now_ns().saturating_sub(self.boot_ns) as f64 / 1e3;
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
            self.time.sleep_ns(virtual_ns).await;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Executor;

    #[test]
    fn epochs_and_drift_read_as_separate_boards() {
        let time = VirtualTime::new();
        let ex = Executor::new(time.clone());
        let mut offset = SimClock::new(time.clone(), 5_000, 0.0);
        let fast = SimClock::new(time.clone(), 0, 100.0);
        let woke = ex.spawn(async move {
            offset.sleep_until_us(1_005_000).await;
            offset.virtual_us()
        });
        ex.run_for(core::time::Duration::from_secs(2));
        assert_eq!(woke.take(), Some(1_000_000));
        assert_eq!(fast.virtual_us(), 2_000_000);
        assert_eq!(fast.now_us(), 2_000_200);
        let booted = SimClock::booting_now(time, 0.0);
        assert_eq!(booted.now_us(), 0);
        assert_eq!(booted.now_ms(), 0);
    }

    #[test]
    fn a_fast_clock_wakes_its_board_early_in_virtual_time() {
        let time = VirtualTime::new();
        let ex = Executor::new(time.clone());
        let mut fast = SimClock::new(time.clone(), 0, 1_000.0);
        let woke = ex.spawn(async move {
            fast.sleep_until_us(1_001_000).await;
            (fast.virtual_us(), fast.now_us())
        });
        ex.run_for(core::time::Duration::from_secs(2));
        assert_eq!(woke.take(), Some((1_000_000, 1_001_000)));
    }
}
