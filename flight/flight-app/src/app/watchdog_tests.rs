//! The check-in rule and the IWDG margin, simulated with the flight firmware's task periods
//! and latencies at both ends of the LSI's range.

use super::*;

#[test]
fn the_iwdg_keeps_its_margin_over_the_whole_lsi_range() {
    assert_eq!(
        IWDG,
        IwdgSetting {
            prescaler: 0,
            reload: 2349
        }
    );
    let fastest = IWDG.timeout_ms(LSI_MAX_HZ);
    let slowest = IWDG.timeout_ms(LSI_MIN_HZ);
    assert_eq!((fastest, WATCHDOG_TIMEOUT_MS, slowest), (200, 293, 552));
    assert!(fastest >= MARGIN * FEED_GAP_MAX_MS);
    // The setting before: ÷32, reload 249 — 250 ms only at 32 kHz, 170 ms at 47 kHz.
    let before = IwdgSetting {
        prescaler: 3,
        reload: 249,
    };
    assert_eq!(before.timeout_ms(LSI_MAX_HZ), 170);
    // Every timeout the rule can ask for fits a 12-bit reload.
    for ms in [1, 8, 200, 4_000, 22_000] {
        let s = IwdgSetting::at_least(ms);
        assert!(s.reload <= 0xFFF && s.prescaler <= 6);
        assert!(s.timeout_ms(LSI_MAX_HZ) >= ms.min(22_000), "{ms}: {s:?}");
    }
}

/// A deterministic jitter source (SplitMix64): 0 ≤ draw < `below`.
struct Jitter(u64);

impl Jitter {
    fn below(&mut self, below: u32) -> u32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) % u64::from(below.max(1))) as u32
    }
}

/// How a firmware task checks in: every `period_ms`, either on a ticker (the schedule holds,
/// each check-in late by up to the latency) or after a `Timer::after` (each period starts
/// when the previous check-in ran, so lateness accumulates as drift).
#[derive(Clone, Copy)]
struct Cadence {
    task: Task,
    period_ms: u32,
    ticker: bool,
}

/// flight-fw's tasks at their slowest: heartbeat and battery 50 ms tickers, alerts 10 ms,
/// baro 20 ms, the IMU's (and motors') 5 ms poll without edges (its report task checks it
/// in), the link's 50 ms idle check-in, the gains task's `Timer::after(100 ms)`.
const FIRMWARE: [Cadence; 7] = [
    Cadence {
        task: Task::Heartbeat,
        period_ms: 50,
        ticker: true,
    },
    Cadence {
        task: Task::Link,
        period_ms: 50,
        ticker: false,
    },
    Cadence {
        task: Task::Battery,
        period_ms: 50,
        ticker: true,
    },
    Cadence {
        task: Task::Alerts,
        period_ms: 10,
        ticker: true,
    },
    Cadence {
        task: Task::Imu,
        period_ms: 5,
        ticker: false,
    },
    Cadence {
        task: Task::Baro,
        period_ms: 20,
        ticker: true,
    },
    Cadence {
        task: Task::Gains,
        period_ms: 100,
        ticker: false,
    },
];

/// A check-in rule under test: the one in force, or the one before it.
trait Rule {
    fn check_in(&mut self, task: Task);
    /// The poll: feed now?
    fn poll(&mut self) -> bool;
    fn period_ms(&self) -> u32;
}

impl Rule for Watchdog {
    fn check_in(&mut self, task: Task) {
        Watchdog::check_in(self, task);
    }
    fn poll(&mut self) -> bool {
        Watchdog::poll(self, 0)
    }
    fn period_ms(&self) -> u32 {
        FEED_PERIOD_MS
    }
}

/// The rule before: fed at 100 ms polls only when every task checked in since the last
/// feed.
struct SinceLastFeed(u16);

impl Rule for SinceLastFeed {
    fn check_in(&mut self, task: Task) {
        self.0 |= task.bit();
    }
    fn poll(&mut self) -> bool {
        let all = Task::ALL.iter().fold(0, |acc, t| acc | t.bit());
        let feed = self.0 == all;
        if feed {
            self.0 = 0;
        }
        feed
    }
    fn period_ms(&self) -> u32 {
        100
    }
}

/// What a run found: the longest gap between feeds and when the IWDG (timeout `timeout_ms`)
/// would first have fired, ms.
#[derive(Debug)]
struct Run {
    longest_gap_ms: u32,
    reset_at_ms: Option<u32>,
}

/// Runs `rule` for `duration_ms` with the firmware's cadences, every check-in and poll late
/// by up to `latency_ms` (seeded), `dead` stopping one task from a time on.
fn simulate(
    rule: &mut impl Rule,
    timeout_ms: u32,
    latency_ms: u32,
    duration_ms: u32,
    dead: Option<(Task, u32)>,
) -> Run {
    let mut jitter = Jitter(7);
    // Next due time (the schedule) and next actual run per task; the same for the poll.
    let mut due: [u32; 7] = [0; 7];
    let mut runs: [u32; 7] = [0; 7];
    for (i, c) in FIRMWARE.iter().enumerate() {
        due[i] = c.period_ms;
        runs[i] = c.period_ms + jitter.below(latency_ms + 1);
    }
    let period = rule.period_ms();
    let mut poll_due = period;
    let mut poll_at = period + jitter.below(latency_ms + 1);
    let mut last_feed = 0;
    let mut run = Run {
        longest_gap_ms: 0,
        reset_at_ms: None,
    };
    for now in 0..duration_ms {
        for (i, c) in FIRMWARE.iter().enumerate() {
            if runs[i] != now {
                continue;
            }
            if dead.is_none_or(|(t, from)| t != c.task || now < from) {
                rule.check_in(c.task);
            }
            due[i] = if c.ticker {
                due[i] + c.period_ms
            } else {
                now + c.period_ms
            };
            runs[i] = due[i].max(now + 1) + jitter.below(latency_ms + 1);
        }
        if now == poll_at {
            if rule.poll() {
                run.longest_gap_ms = run.longest_gap_ms.max(now - last_feed);
                last_feed = now;
            }
            poll_due += period;
            poll_at = poll_due.max(now + 1) + jitter.below(latency_ms + 1);
        }
        if now - last_feed >= timeout_ms && run.reset_at_ms.is_none() {
            run.reset_at_ms = Some(now);
        }
    }
    run
}

#[test]
fn healthy_tasks_never_reset_the_board_at_either_end_of_the_lsi_range() {
    for lsi in [LSI_MIN_HZ, LSI_TYP_HZ, LSI_MAX_HZ] {
        let timeout = IWDG.timeout_ms(lsi);
        let run = simulate(
            &mut Watchdog::new(0),
            timeout,
            POLL_LATENCY_MAX_MS,
            120_000,
            None,
        );
        assert_eq!(run.reset_at_ms, None, "{lsi} Hz: {run:?}");
        assert!(run.longest_gap_ms <= FEED_GAP_MAX_MS, "{lsi} Hz: {run:?}");
        assert!(timeout >= MARGIN * run.longest_gap_ms, "{lsi} Hz: {run:?}");
    }
}

#[test]
fn the_rule_before_reset_a_fast_lsi_board() {
    // 100 ms polls, fed only when all checked in since the last feed, 250 ms at 32 kHz
    // (÷32, reload 249): the 100 ms tasks drift against the polls and leave 200 ms gaps,
    // beyond the 170 ms the IWDG lasts at 47 kHz.
    let before = IwdgSetting {
        prescaler: 3,
        reload: 249,
    };
    let fast = simulate(
        &mut SinceLastFeed(0),
        before.timeout_ms(LSI_MAX_HZ),
        POLL_LATENCY_MAX_MS,
        120_000,
        None,
    );
    assert!(fast.longest_gap_ms >= 200, "{fast:?}");
    assert!(fast.reset_at_ms.is_some(), "{fast:?}");
    // The rule now, on the same schedule, feeds every poll.
    let now = simulate(
        &mut Watchdog::new(0),
        before.timeout_ms(LSI_MAX_HZ),
        0,
        120_000,
        None,
    );
    assert_eq!(now.longest_gap_ms, FEED_PERIOD_MS, "{now:?}");
}

#[test]
fn a_dead_task_resets_the_board_within_the_window_and_one_timeout() {
    for lsi in [LSI_MIN_HZ, LSI_MAX_HZ] {
        for cadence in FIRMWARE {
            let timeout = IWDG.timeout_ms(lsi);
            let run = simulate(
                &mut Watchdog::new(0),
                timeout,
                POLL_LATENCY_MAX_MS,
                30_000,
                Some((cadence.task, 10_000)),
            );
            let reset = run.reset_at_ms.expect("a dead task stops the feeds");
            // Dead from 10 s: its last check-in was at most one period before; the feeds stop
            // once CHECK_IN_POLLS intervals passed without it, the IWDG fires a timeout later.
            let bound = 10_000
                + (CHECK_IN_POLLS as u32 + 1) * FEED_PERIOD_MS
                + POLL_LATENCY_MAX_MS
                + timeout;
            assert!(
                (10_000..=bound).contains(&reset),
                "{lsi} Hz, {:?}: {reset}",
                cadence.task
            );
        }
    }
}

#[test]
fn a_task_is_alive_for_the_last_check_in_polls_intervals() {
    let mut w = Watchdog::new(0);
    for t in Task::ALL {
        w.check_in(t);
    }
    assert!(w.poll(50));
    // Only the IMU keeps checking in: the others stay alive for the window.
    for k in 2..=CHECK_IN_POLLS as u32 {
        w.check_in(Task::Imu);
        assert!(w.poll(50 * k), "poll {k}");
    }
    w.check_in(Task::Imu);
    assert!(!w.poll(50 * (CHECK_IN_POLLS as u32 + 1)));
    assert_eq!(w.missing().count(), Task::ALL.len() - 1);
    assert!(!w.expired(50 * CHECK_IN_POLLS as u32 + WATCHDOG_TIMEOUT_MS - 1));
    assert!(w.expired(50 * CHECK_IN_POLLS as u32 + WATCHDOG_TIMEOUT_MS));
    // An excused task no longer holds the feeds back.
    for t in Task::ALL {
        if t != Task::Baro {
            w.check_in(t);
        }
    }
    assert!(!w.poll(400));
    w.excuse(Task::Baro);
    assert!(w.poll(450));
    w.require(Task::Baro);
    assert!(!w.poll(500));
}

#[test]
fn the_model_follows_the_lsi() {
    let mut w = Watchdog::new(0);
    w.set_lsi_hz(LSI_MAX_HZ);
    assert!(!w.expired(199));
    assert!(w.expired(200));
    w.set_lsi_hz(LSI_MIN_HZ);
    assert!(!w.expired(551));
    assert!(w.expired(552));
    w.stretch(1_000, 4_000);
    // ÷64, reload 2937: 4.0 s at 47 kHz, 11 s at 17 kHz.
    assert_eq!(
        IwdgSetting::at_least(4_000),
        IwdgSetting {
            prescaler: 4,
            reload: 2937
        }
    );
    assert_eq!(w.timeout_ms(), 11_060);
    assert!(!w.expired(12_059));
    w.restore(12_000);
    assert_eq!(w.timeout_ms(), 552);
}
