//! The barometer's health: when a failing MS5611 is declared failed, and what follows.
//!
//! The baro task bounds every I²C transaction with a timeout and recovers the bus (nine SCL
//! clocks and a STOP, then I2C1 re-initialised) at boot and after each timeout, so it never
//! hangs; it hands each reading, or `None` for a failed one, to [`FlightApp::on_baro`]. Here:
//! [`BARO_FAILED_AFTER`] failed readings in a row declare the baro failed. Then the watchdog
//! no longer requires the baro task (a baro is not worth a reset, in the air least of all),
//! the hold modes fall back to attitude mode (the loop's input `vertical_lost`,
//! `FlightLoop::set_vertical_lost`: the switch
//! cannot engage them, an engaged one hands the throttle back), the pilot hears the sensor
//! alert, and `status` and the telemetry's health report say so. [`BARO_HEALTHY_AFTER`] good
//! readings in a row take it all back.

use super::{FlightApp, Task};
use crate::alerts::Alert;

/// Failed readings in a row that declare the baro failed (at the task's 50 Hz: 0.1 s of
/// readings, or five timed-out transactions and bus recoveries).
pub const BARO_FAILED_AFTER: u8 = 5;
/// Good readings in a row that declare a failed baro healthy again (1 s at 50 Hz).
pub const BARO_HEALTHY_AFTER: u8 = 50;
/// How soon the baro task tries a failed reading's bus clear and re-initialisation again,
/// ms: at the reading period while the baro counts as healthy, once a second once it is
/// declared failed (each try costs the task a few ms of I²C and conversion waits).
pub const BARO_RETRY_MS: [u32; 2] = [20, 1_000];

/// The baro's health as the readings tell it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BaroHealth {
    failed: bool,
    /// Failed (or, while failed, good) readings in a row.
    run: u8,
    /// Failed readings since boot.
    failures: u32,
}

/// A change of the baro's standing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BaroChange {
    /// Declared failed.
    Failed,
    /// Healthy again.
    Recovered,
}

impl BaroHealth {
    /// The baro was declared failed and has not recovered.
    pub fn failed(&self) -> bool {
        self.failed
    }

    /// Failed readings since boot.
    pub fn failures(&self) -> u32 {
        self.failures
    }

    /// One reading, good or not; the change it makes, if any.
    pub fn on_reading(&mut self, good: bool) -> Option<BaroChange> {
        if !good {
            self.failures = self.failures.saturating_add(1);
        }
        // While healthy count failures in a row, while failed good readings in a row.
        if good == self.failed {
            self.run = self.run.saturating_add(1);
        } else {
            self.run = 0;
        }
        let limit = if self.failed {
            BARO_HEALTHY_AFTER
        } else {
            BARO_FAILED_AFTER
        };
        if self.run < limit {
            return None;
        }
        self.run = 0;
        self.failed = !self.failed;
        Some(if self.failed {
            BaroChange::Failed
        } else {
            BaroChange::Recovered
        })
    }
}

impl FlightApp {
    /// A baro altitude (`None`: the reading failed or timed out) at `now_ms`.
    pub fn on_baro(&mut self, now_ms: u32, altitude_m: Option<f32>) {
        self.watchdog.check_in(Task::Baro);
        match self.baro.on_reading(altitude_m.is_some()) {
            Some(BaroChange::Failed) => {
                self.watchdog.excuse(Task::Baro);
                self.player.push(Alert::SensorFault);
            }
            Some(BaroChange::Recovered) => self.watchdog.require(Task::Baro),
            None => {}
        }
        self.climb_mps = altitude_m.and_then(|a| self.climb.update(now_ms, a));
        if self.climb_mps.is_some() && self.baro_ground_m.is_none() {
            self.baro_ground_m = self.climb.altitude_m();
        }
        if let Some(a) = altitude_m {
            // For the loop's INS, with its next step (the log has it at its reading's time).
            self.log.on_baro(now_ms, a);
            self.pending_baro_m = altitude_m;
        }
    }

    /// The baro's health.
    pub fn baro_health(&self) -> BaroHealth {
        self.baro
    }

    /// After a failed reading, how long the baro task waits before it clears the bus and
    /// initialises the sensor again, ms ([`BARO_RETRY_MS`]).
    pub fn baro_retry_ms(&self) -> u32 {
        let [healthy, failed] = BARO_RETRY_MS;
        if self.baro.failed() { failed } else { healthy }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::Settings;
    use crate::supervisor::FlightMode;

    #[test]
    fn five_failures_in_a_row_declare_it_failed_fifty_good_ones_recover_it() {
        let mut h = BaroHealth::default();
        for _ in 0..4 {
            assert_eq!(h.on_reading(false), None);
        }
        // A good reading in between starts the count over.
        assert_eq!(h.on_reading(true), None);
        for _ in 0..4 {
            assert_eq!(h.on_reading(false), None);
        }
        assert_eq!(h.on_reading(false), Some(BaroChange::Failed));
        assert!(h.failed());
        for _ in 0..49 {
            assert_eq!(h.on_reading(true), None);
        }
        assert_eq!(h.on_reading(false), None);
        for _ in 0..49 {
            assert_eq!(h.on_reading(true), None);
        }
        assert_eq!(h.on_reading(true), Some(BaroChange::Recovered));
        assert_eq!(h.failures(), 10);
    }

    #[test]
    fn a_failed_baro_never_resets_the_board_and_the_hold_modes_fall_back() {
        let mut app = FlightApp::new(Settings::default(), 0).unwrap();
        for t in 0..5 {
            app.on_baro(20 * t, None);
        }
        assert!(app.baro_health().failed());
        assert_eq!(app.baro_retry_ms(), 1_000);
        // The baro task stops checking in (stuck for good): every other task keeps the
        // feeds coming, well past the window and the IWDG's longest timeout.
        for k in 1..=40 {
            for task in Task::ALL {
                if task != Task::Baro {
                    app.check_in(task);
                }
            }
            assert!(app.on_watchdog_poll(100 + 50 * k), "poll {k}");
        }
        assert!(app.loop_inputs().vertical_lost);
        app.on_imu_sample(3_000, &crate::app::tests::resting(0));
        let flight = app.loop_side().unwrap().flight_loop();
        assert_eq!(
            flight.effective_mode(FlightMode::AltitudeHold),
            FlightMode::Attitude
        );
        // Healthy again: required again, and the hold modes engage.
        for t in 0..50 {
            app.on_baro(3_000 + 20 * t, Some(100.0));
        }
        assert!(!app.baro_health().failed());
        app.on_imu_sample(4_000, &crate::app::tests::resting(1));
        let flight = app.loop_side().unwrap().flight_loop();
        assert_eq!(
            flight.effective_mode(FlightMode::AltitudeHold),
            FlightMode::AltitudeHold
        );
        for _ in 0..crate::app::CHECK_IN_POLLS {
            for task in Task::ALL {
                if task != Task::Baro {
                    app.check_in(task);
                }
            }
            app.on_watchdog_poll(5_000);
        }
        assert!(
            !app.on_watchdog_poll(5_050),
            "a silent baro task holds the feeds again"
        );
    }
}
