//! The module's watchdog check-in rule: which tasks must be alive before the nRF52840's WDT
//! may be fed. Lock-free (atomics), so any task or interrupt may check in; the supervisor task
//! polls every [`FEED_PERIOD_MS`] and feeds the WDT when [`CheckIns::poll`] says so, and
//! flight-sitl's module board runs the same rule against its simulated WDT.
//!
//! **The rule** (the flight side's, `flight_app::app::Watchdog`): a registered task is alive
//! when it checked in during one of the last [`CHECK_IN_POLLS`] poll intervals, and each poll
//! at which all are alive feeds. Counting the window in polls rather than from the last feed
//! keeps a task's period from beating against the poll's (a 100 ms task against 100 ms
//! polls left 200 ms between feeds now and then, against a 250 ms WDT).
//!
//! **The margin.** The longest feed gap while every task is alive is a poll period plus the
//! poll's longest latency, [`FEED_GAP_MAX_MS`]: the supervisor shares the executor with the
//! settings store, whose page erase halts the CPU up to 85 ms. The WDT counts the LFCLK — a
//! crystal, or without one the LFRC, ±2 % uncalibrated (nRF52840 PS, LFRC f_TOL) — so
//! [`WATCHDOG_TIMEOUT_MS`] is chosen to last [`MARGIN`] longest gaps even on an LFRC 2 % fast.
//! A task dead for [`CHECK_IN_POLLS`] polls stops the feeds; the reset follows one timeout
//! later.

use core::sync::atomic::{AtomicU32, Ordering};

/// The WDT timeout the firmware programs, ms (module-fw `board::WATCHDOG_TICKS`, 32 768 Hz).
pub const WATCHDOG_TIMEOUT_MS: u32 = 300;
/// How often the supervisor polls, ms.
pub const FEED_PERIOD_MS: u32 = 50;
/// A task counts as alive when it checked in during one of this many last poll intervals
/// (at least `CHECK_IN_POLLS × FEED_PERIOD_MS − POLL_LATENCY_MAX_MS` = 215 ms): longer than
/// any task's check-in period (the app tick's 100 ms) plus its latency.
pub const CHECK_IN_POLLS: usize = 6;
/// The supervisor's poll comes at most this late, ms: an NVMC page erase halts the CPU
/// (nRF52840 PS, t_ERASEPAGE 85 ms max).
pub const POLL_LATENCY_MAX_MS: u32 = 85;
/// The longest gap between feeds while every task is alive, ms.
pub const FEED_GAP_MAX_MS: u32 = FEED_PERIOD_MS + POLL_LATENCY_MAX_MS;
/// The WDT lasts at least this many longest feed gaps, on the fastest LF clock.
pub const MARGIN: u32 = 2;
/// The fastest LF clock the WDT may count, ppm above 32 768 Hz: the LFRC's uncalibrated
/// tolerance (the crystals are within 50 ppm).
pub const LFCLK_FAST_PPM: u32 = 20_000;

/// The WDT's timeout when its clock runs `ppm` fast, ms (rounded down).
pub const fn timeout_at_ppm(ppm: u32) -> u32 {
    (WATCHDOG_TIMEOUT_MS as u64 * 1_000_000 / (1_000_000 + ppm as u64)) as u32
}

/// A supervised task (one bit each).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u32)]
pub enum Watched {
    /// The status LED task.
    StatusLed = 1 << 0,
    /// The radio task.
    Radio = 1 << 1,
    /// PPM capture (transmitter role, PPM input).
    PpmIn = 1 << 2,
    /// PPM output (receiver role).
    PpmOut = 1 << 3,
    /// JR pin 5 line (transmitter role).
    JrLine = 1 << 4,
    /// HM-10 UART.
    Hm10 = 1 << 5,
    /// Battery ADC.
    Battery = 1 << 6,
    /// Bind button.
    Button = 1 << 7,
    /// Settings storage.
    Settings = 1 << 8,
    /// The module core's periodic work.
    App = 1 << 9,
}

/// The expected tasks and their check-ins over the last polls.
#[derive(Debug, Default)]
pub struct CheckIns {
    expected: AtomicU32,
    /// Check-ins since the last poll.
    checked_in: AtomicU32,
    /// The check-ins of the last [`CHECK_IN_POLLS`] − 1 poll intervals, newest first (only
    /// the poll writes them).
    history: [AtomicU32; CHECK_IN_POLLS - 1],
}

impl CheckIns {
    /// Nothing expected yet.
    pub const fn new() -> Self {
        Self {
            expected: AtomicU32::new(0),
            checked_in: AtomicU32::new(0),
            history: [const { AtomicU32::new(0) }; CHECK_IN_POLLS - 1],
        }
    }

    /// Registers a task before it starts: from then on it must check in. It counts as
    /// checked in now, so it has the whole window to check in first.
    pub fn expect(&self, task: Watched) {
        self.expected.fetch_or(task as u32, Ordering::Relaxed);
        self.check_in(task);
    }

    /// A task is alive (at least every [`CHECK_IN_POLLS`] polls).
    pub fn check_in(&self, task: Watched) {
        self.checked_in.fetch_or(task as u32, Ordering::Relaxed);
    }

    /// The supervisor's poll: true when every expected task checked in during the last
    /// [`CHECK_IN_POLLS`] intervals — feed the WDT now. The interval ends here either way.
    pub fn poll(&self) -> bool {
        let newest = self.checked_in.swap(0, Ordering::Relaxed);
        let mut alive = newest;
        let mut carry = newest;
        for slot in &self.history {
            let older = slot.swap(carry, Ordering::Relaxed);
            alive |= older;
            carry = older;
        }
        let expected = self.expected.load(Ordering::Relaxed);
        alive & expected == expected
    }
}

#[cfg(test)]
#[path = "watchdog_tests.rs"]
mod tests;
