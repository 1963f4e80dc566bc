//! `--dynamic-power --walk`: the flight side walks away from the module, from near to
//! beyond the range at the fixed maximum power, while both ends run their real link
//! applications — the module core (`module_core::app::App` with its `AirLink`, the master's
//! hook) and the flight application (`flight_app::app::FlightApp`, the follower's hook) —
//! on the radio driver over virtual Si4432s. Run once at the fixed maximum (+20 dBm, dynamic
//! power off on both ends) and once with dynamic power (`telemetry::link::power`), same seed.
//!
//! The distance grows geometrically (free-space path loss then rises at a constant rate in
//! dB, so each dB of margin gets the same time); it is split into equal time bins. Per bin,
//! from the air trace: each end's mean transmit power over the frames it sent (the power the
//! chip radiated: the register the link loop wrote), and the LQ of each direction — uplinks
//! delivered of those sent (the master sends every uplink slot), downlinks delivered of the
//! downlink slots in the bin (a follower that lost the grid sends none).

use std::fmt::Write as _;
use std::time::Duration;

use flight_app::app::FlightApp;
use flight_app::settings::{Settings as FlightSettings, handles};
use module_core::air::{AirLink, link_params};
use module_core::app::App;
use module_core::handset::Handset;
use module_core::settings::{Band, Role, Settings as ModuleSettings};
use radio_rfm22b::{Rfm22b, TxPower};
use serde::Serialize;
use si4432_sim::{Outcome as ChipOutcome, RadioConfig as ChipPlacement, RadioId, Simulation};
use telemetry::channels::FailsafeValues;
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::run_follower;
use telemetry::link::master::{MasterHooks, run_master};
use telemetry::link::{LinkParams, RateMode};

use crate::driver::{LinkRadio, SimClock};

/// Time bins of a walk on the command line.
pub const WALK_BINS: usize = 10;
/// The bind ID of the walk's link.
const BIND_ID: u32 = 0x3A1C_0935;
/// How often the flight side's position is moved.
const MOVE_PERIOD: Duration = Duration::from_millis(100);
/// The flight side's failsafe delay (the flight firmware's).
const FAILSAFE_US: u64 = 500_000;

/// A walk: rate mode, telemetry ratio, distances, duration and bins.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct WalkPlan {
    /// The link's rate mode.
    #[serde(serialize_with = "rate_name")]
    pub rate: RateMode,
    /// One downlink slot in this many.
    pub ratio: u8,
    /// Distance at the start, metres.
    pub from_m: f64,
    /// Distance at the end, metres.
    pub to_m: f64,
    /// Virtual duration, seconds.
    pub duration_s: f64,
    /// Time bins reported.
    pub bins: usize,
    /// Seed of the simulation's random draws.
    pub seed: u64,
}

fn rate_name<S: serde::Serializer>(rate: &RateMode, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(rate.name())
}

impl WalkPlan {
    /// The walk the README quotes (`taulink-sim --dynamic-power --walk`, every option at its
    /// default): F250 at 1:4, 2 km → 200 km over 30 s, seed 1.
    pub const DOCUMENTED: Self = Self {
        rate: RateMode::F250,
        ratio: 4,
        from_m: 2_000.0,
        to_m: 200_000.0,
        duration_s: 30.0,
        bins: WALK_BINS,
        seed: 1,
    };

    /// The distance at `t_s` into the walk (geometric from `from_m` to `to_m`).
    pub fn distance_m(&self, t_s: f64) -> f64 {
        let f = (t_s / self.duration_s).clamp(0.0, 1.0);
        self.from_m * (self.to_m / self.from_m).powf(f)
    }
}

/// What one time bin of a walk measured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct WalkBin {
    /// Distance at the bin's middle, metres.
    pub distance_m: f64,
    /// The module's mean transmit power over its frames, mW.
    pub module_mw: f64,
    /// The flight side's mean transmit power over its frames, mW (0: it sent none).
    pub flight_mw: f64,
    /// Uplinks delivered of those sent, %.
    pub uplink_lq: f64,
    /// Downlinks delivered of the bin's downlink slots, %.
    pub downlink_lq: f64,
    /// Frames the module sent.
    pub module_frames: u64,
    /// Frames the flight side sent.
    pub flight_frames: u64,
}

/// One walk's bins.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WalkRun {
    /// Dynamic power on at both ends.
    pub dynamic: bool,
    /// The bins, nearest first.
    pub bins: Vec<WalkBin>,
}

impl WalkRun {
    /// Each end's mean transmit power over all the frames it sent in the walk: (module,
    /// flight) mW.
    pub fn mean_mw(&self) -> (f64, f64) {
        let mean = |mw: fn(&WalkBin) -> f64, frames: fn(&WalkBin) -> u64| {
            let n: u64 = self.bins.iter().map(frames).sum();
            let energy: f64 = self.bins.iter().map(|b| mw(b) * frames(b) as f64).sum();
            if n == 0 { 0.0 } else { energy / n as f64 }
        };
        (
            mean(|b| b.module_mw, |b| b.module_frames),
            mean(|b| b.flight_mw, |b| b.flight_frames),
        )
    }
}

/// Both walks and the criteria.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WalkReport {
    /// What was walked.
    pub plan: WalkPlan,
    /// At the fixed maximum.
    pub fixed: WalkRun,
    /// With dynamic power.
    pub dynamic: WalkRun,
}

/// LQ a bin must keep where the fixed maximum kept it, %.
pub const KEPT_LQ: f64 = 95.0;

impl WalkReport {
    /// Walks `plan` at the fixed maximum and with dynamic power.
    pub fn run(plan: &WalkPlan) -> Self {
        Self {
            plan: *plan,
            fixed: walk(plan, false),
            dynamic: walk(plan, true),
        }
    }

    /// The bins (index, direction) where the fixed maximum had ≥ [`KEPT_LQ`] and dynamic
    /// power did not: empty when the criterion holds.
    pub fn lq_lost(&self) -> Vec<(usize, &'static str)> {
        let mut lost = Vec::new();
        for (i, (f, d)) in self.fixed.bins.iter().zip(&self.dynamic.bins).enumerate() {
            if f.uplink_lq >= KEPT_LQ && d.uplink_lq < KEPT_LQ {
                lost.push((i, "uplink"));
            }
            if f.downlink_lq >= KEPT_LQ && d.downlink_lq < KEPT_LQ {
                lost.push((i, "downlink"));
            }
        }
        lost
    }

    /// The power saved by each end over the walk, % of the fixed maximum's mean.
    pub fn saved_percent(&self) -> (f64, f64) {
        let (fm, ff) = self.fixed.mean_mw();
        let (dm, df) = self.dynamic.mean_mw();
        let saved =
            |fixed: f64, dynamic: f64| 100.0 * (1.0 - dynamic / fixed.max(f64::MIN_POSITIVE));
        (saved(fm, dm), saved(ff, df))
    }

    /// The report as a Markdown table and the criteria's lines.
    pub fn table(&self) -> String {
        let p = &self.plan;
        let mut out = format!(
            "{} at 1:{}, {:.0} m → {:.0} m over {:.0} s (free space, 433 MHz), seed {}\n\n",
            p.rate.name(),
            p.ratio,
            p.from_m,
            p.to_m,
            p.duration_s,
            p.seed
        );
        out.push_str("| distance | module mW fixed / dyn | flight mW fixed / dyn | uplink LQ fixed / dyn | downlink LQ fixed / dyn |\n");
        out.push_str("|---:|---:|---:|---:|---:|\n");
        for (f, d) in self.fixed.bins.iter().zip(&self.dynamic.bins) {
            let _ = writeln!(
                out,
                "| {:.1} km | {:.0} / {:.1} | {:.0} / {:.1} | {:.1} / {:.1} % | {:.1} / {:.1} % |",
                f.distance_m / 1_000.0,
                f.module_mw,
                d.module_mw,
                f.flight_mw,
                d.flight_mw,
                f.uplink_lq,
                d.uplink_lq,
                f.downlink_lq,
                d.downlink_lq
            );
        }
        let ((fm, ff), (dm, df)) = (self.fixed.mean_mw(), self.dynamic.mean_mw());
        let (sm, sf) = self.saved_percent();
        let _ = writeln!(
            out,
            "\nmean power over the frames sent: module {fm:.1} → {dm:.1} mW ({sm:.1} % saved), flight {ff:.1} → {df:.1} mW ({sf:.1} % saved)"
        );
        let lost = self.lq_lost();
        let _ = writeln!(
            out,
            "LQ ≥ {KEPT_LQ:.0} % wherever the fixed maximum had it: {}",
            if lost.is_empty() {
                "yes".to_string()
            } else {
                format!("no, bins {lost:?}")
            }
        );
        out
    }
}

/// The module core as the master's hook (as the firmware's link task calls it).
struct ModuleHooks(App<AirLink, Handset>);

impl MasterHooks for ModuleHooks {
    fn on_slot(&mut self, now_us: u64, master: &mut Master) {
        let now_ms = u32::try_from((now_us / 1_000) % (1 << 32)).unwrap_or(0);
        self.0.on_master_slot(now_us, now_ms, master);
    }
}

/// The module's settings for the walk: bound, unauthenticated (the key changes nothing on
/// the air's power), +20 dBm at most.
fn module_settings(plan: &WalkPlan, dynamic: bool) -> ModuleSettings {
    ModuleSettings {
        role: Role::Transmitter,
        rate: plan.rate,
        band: Band::Mhz433,
        tx_power: TxPower::MAX.step(),
        bind_id: BIND_ID,
        telemetry_ratio: plan.ratio,
        plain: true,
        dynamic_power: dynamic,
        ..ModuleSettings::default()
    }
}

/// The flight application with `link.dynamic_power` as given.
fn flight_app(dynamic: bool) -> Option<FlightApp> {
    let mut settings = FlightSettings::default();
    settings
        .apply(&[handles::LINK_DYNAMIC_POWER.to(u32::from(dynamic))])
        .ok()?;
    FlightApp::new(settings, 0)
}

/// One walk of `plan`, dynamic power on or off at both ends.
pub fn walk(plan: &WalkPlan, dynamic: bool) -> WalkRun {
    let sim = Simulation::new(plan.seed);
    let medium = sim.medium();
    let module = medium.add_radio(ChipPlacement::at([0.0, 0.0, 0.0]));
    let flight = medium.add_radio(ChipPlacement::at([plan.from_m, 0.0, 0.0]));
    let ids = (module.id, flight.id);
    let settings = module_settings(plan, dynamic);
    let (Some(params), Some(app), Some(flight_app)) = (
        link_params(&settings),
        App::new(settings, AirLink::new(), Handset::new(&settings), false).ok(),
        flight_app(dynamic),
    ) else {
        return WalkRun {
            dynamic,
            bins: Vec::new(),
        };
    };
    let radio = |r: si4432_sim::RadioHandle| {
        LinkRadio::new(Rfm22b::new(r.spi, r.nirq, r.sdn, r.delay), TxPower::MAX)
    };
    let (mut module_radio, mut flight_radio) = (radio(module), radio(flight));
    let mut master = app.master(params);
    let mut hooks = ModuleHooks(app);
    let mut clock = SimClock::new(medium.time(), 1_000_000, 8.0);
    sim.spawn(async move {
        let _ = run_master(&mut module_radio, &mut clock, &mut master, &mut hooks).await;
    });
    let mut flight_clock = SimClock::new(medium.time(), 7_000_000, -6.0);
    let mut flight_app = flight_app;
    sim.spawn(async move {
        let mut follower = Follower::new(params, FailsafeValues::default(), FAILSAFE_US);
        let _ = run_follower(
            &mut flight_radio,
            &mut flight_clock,
            &mut follower,
            &mut flight_app,
        )
        .await;
    });
    let bin_s = plan.duration_s / plan.bins.max(1) as f64;
    let mut bins = Vec::with_capacity(plan.bins);
    let mut t_s = 0.0;
    for i in 0..plan.bins {
        let end_s = (i + 1) as f64 * bin_s;
        while t_s < end_s {
            medium.set_position(ids.1, [plan.distance_m(t_s), 0.0, 0.0]);
            sim.run_for(MOVE_PERIOD);
            t_s += MOVE_PERIOD.as_secs_f64();
        }
        let mid_m = plan.distance_m((i as f64 + 0.5) * bin_s);
        bins.push(measure(&medium, ids, &params, bin_s, mid_m));
        medium.clear_trace();
    }
    WalkRun { dynamic, bins }
}

/// A bin's figures from the air trace since it was last cleared.
fn measure(
    medium: &si4432_sim::Medium,
    (module, flight): (RadioId, RadioId),
    params: &LinkParams,
    bin_s: f64,
    distance_m: f64,
) -> WalkBin {
    let (mut up, mut down) = (Tally::default(), Tally::default());
    medium.with_trace(|frames| {
        for f in frames {
            let (tally, to) = match f.radio {
                r if r == module => (&mut up, flight),
                r if r == flight => (&mut down, module),
                _ => continue,
            };
            tally.sent += 1;
            tally.mw += 10f64.powf(f.tx_power_dbm / 10.0);
            if matches!(f.outcome_at(to), Some(ChipOutcome::Delivered { .. })) {
                tally.delivered += 1;
            }
        }
    });
    let slots = bin_s * 1e6 / f64::from(params.rate.slot_us());
    let downlink_slots = slots / f64::from(params.telemetry_ratio.max(1));
    WalkBin {
        distance_m,
        module_mw: up.mean_mw(),
        flight_mw: down.mean_mw(),
        uplink_lq: percent(up.delivered as f64, up.sent as f64),
        downlink_lq: percent(down.delivered as f64, downlink_slots).min(100.0),
        module_frames: up.sent,
        flight_frames: down.sent,
    }
}

fn percent(part: f64, whole: f64) -> f64 {
    if whole > 0.0 {
        100.0 * part / whole
    } else {
        0.0
    }
}

/// One direction's frames in a bin.
#[derive(Default)]
struct Tally {
    sent: u64,
    delivered: u64,
    mw: f64,
}

impl Tally {
    fn mean_mw(&self) -> f64 {
        if self.sent == 0 {
            0.0
        } else {
            self.mw / self.sent as f64
        }
    }
}
