//! The module's watchdog check-in policy: which tasks must have checked in since the last
//! feed before the nRF52840's WDT may be fed. Lock-free (atomics), so any task or interrupt
//! may check in; the supervisor task polls every [`FEED_PERIOD_MS`] and feeds the WDT when
//! [`CheckIns::poll`] says so, and flight-sitl's module board runs the same policy against
//! its simulated WDT. A task that stops checking in stops the feeds: a reset within
//! [`WATCHDOG_TIMEOUT_MS`].

use core::sync::atomic::{AtomicU32, Ordering};

/// The WDT timeout the firmware programs, ms (module-fw `board::WATCHDOG_TICKS`, 32 768 Hz).
pub const WATCHDOG_TIMEOUT_MS: u32 = 250;
/// How often the supervisor polls, ms: every expected task must check in at least this often.
pub const FEED_PERIOD_MS: u32 = 100;

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

/// The expected tasks and those that checked in since the last feed.
#[derive(Debug, Default)]
pub struct CheckIns {
    expected: AtomicU32,
    checked_in: AtomicU32,
}

impl CheckIns {
    /// Nothing expected yet.
    pub const fn new() -> Self {
        Self {
            expected: AtomicU32::new(0),
            checked_in: AtomicU32::new(0),
        }
    }

    /// Registers a task before it starts: from then on it must check in.
    pub fn expect(&self, task: Watched) {
        self.expected.fetch_or(task as u32, Ordering::Relaxed);
    }

    /// A task is alive (at least every [`FEED_PERIOD_MS`]).
    pub fn check_in(&self, task: Watched) {
        self.checked_in.fetch_or(task as u32, Ordering::Relaxed);
    }

    /// The supervisor's poll: true when every expected task has checked in since the last
    /// feed — feed the WDT now; the check-ins start over. False leaves them, so a task that
    /// checks in late still counts at the next poll (the WDT's timeout is the limit).
    pub fn poll(&self) -> bool {
        let expected = self.expected.load(Ordering::Relaxed);
        if self.checked_in.load(Ordering::Relaxed) & expected == expected {
            self.checked_in.store(0, Ordering::Relaxed);
            true
        } else {
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_feed_needs_every_expected_task_since_the_last_one() {
        let c = CheckIns::new();
        c.expect(Watched::Radio);
        c.expect(Watched::App);
        assert!(!c.poll(), "nobody checked in");
        c.check_in(Watched::Radio);
        assert!(!c.poll(), "the app did not");
        c.check_in(Watched::App);
        assert!(c.poll());
        assert!(!c.poll(), "check-ins start over after a feed");
    }

    #[test]
    fn an_unexpected_task_neither_helps_nor_blocks() {
        let c = CheckIns::new();
        c.expect(Watched::Radio);
        c.check_in(Watched::Hm10);
        assert!(!c.poll());
        c.check_in(Watched::Radio);
        assert!(c.poll());
    }

    #[test]
    fn nothing_expected_feeds() {
        assert!(CheckIns::new().poll());
    }
}
