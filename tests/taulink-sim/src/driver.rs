//! `LinkClock` for the chip simulator's virtual time. With the driver's own link adapter
//! (`radio_rfm22b::link::LinkRadio`) it puts the link code on `radio-rfm22b` over
//! `si4432-sim`.

pub use radio_rfm22b::link::{LinkRadio, LinkRadioError, modem_for, packet_config};
use si4432_sim::{Medium, SimDelay};
use telemetry::link::LinkClock;

/// A link clock on the chip simulator's virtual time, offset like a separately booted MCU
/// and running `drift_ppm` fast or slow like its crystal.
#[derive(Clone)]
pub struct SimClock {
    medium: Medium,
    delay: SimDelay,
    offset_us: u64,
    drift_ppm: f64,
}

impl SimClock {
    /// A clock reading (virtual time × (1 + drift_ppm·10⁻⁶)) + `offset_us`.
    pub fn new(medium: Medium, delay: SimDelay, offset_us: u64, drift_ppm: f64) -> Self {
        Self {
            medium,
            delay,
            offset_us,
            drift_ppm,
        }
    }

    /// Virtual time without offset or drift (the common reference for measurements).
    pub fn virtual_us(&self) -> u64 {
        self.medium.now().as_micros() as u64
    }
}

impl LinkClock for SimClock {
    fn now_us(&self) -> u64 {
        let v = self.medium.now().as_nanos() as f64 / 1e3;
        (v * (1.0 + self.drift_ppm * 1e-6)) as u64 + self.offset_us
    }

    async fn sleep_until_us(&mut self, deadline_us: u64) {
        let local_wait_us = deadline_us.saturating_sub(self.now_us());
        if local_wait_us > 0 {
            // Local microseconds → virtual nanoseconds, rounded up so we never wake early.
            let virtual_ns =
                (local_wait_us as f64 * 1e3 / (1.0 + self.drift_ppm * 1e-6)).ceil() as u64;
            self.delay.sleep_ns(virtual_ns).await;
        }
    }
}
