//! Dynamic transmit power: which of the RFM22B's eight power steps (0 = +1 dBm … 7 = +20 dBm,
//! `radio_rfm22b::TxPower`) a link end sends at, chosen from how the *other* end reports
//! hearing it (the [`LinkReport`] each end's frames carry: smoothed RSSI and LQ of our
//! packets), as ExpressLRS' dynamic power does on its transmitter. The application decides
//! here and hands the step to its state machine (`Master::set_tx_power`,
//! `Follower::set_tx_power`); the link loop writes the radio's power register between slots.
//!
//! The rule, in margin over the rate mode's sensitivity ([`RateMode::sensitivity_dbm`]):
//! - below [`RAISE_BELOW_DB`] (or a reported LQ below [`RAISE_LQ`]): one step up, after a
//!   step up only once the reports have had time to show it ([`SETTLE_REPORTS`]);
//! - from [`LOWER_FROM_DB`] with LQ ≥ [`LOWER_LQ`] held for [`LOWER_HOLD_US`] and
//!   [`SETTLE_REPORTS`] reports: one step down, so at most one step a second;
//! - at once to the maximum while not connected, when the reported LQ falls below
//!   [`BOOST_LQ`], or after [`MISSED_REPORTS`] report periods without a report.
//!
//! Never above the set maximum; with dynamic power off, always the maximum. Pure and
//! integer-only: time comes in with each update.

use crate::frame::LinkReport;
use crate::link::rate::RateMode;

/// The highest power step (+20 dBm).
pub const MAX_STEP: u8 = 7;
/// Raise a step while the reported RSSI is less than this above sensitivity. 10 dB: the
/// Si4432's sensitivity is its BER 10⁻³ point, where a 20–60-byte frame fails one time in
/// three; 10 dB over it the bit errors are gone, and the rest is room for what a decision
/// every few hundred milliseconds cannot follow (a turn of the quad, a hand on the antenna).
pub const RAISE_BELOW_DB: i16 = 10;
/// Lower a step while the reported RSSI is at least this above sensitivity. A step is 3 dB,
/// so one step down leaves ≥ 17 dB, 7 dB above [`RAISE_BELOW_DB`]: the smoothed RSSI's
/// wander of a dB or two never bounces it straight back up.
pub const LOWER_FROM_DB: i16 = 20;
/// Raise a step while the reported LQ is below this, whatever the RSSI says (interference
/// RSSI does not show); ExpressLRS raises below 85 %.
pub const RAISE_LQ: u8 = 95;
/// Lower only while the reported LQ is at least this.
pub const LOWER_LQ: u8 = 98;
/// To the maximum at once when the reported LQ falls below this: a fifth of the last 100
/// packets lost is a link falling faster than step-by-step follows (ExpressLRS boosts on a
/// drop of 20 points; its absolute floor of 50 % is lower than the ≥ 95 % LQ kept here).
pub const BOOST_LQ: u8 = 80;
/// To the maximum at once after this many report periods without a report of the other end.
pub const MISSED_REPORTS: u32 = 3;
/// The margin must hold this long, and a step last this long, before a step down.
pub const LOWER_HOLD_US: u64 = 1_000_000;
/// Reports that must arrive after a change before a step down, or after a step up before
/// the next: the other end smooths its RSSI by 1/8 per packet, so its reports take that long
/// to show most of a 3 dB change.
pub const SETTLE_REPORTS: u8 = 8;

/// What the controller is told at each update.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PowerInput {
    /// The end's link clock.
    pub now_us: u64,
    /// The link's rate mode (its sensitivity).
    pub rate: RateMode,
    /// The link is up (master: a downlink within its timeout; follower: not in failsafe).
    pub connected: bool,
    /// The other end's latest report of how it hears us, with the time it arrived.
    pub report: Option<(LinkReport, u64)>,
    /// How often a report is due (a telemetry cycle: the telemetry ratio's slots).
    pub report_period_us: u32,
}

/// The power controller of one link end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PowerControl {
    max: u8,
    dynamic: bool,
    step: u8,
    /// Reports arrived since the last change (saturating).
    reports_since_change: u8,
    /// The last change was a step up (the next waits for the reports to show it).
    raised: bool,
    /// When the last step change was made.
    changed_us: Option<u64>,
    /// Since when the margin to lower has held.
    holding_since_us: Option<u64>,
    /// Arrival time of the last report counted.
    last_report_us: Option<u64>,
}

impl PowerControl {
    /// A controller capped at step `max` (0…7; more is 7), dynamic or fixed; it starts at the
    /// maximum (not connected yet).
    pub const fn new(max: u8, dynamic: bool) -> Self {
        let max = if max > MAX_STEP { MAX_STEP } else { max };
        Self {
            max,
            dynamic,
            step: max,
            reports_since_change: 0,
            raised: false,
            changed_us: None,
            holding_since_us: None,
            last_report_us: None,
        }
    }

    /// The step to send at now.
    pub const fn step(&self) -> u8 {
        self.step
    }

    /// The set maximum.
    pub const fn max(&self) -> u8 {
        self.max
    }

    /// Whether the power follows the link (else it stays at the maximum).
    pub const fn dynamic(&self) -> bool {
        self.dynamic
    }

    /// New settings: a lower maximum applies at once, a higher one or dynamic power turned
    /// off goes to the new maximum.
    pub fn configure(&mut self, max: u8, dynamic: bool) {
        if (max, dynamic) != (self.max, self.dynamic) {
            *self = Self {
                last_report_us: self.last_report_us,
                ..Self::new(max, dynamic)
            };
        }
    }

    /// Takes the state of the link and returns the step to send at.
    pub fn update(&mut self, input: &PowerInput) -> u8 {
        self.count_report(input);
        if !self.dynamic || self.must_boost(input) {
            self.holding_since_us = None;
            self.change_to(self.max, input.now_us);
            return self.step;
        }
        let Some((report, _)) = input.report else {
            return self.step;
        };
        let margin = i16::from(report.rssi_dbm) - input.rate.sensitivity_dbm();
        let settled = self.reports_since_change >= SETTLE_REPORTS;
        if margin < RAISE_BELOW_DB || report.lq_percent < RAISE_LQ {
            self.holding_since_us = None;
            // A margin short right after a step down is shorter still once the reports show
            // all of it: only a step up waits for the reports to settle.
            if (settled || !self.raised) && self.step < self.max {
                self.change_to(self.step + 1, input.now_us);
            }
        } else if margin >= LOWER_FROM_DB && report.lq_percent >= LOWER_LQ {
            let since = *self.holding_since_us.get_or_insert(input.now_us);
            let held = |t: u64| input.now_us.saturating_sub(t) >= LOWER_HOLD_US;
            if settled && held(since) && self.changed_us.is_none_or(held) && self.step > 0 {
                self.change_to(self.step - 1, input.now_us);
                self.holding_since_us = Some(input.now_us);
            }
        } else {
            self.holding_since_us = None;
        }
        self.step
    }

    /// Counts a report that arrived since the last update.
    fn count_report(&mut self, input: &PowerInput) {
        let arrived = input.report.map(|(_, at)| at);
        if arrived.is_some() && arrived != self.last_report_us {
            self.last_report_us = arrived;
            self.reports_since_change = self.reports_since_change.saturating_add(1);
        }
    }

    /// Not connected, no report for [`MISSED_REPORTS`] periods, or LQ below [`BOOST_LQ`].
    fn must_boost(&self, input: &PowerInput) -> bool {
        let Some((report, at_us)) = input.report.filter(|_| input.connected) else {
            return true;
        };
        let silent_us = u64::from(input.report_period_us) * u64::from(MISSED_REPORTS);
        input.now_us.saturating_sub(at_us) > silent_us || report.lq_percent < BOOST_LQ
    }

    fn change_to(&mut self, step: u8, now_us: u64) {
        let step = step.min(self.max);
        if step != self.step {
            self.raised = step > self.step;
            self.step = step;
            self.changed_us = Some(now_us);
            self.reports_since_change = 0;
        }
    }
}

#[cfg(test)]
#[path = "power_tests.rs"]
mod tests;
