//! The check-in rule and the WDT margin, simulated with the module firmware's task periods
//! and latencies, the LF clock at its fastest.

use super::*;

#[test]
fn the_wdt_keeps_its_margin_on_the_fastest_lf_clock() {
    let fastest = timeout_at_ppm(LFCLK_FAST_PPM);
    assert_eq!(fastest, 294);
    assert!(fastest >= MARGIN * FEED_GAP_MAX_MS, "{fastest} ms");
    // The timeout before, 250 ms, held 1.85 longest gaps.
    const { assert!(250 < MARGIN * FEED_GAP_MAX_MS) };
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

/// module-fw's tasks at their slowest: (task, period ms, on a ticker — else each period
/// starts when the previous check-in ran). The status LED and the HM-10 sleep between steps,
/// the link task checks in every `session::POLL_MS`, PPM input at its idle tick, PPM output
/// per frame, the JR line and settings at their 50 ms receive timeouts, the app's 10 Hz tick.
const FIRMWARE: [(Watched, u32, bool); 10] = [
    (Watched::StatusLed, 25, false),
    (Watched::Radio, crate::session::POLL_MS, false),
    (Watched::PpmIn, 50, false),
    (Watched::PpmOut, 23, true),
    (Watched::JrLine, 50, false),
    (Watched::Hm10, 20, false),
    (Watched::Battery, 50, true),
    (Watched::Button, 10, true),
    (Watched::Settings, 50, false),
    (Watched::App, 100, true),
];

/// A check-in rule under test: `poll` feeds or not; its poll period.
trait Rule {
    fn check_in(&mut self, task: Watched);
    fn poll(&mut self) -> bool;
    fn period_ms(&self) -> u32;
}

impl Rule for CheckIns {
    fn check_in(&mut self, task: Watched) {
        CheckIns::check_in(self, task);
    }
    fn poll(&mut self) -> bool {
        CheckIns::poll(self)
    }
    fn period_ms(&self) -> u32 {
        FEED_PERIOD_MS
    }
}

/// The rule before: 100 ms polls, fed only when every task checked in since the last feed.
struct SinceLastFeed(u32);

impl Rule for SinceLastFeed {
    fn check_in(&mut self, task: Watched) {
        self.0 |= task as u32;
    }
    fn poll(&mut self) -> bool {
        let all = FIRMWARE.iter().fold(0, |acc, (t, _, _)| acc | *t as u32);
        let feed = self.0 & all == all;
        if feed {
            self.0 = 0;
        }
        feed
    }
    fn period_ms(&self) -> u32 {
        100
    }
}

/// Runs `rule` with every task registered; returns the longest feed gap and the first
/// time the WDT (`timeout_ms`) would have fired, with every check-in and poll late by up to
/// `latency_ms` and `dead` stopping a task from a time on.
fn simulate(
    rule: &mut impl Rule,
    timeout_ms: u32,
    latency_ms: u32,
    duration_ms: u32,
    dead: Option<(Watched, u32)>,
) -> (u32, Option<u32>) {
    let mut jitter = Jitter(11);
    let mut due = [0u32; 10];
    let mut runs = [0u32; 10];
    for (i, (_, period, _)) in FIRMWARE.iter().enumerate() {
        due[i] = *period;
        runs[i] = period + jitter.below(latency_ms + 1);
    }
    let period = rule.period_ms();
    let (mut poll_due, mut poll_at) = (period, period + jitter.below(latency_ms + 1));
    let (mut last_feed, mut longest, mut reset) = (0, 0, None);
    for now in 0..duration_ms {
        for (i, (task, period, ticker)) in FIRMWARE.iter().enumerate() {
            if runs[i] != now {
                continue;
            }
            if dead.is_none_or(|(t, from)| t != *task || now < from) {
                rule.check_in(*task);
            }
            due[i] = if *ticker {
                due[i] + period
            } else {
                now + period
            };
            runs[i] = due[i].max(now + 1) + jitter.below(latency_ms + 1);
        }
        if now == poll_at {
            if rule.poll() {
                longest = longest.max(now - last_feed);
                last_feed = now;
            }
            poll_due += period;
            poll_at = poll_due.max(now + 1) + jitter.below(latency_ms + 1);
        }
        if now - last_feed >= timeout_ms && reset.is_none() {
            reset = Some(now);
        }
    }
    (longest, reset)
}

fn registered() -> CheckIns {
    let c = CheckIns::new();
    for (task, _, _) in FIRMWARE {
        c.expect(task);
    }
    c
}

#[test]
fn healthy_tasks_never_reset_the_module_on_the_fastest_lf_clock() {
    let timeout = timeout_at_ppm(LFCLK_FAST_PPM);
    let (longest, reset) = simulate(
        &mut registered(),
        timeout,
        POLL_LATENCY_MAX_MS,
        120_000,
        None,
    );
    assert_eq!(reset, None);
    assert!(longest <= FEED_GAP_MAX_MS, "{longest}");
    assert!(timeout >= MARGIN * longest);
}

#[test]
fn the_rule_before_left_gaps_twice_its_poll() {
    let (longest, _) = simulate(
        &mut SinceLastFeed(0),
        250,
        POLL_LATENCY_MAX_MS,
        120_000,
        None,
    );
    assert!(longest >= 200, "{longest}");
    // With a page erase in the way, beyond the 250 ms WDT.
    let (_, reset) = simulate(
        &mut SinceLastFeed(0),
        250,
        POLL_LATENCY_MAX_MS,
        600_000,
        None,
    );
    assert!(reset.is_some());
}

#[test]
fn a_dead_task_resets_the_module_within_the_window_and_one_timeout() {
    for (task, _, _) in FIRMWARE {
        let timeout = timeout_at_ppm(LFCLK_FAST_PPM);
        let (_, reset) = simulate(
            &mut registered(),
            timeout,
            POLL_LATENCY_MAX_MS,
            20_000,
            Some((task, 5_000)),
        );
        let reset = reset.expect("a dead task stops the feeds");
        let bound =
            5_000 + (CHECK_IN_POLLS as u32 + 1) * FEED_PERIOD_MS + POLL_LATENCY_MAX_MS + timeout;
        assert!((5_000..=bound).contains(&reset), "{task:?}: {reset}");
    }
}

#[test]
fn a_feed_needs_every_expected_task_within_the_window() {
    let c = CheckIns::new();
    c.expect(Watched::Radio);
    c.expect(Watched::App);
    // Registered counts as checked in: the whole window to start.
    for k in 0..CHECK_IN_POLLS {
        assert!(c.poll(), "grace poll {k}");
    }
    assert!(!c.poll(), "nobody checked in");
    c.check_in(Watched::Radio);
    assert!(!c.poll(), "the app did not");
    c.check_in(Watched::App);
    assert!(c.poll());
    assert!(c.poll(), "both still within the window");
}

#[test]
fn an_unexpected_task_neither_helps_nor_blocks() {
    let c = CheckIns::new();
    c.expect(Watched::Radio);
    for _ in 0..CHECK_IN_POLLS {
        c.poll();
    }
    c.check_in(Watched::Hm10);
    assert!(!c.poll());
    c.check_in(Watched::Radio);
    assert!(c.poll());
}

#[test]
fn nothing_expected_feeds() {
    assert!(CheckIns::new().poll());
}
