//! The watchdog: the check-in rule that decides when the STM32's independent watchdog may be
//! fed, and the IWDG's programming, with its margin over the whole LSI range. Pure, with
//! time injected: the firmware's supervisor task feeds the IWDG when [`Watchdog::poll`] says
//! so and programs [`IWDG`]; a simulator models the IWDG with [`Watchdog::expired`].
//!
//! **The rule.** The supervisor polls every [`FEED_PERIOD_MS`]. A supervised task is alive
//! when it checked in during one of the last [`CHECK_IN_POLLS`] poll intervals; every poll
//! at which all of them are alive feeds. The window is counted in polls, not from the last
//! feed, so a task's period never beats against the poll's: a task that checks in every
//! 100 ms keeps the feeds coming every 50 ms (with "since the last feed", a 100 ms task
//! drifting against 100 ms polls left a 200 ms gap now and then).
//!
//! **The margin.** While every task is alive the longest feed gap is one poll period plus
//! the poll's longest latency, [`FEED_GAP_MAX_MS`]: the supervisor shares the thread-mode
//! executor with the gain design, the longest poll there ([`POLL_LATENCY_MAX_MS`]). The
//! IWDG counts the LSI, which DS8626 allows anywhere in 17–47 kHz; [`IWDG`] is chosen so
//! that its timeout at the fastest LSI is [`MARGIN`] times that gap, which makes it
//! [`IWDG`]`.timeout_ms(LSI_MIN_HZ)` at the slowest. A task dead for
//! [`CHECK_IN_POLLS`] polls stops the feeds; the reset follows one timeout later.

/// The LSI's range and typical frequency, Hz (DS8626 table "LSI oscillator
/// characteristics": f_LSI 17 min, 32 typ, 47 max kHz).
pub const LSI_MIN_HZ: u32 = 17_000;
/// See [`LSI_MIN_HZ`].
pub const LSI_TYP_HZ: u32 = 32_000;
/// See [`LSI_MIN_HZ`].
pub const LSI_MAX_HZ: u32 = 47_000;

/// How often the supervisor polls, ms.
pub const FEED_PERIOD_MS: u32 = 50;
/// A task counts as alive when it checked in during one of this many last poll intervals
/// (at least `CHECK_IN_POLLS × FEED_PERIOD_MS − POLL_LATENCY_MAX_MS` = 250 ms): longer than
/// any task's check-in period (100 ms) plus its own latency.
pub const CHECK_IN_POLLS: usize = 6;
/// The supervisor's poll comes at most this late, ms: the longest poll of another task on
/// its executor, the gain design (≈ 42.7 ms of CPU, `flight-sitl`'s `DESIGN_US`), stretched
/// by the flight loop's interrupt share (≈ 15 % at 1 kHz).
pub const POLL_LATENCY_MAX_MS: u32 = 50;
/// The longest gap between feeds while every task is alive, ms.
pub const FEED_GAP_MAX_MS: u32 = FEED_PERIOD_MS + POLL_LATENCY_MAX_MS;
/// The IWDG timeout at the fastest LSI is at least this many longest feed gaps.
pub const MARGIN: u32 = 2;

/// IWDG programming: the prescaler code PR (divider 4 · 2^PR) and the 12-bit reload RL
/// (RM0090 §21.3.2: timeout = 4 · 2^PR · (RL + 1) / f_LSI).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct IwdgSetting {
    /// IWDG_PR, 0 (÷4) … 6 (÷256).
    pub prescaler: u8,
    /// IWDG_RLR, 0 … 0xFFF.
    pub reload: u16,
}

impl IwdgSetting {
    /// The shortest setting whose timeout at the fastest LSI is at least `min_ms` (the
    /// smallest prescaler that fits, for the finest reload); 8 ms … 22 s.
    pub const fn at_least(min_ms: u32) -> Self {
        let mut prescaler = 0;
        loop {
            let divider = 4u64 << prescaler;
            // ticks = ceil(min_ms · f / (1000 · divider))
            let num = min_ms as u64 * LSI_MAX_HZ as u64;
            let den = 1_000 * divider;
            let ticks = num.div_ceil(den);
            if ticks <= 0x1000 || prescaler == 6 {
                let ticks = if ticks == 0 {
                    1
                } else if ticks > 0x1000 {
                    0x1000
                } else {
                    ticks
                };
                return Self {
                    prescaler,
                    reload: (ticks - 1) as u16,
                };
            }
            prescaler += 1;
        }
    }

    /// The LSI divider, 4 · 2^PR.
    pub const fn divider(&self) -> u32 {
        4 << self.prescaler
    }

    /// The timeout at `lsi_hz`, ms (rounded down; 0 for a 0 Hz LSI).
    pub const fn timeout_ms(&self, lsi_hz: u32) -> u32 {
        let ticks = (self.reload as u64 + 1) * self.divider() as u64 * 1_000;
        match ticks.checked_div(lsi_hz as u64) {
            Some(ms) if ms <= u32::MAX as u64 => ms as u32,
            Some(_) => u32::MAX,
            None => 0,
        }
    }
}

/// The IWDG as the firmware programs it: [`MARGIN`] × [`FEED_GAP_MAX_MS`] at the fastest
/// LSI (÷4, reload 2349: 200 ms at 47 kHz, 293 ms at 32 kHz, 552 ms at 17 kHz).
pub const IWDG: IwdgSetting = IwdgSetting::at_least(MARGIN * FEED_GAP_MAX_MS);
/// The IWDG timeout at the typical LSI, ms (what the simulators model by default).
pub const WATCHDOG_TIMEOUT_MS: u32 = IWDG.timeout_ms(LSI_TYP_HZ);

/// A supervised task.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Task {
    /// The heartbeat LED task.
    Heartbeat,
    /// The link (radio) task: checks in on every follower hook call and while it waits
    /// (bind window, retry after a radio error).
    Link,
    /// The battery task.
    Battery,
    /// The alert (tone) task.
    Alerts,
    /// The IMU / flight-loop task (it drives the motor outputs too).
    Imu,
    /// The baro task.
    Baro,
    /// The gain-design task.
    Gains,
}

impl Task {
    /// Every supervised task.
    pub const ALL: [Task; 7] = [
        Task::Heartbeat,
        Task::Link,
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

/// The check-ins of the last polls and the time of the last feed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Watchdog {
    required: u16,
    /// Check-ins since the last poll.
    checked_in: u16,
    /// The check-ins of the last [`CHECK_IN_POLLS`] − 1 poll intervals, newest first.
    history: [u16; CHECK_IN_POLLS - 1],
    last_feed_ms: u32,
    /// The period in force at the modelled LSI: [`IWDG`]'s, or a stretch around a flash
    /// write.
    timeout_ms: u32,
    /// The LSI the model counts, Hz (the firmware's never matters: it only polls).
    lsi_hz: u32,
}

impl Watchdog {
    /// Every task in [`Task::ALL`] required; the hardware watchdog starts (is fed) at
    /// `now_ms`, modelled at the typical LSI. Every task counts as checked in at the start:
    /// each has the whole window to check in first, as after any check-in.
    pub fn new(now_ms: u32) -> Self {
        let required = Task::ALL.iter().fold(0, |acc, t| acc | t.bit());
        Self {
            required,
            checked_in: required,
            history: [0; CHECK_IN_POLLS - 1],
            last_feed_ms: now_ms,
            timeout_ms: WATCHDOG_TIMEOUT_MS,
            lsi_hz: LSI_TYP_HZ,
        }
    }

    /// The model counts an LSI of `lsi_hz` (a simulation of a fast or slow chip).
    pub fn set_lsi_hz(&mut self, lsi_hz: u32) {
        self.lsi_hz = lsi_hz;
        self.timeout_ms = IWDG.timeout_ms(lsi_hz);
    }

    /// The hardware watchdog was reprogrammed to `IwdgSetting::at_least(min_ms)` at `now_ms`
    /// (which feeds it): a blocking job such as a sector erase may run at least `min_ms`.
    pub fn stretch(&mut self, now_ms: u32, min_ms: u32) {
        self.last_feed_ms = now_ms;
        self.timeout_ms = IwdgSetting::at_least(min_ms).timeout_ms(self.lsi_hz);
    }

    /// Back to [`IWDG`] at `now_ms`, with the feed reprogramming gives.
    pub fn restore(&mut self, now_ms: u32) {
        self.last_feed_ms = now_ms;
        self.timeout_ms = IWDG.timeout_ms(self.lsi_hz);
    }

    /// The period in force, ms.
    pub fn timeout_ms(&self) -> u32 {
        self.timeout_ms
    }

    /// `task` is alive.
    pub fn check_in(&mut self, task: Task) {
        self.checked_in |= task.bit();
    }

    /// A task that is optional from now on (a sensor declared failed) no longer holds the
    /// feeds back; [`Watchdog::require`] takes it back.
    pub fn excuse(&mut self, task: Task) {
        self.required &= !task.bit();
    }

    /// `task` is required again.
    pub fn require(&mut self, task: Task) {
        self.required |= task.bit();
    }

    fn alive(&self) -> u16 {
        self.history.iter().fold(self.checked_in, |acc, h| acc | h)
    }

    /// The supervisor's periodic poll: `true` means feed the hardware watchdog now (every
    /// required task checked in during the last [`CHECK_IN_POLLS`] intervals). The interval
    /// ends here either way.
    pub fn poll(&mut self, now_ms: u32) -> bool {
        let feed = self.alive() & self.required == self.required;
        self.history.rotate_right(1);
        if let Some(newest) = self.history.first_mut() {
            *newest = self.checked_in;
        }
        self.checked_in = 0;
        if feed {
            self.last_feed_ms = now_ms;
        }
        feed
    }

    /// The required tasks that have not checked in during the last [`CHECK_IN_POLLS`]
    /// intervals.
    pub fn missing(&self) -> impl Iterator<Item = Task> + '_ {
        let alive = self.alive();
        Task::ALL
            .into_iter()
            .filter(move |t| self.required & t.bit() != 0 && alive & t.bit() == 0)
    }

    /// The hardware model: no feed for the timeout in force means the chip has reset.
    pub fn expired(&self, now_ms: u32) -> bool {
        now_ms.wrapping_sub(self.last_feed_ms) >= self.timeout_ms
    }
}

#[cfg(test)]
#[path = "watchdog_tests.rs"]
mod tests;
