//! The watchdog check-in policy: which tasks must have checked in before the independent
//! watchdog may be fed. Pure, with time injected: the firmware's supervisor task feeds the
//! STM32 IWDG when [`Watchdog::poll`] says so, and a simulator models the IWDG with
//! [`Watchdog::expired`] (a reset when no feed came within the timeout).

/// The IWDG timeout the firmware programs, ms (LSI 32 kHz / 32, reload 249).
pub const WATCHDOG_TIMEOUT_MS: u32 = 250;
/// How often the supervisor task polls, ms: every task must check in at least this often
/// (two missed polls in a row are a reset).
pub const FEED_PERIOD_MS: u32 = 100;

/// A supervised task.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Task {
    /// The heartbeat LED task.
    Heartbeat,
    /// The link (radio) task: checks in on every follower hook call and while it waits
    /// (bind window, retry after a radio error).
    Link,
    /// The motor output task.
    Motors,
    /// The battery task.
    Battery,
    /// The alert (tone) task.
    Alerts,
    /// The IMU / flight-loop task.
    Imu,
    /// The baro task.
    Baro,
    /// The gain-design task.
    Gains,
}

impl Task {
    /// Every supervised task.
    pub const ALL: [Task; 8] = [
        Task::Heartbeat,
        Task::Link,
        Task::Motors,
        Task::Battery,
        Task::Alerts,
        Task::Imu,
        Task::Baro,
        Task::Gains,
    ];

    const fn bit(self) -> u16 {
        1 << self as u16
    }
}

/// The check-in set and the time of the last feed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Watchdog {
    required: u16,
    checked_in: u16,
    last_feed_ms: u32,
    /// The period in force: [`WATCHDOG_TIMEOUT_MS`], or a stretch around a flash write.
    timeout_ms: u32,
}

impl Watchdog {
    /// Every task in [`Task::ALL`] required; the hardware watchdog starts (is fed) at `now_ms`.
    pub fn new(now_ms: u32) -> Self {
        let required = Task::ALL.iter().fold(0, |acc, t| acc | t.bit());
        Self {
            required,
            checked_in: 0,
            last_feed_ms: now_ms,
            timeout_ms: WATCHDOG_TIMEOUT_MS,
        }
    }

    /// The hardware watchdog was reprogrammed to `timeout_ms` at `now_ms` (which feeds it):
    /// a blocking job such as a sector erase may run that long.
    pub fn stretch(&mut self, now_ms: u32, timeout_ms: u32) {
        self.last_feed_ms = now_ms;
        self.timeout_ms = timeout_ms;
    }

    /// Back to [`WATCHDOG_TIMEOUT_MS`] at `now_ms`, with the feed reprogramming gives.
    pub fn restore(&mut self, now_ms: u32) {
        self.stretch(now_ms, WATCHDOG_TIMEOUT_MS);
    }

    /// The period in force, ms.
    pub fn timeout_ms(&self) -> u32 {
        self.timeout_ms
    }

    /// `task` is alive.
    pub fn check_in(&mut self, task: Task) {
        self.checked_in |= task.bit();
    }

    /// The supervisor's periodic poll: `true` means feed the hardware watchdog now (every
    /// required task checked in since the last feed); the set starts over.
    pub fn poll(&mut self, now_ms: u32) -> bool {
        if self.checked_in & self.required != self.required {
            return false;
        }
        self.checked_in = 0;
        self.last_feed_ms = now_ms;
        true
    }

    /// The tasks that have not checked in since the last feed.
    pub fn missing(&self) -> impl Iterator<Item = Task> + '_ {
        Task::ALL
            .into_iter()
            .filter(|t| self.required & t.bit() != 0 && self.checked_in & t.bit() == 0)
    }

    /// The hardware model: no feed for the timeout in force means the chip has reset.
    pub fn expired(&self, now_ms: u32) -> bool {
        now_ms.wrapping_sub(self.last_feed_ms) >= self.timeout_ms
    }
}
