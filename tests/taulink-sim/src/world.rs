//! Builds the simulated world for a [`Scenario`] — medium, both link ends (and optionally a
//! foreign link and a jammer) — runs it in virtual time and summarises what was measured.

use std::cell::RefCell;
use std::rc::Rc;

use telemetry::link::rate::airtime_us;
use telemetry::link::{HOP_CHANNELS, LinkParams, PacketRadio, RadioConfig};
use telemetry::mock::{
    ChannelModel, Executor, Medium, MediumStats, MockRadio, Node, SimClock, SplitMix64, VirtualTime,
};

use crate::ends::{FlightStart, ModuleBind, apps, flight_end, master_nonce_seed, module_end};
use crate::probe::{Now, Record, Shared, Snapshot};
use crate::report::{Report, summarise};
use crate::scenario::Scenario;

/// How long each end's bind mode lasts before giving up.
pub(crate) const BIND_TIMEOUT_US: u64 = 5_000_000;
/// Boot offsets of the two ends' clocks (they count from different epochs).
pub(crate) const MODULE_EPOCH_US: u64 = 1_234_567;
pub(crate) const FLIGHT_EPOCH_US: u64 = 987_654_321;
/// Status callback period, virtual.
pub(crate) const STATUS_PERIOD_US: u64 = 1_000_000;

/// One live status sample.
#[derive(Clone, Copy, Debug)]
pub struct Status {
    /// Virtual time, seconds.
    pub time_s: f64,
    /// Both ends' state.
    pub link: Snapshot,
    /// Uplink channel updates in the last period, per second.
    pub update_rate_hz: f64,
    /// Mean latency over the last period, µs.
    pub latency_us: f64,
    /// Uplink / downlink stream goodput in the last period, bytes per second.
    pub goodput_bps: (f64, f64),
}

/// The link-under-test's records, the foreign link's, and the medium's counters.
pub struct Outcome {
    /// Link under test.
    pub main: Record,
    /// The foreign link, if any.
    pub foreign: Option<Record>,
    /// Air counters.
    pub medium: MediumStats,
    /// Link parameters used.
    pub params: LinkParams,
}

pub(crate) fn params_for(s: &Scenario, random: u32) -> LinkParams {
    LinkParams::new(random, s.band, s.rate, s.format, s.telemetry_ratio)
}

/// Spawns a master and follower pair. With `bind`, both start in bind mode.
#[allow(clippy::too_many_arguments)]
fn spawn_pair<'a>(
    ex: &Executor<'a>,
    time: &VirtualTime,
    medium: &Medium,
    s: &Scenario,
    params: LinkParams,
    positions: (f64, f64),
    salt: u64,
    bind: bool,
) -> (Shared, usize, usize) {
    let record: Shared = Rc::new(RefCell::new(Record::default()));
    let node = |position_m| Node {
        position_m,
        check_header: s.header_check,
        chip_crc: s.chip_crc,
        ..Node::default()
    };
    let module_node = medium.add_node(node(positions.0));
    let flight_node = medium.add_node(node(positions.1));
    let module_radio = MockRadio::new(medium.clone(), module_node);
    let flight_radio = MockRadio::new(medium.clone(), flight_node);
    // The ends boot at different times and count from different epochs.
    let module_clock = SimClock::new(time.clone(), MODULE_EPOCH_US, 0.0);
    let flight_clock = SimClock::new(time.clone(), FLIGHT_EPOCH_US, 0.0);
    let t = time.clone();
    let now: Now = Rc::new(move || t.now_us());
    let (module_app, flight_app) = apps(s, now, &record, salt);
    ex.spawn(module_end(
        module_radio,
        module_clock,
        params,
        bind.then(|| ModuleBind::of(s, salt)),
        s.key.map(|k| (k, master_nonce_seed(s.seed, salt))),
        module_app,
    ));
    let start = FlightStart::of(s, bind, params, salt);
    // Both mock clocks count the shared virtual time from their own epoch.
    ex.spawn(flight_end(
        flight_radio,
        flight_clock,
        start,
        flight_app,
        record.clone(),
        |c: &SimClock| c.now_us() - FLIGHT_EPOCH_US,
    ));
    (record, module_node, flight_node)
}

/// A jammer: random bursts on random grid channels at `duty` of the time.
fn spawn_jammer(
    ex: &Executor<'_>,
    time: &VirtualTime,
    medium: &Medium,
    s: &Scenario,
    position_m: f64,
) {
    let node = medium.add_node(Node {
        position_m,
        ..Node::default()
    });
    let mut radio = MockRadio::new(medium.clone(), node);
    let mut rng = SplitMix64::new(s.seed ^ 0x1A33_E500);
    let (rate, band, duty) = (s.rate, s.band, s.interference.clamp(0.001, 0.95));
    let mut clock = SimClock::new(time.clone(), 0, 0.0);
    ex.spawn(async move {
        let _ = radio
            .configure(&RadioConfig {
                rate,
                header: *b"JAM!",
                base_hz: band.base_hz(),
                spacing_hz: band.spacing_hz(),
                reduced_power: false,
            })
            .await;
        let mut junk = [0u8; 32];
        loop {
            for b in junk.iter_mut() {
                *b = rng.next_u64() as u8;
            }
            let _ = radio
                .set_channel(rng.below(HOP_CHANNELS as u64) as u8)
                .await;
            let _ = radio.transmit(&junk).await;
            let on = f64::from(airtime_us(junk.len(), rate.bit_rate_bps()));
            let gap = (on * (1.0 - duty) / duty * 2.0 * rng.unit()) as u64;
            let next = clock.now_us() + gap;
            clock.sleep_until_us(next).await;
        }
    });
}

/// Turns cumulative records into per-period status samples.
#[derive(Default)]
pub(crate) struct StatusTracker {
    outputs: u64,
    up_bytes: u64,
    down_bytes: u64,
    latencies: usize,
}

impl StatusTracker {
    /// The status at `t_us`, `period_us` after the previous sample.
    pub(crate) fn sample(&mut self, t_us: u64, r: &Record, period_us: u64) -> Status {
        let period_s = (period_us as f64 / 1e6).max(1e-9);
        let lat = r.latencies_us.get(self.latencies..).unwrap_or(&[]);
        let latency_us = if lat.is_empty() {
            0.0
        } else {
            lat.iter().map(|&v| f64::from(v)).sum::<f64>() / lat.len() as f64
        };
        let st = Status {
            time_s: t_us as f64 / 1e6,
            link: r.now,
            update_rate_hz: (r.outputs_ok - self.outputs) as f64 / period_s,
            latency_us,
            goodput_bps: (
                (r.up_bytes_ok - self.up_bytes) as f64 / period_s,
                (r.down_bytes_ok - self.down_bytes) as f64 / period_s,
            ),
        };
        *self = Self {
            outputs: r.outputs_ok,
            up_bytes: r.up_bytes_ok,
            down_bytes: r.down_bytes_ok,
            latencies: r.latencies_us.len(),
        };
        st
    }
}

/// Runs `s` on the backend it names, calling `status` once per virtual second.
pub fn simulate(s: &Scenario, status: impl FnMut(&Status)) -> Outcome {
    if s.chip_level {
        crate::chip_world::simulate_chip(s, status)
    } else {
        simulate_packet(s, status)
    }
}

/// Runs `s` on the packet-level mock radios, calling `status` once per virtual second.
pub fn simulate_packet(s: &Scenario, mut status: impl FnMut(&Status)) -> Outcome {
    let time = VirtualTime::new();
    let model = ChannelModel {
        loss: s.loss,
        bit_error_rate: s.bit_error_rate,
        ..ChannelModel::default()
    };
    let medium = Medium::new(time.clone(), model, s.seed);
    let mut rng = SplitMix64::new(s.seed);
    let params = params_for(s, rng.next_u64() as u32);
    let ex = Executor::new(time.clone());
    let (main, module_node, flight_node) = spawn_pair(
        &ex,
        &time,
        &medium,
        s,
        params,
        (0.0, s.distance_m),
        0xA11CE,
        s.bind,
    );
    let foreign = s.foreign_link.then(|| {
        let foreign_params = params_for(s, rng.next_u64() as u32);
        let mid = s.distance_m / 2.0;
        spawn_pair(
            &ex,
            &time,
            &medium,
            s,
            foreign_params,
            (mid - 5.0, mid + 5.0),
            0xB0B,
            false,
        )
        .0
    });
    if s.interference > 0.0 {
        spawn_jammer(&ex, &time, &medium, s, s.distance_m / 2.0);
    }
    if let Some((from_s, to_s)) = s.cut_s {
        let (t, m) = (time.clone(), medium.clone());
        ex.spawn(async move {
            t.sleep_until((from_s * 1e6) as u64).await;
            m.set_cut(module_node, flight_node, true);
            t.sleep_until((to_s * 1e6) as u64).await;
            m.set_cut(module_node, flight_node, false);
        });
    }
    let end_us = (s.duration_s * 1e6) as u64;
    let mut tracker = StatusTracker::default();
    let mut t_us = 0;
    while t_us < end_us {
        let step = STATUS_PERIOD_US.min(end_us - t_us);
        t_us += step;
        ex.run_until_us(t_us);
        status(&tracker.sample(t_us, &main.borrow(), step));
    }
    drop(ex);
    let main = main.borrow().clone();
    let foreign = foreign.map(|f| f.borrow().clone());
    Outcome {
        main,
        foreign,
        medium: medium.stats(),
        params,
    }
}

/// Runs `s` and summarises it.
pub fn run(s: &Scenario, status: impl FnMut(&Status)) -> Report {
    let outcome = simulate(s, status);
    summarise(s, &outcome)
}
