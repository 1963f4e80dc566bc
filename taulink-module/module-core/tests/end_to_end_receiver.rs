//! Issue 6 acceptance, receiver role: the module as the link's follower (the real
//! `telemetry::link` follower over the mock radio) outputs on PPM the channels a master
//! sends, and on failsafe (link cut) holds the last values or stops the pulses, as set.

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

use std::cell::RefCell;
use std::rc::Rc;

use module_core::air::{AirLink, link_params};
use module_core::app::App;
use module_core::channels::us_to_ticks;
use module_core::handset::Handset;
use module_core::ppm::FailsafeOutput;
use module_core::session::LinkStep;
use module_core::settings::{RateMode, Role, Settings};
use telemetry::channels::{CHANNEL_CENTER, Failsafe, FailsafeValues, MAX_CHANNELS};
use telemetry::link::core::follower::DEFAULT_FAILSAFE_US;
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::{FollowerHooks, run_follower};
use telemetry::link::master::{MasterHooks, run_master};
use telemetry::mock::{ChannelModel, Executor, Medium, MockRadio, Node, SimClock, VirtualTime};

/// What the transmitter sends on channels 1…8, µs.
const WIDTHS_US: [u16; 8] = [1000, 1500, 2000, 1234, 1777, 1100, 1900, 1450];
/// The link is cut at this virtual time.
const CUT_US: u64 = 2_000_000;
/// Virtual run time.
const RUN_US: u64 = 3_000_000;

type ReceiverApp = App<AirLink, Handset>;

struct Transmitter;

impl MasterHooks for Transmitter {
    fn on_slot(&mut self, _now_us: u64, master: &mut Master) {
        let mut channels = [CHANNEL_CENTER; MAX_CHANNELS];
        for (slot, width) in channels.iter_mut().zip(WIDTHS_US) {
            *slot = us_to_ticks(width);
        }
        master.set_channels(&channels);
    }
}

struct Receiver {
    app: Rc<RefCell<ReceiverApp>>,
}

impl FollowerHooks for Receiver {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        let now_ms = (now_us / 1_000) as u32;
        self.app
            .borrow_mut()
            .on_follower_step(now_us, now_ms, follower);
    }
}

/// Runs the world; returns every PPM frame boundary: (virtual µs, channel periods or
/// `None` for no pulses).
fn run(failsafe: FailsafeOutput) -> Vec<(u64, Option<Vec<u16>>)> {
    let settings = Settings {
        role: Role::Receiver,
        rate: RateMode::M100,
        failsafe,
        bind_id: 0x0BAD_CAFE,
        // The PPM output is what this test is about: the unauthenticated link (the explicit
        // setting) keeps the master unkeyed.
        plain: true,
        ..Settings::default()
    };
    let params = link_params(&settings).unwrap();
    let time = VirtualTime::new();
    let medium = Medium::new(time.clone(), ChannelModel::default(), 11);
    let tx_node = medium.add_node(Node::default());
    let rx_node = medium.add_node(Node {
        position_m: 300.0,
        ..Node::default()
    });
    let app = Rc::new(RefCell::new(
        App::new(settings, AirLink::new(), Handset::new(&settings), false).unwrap(),
    ));
    // As the firmware's link task: probe, then the follower the core asks for.
    app.borrow_mut().on_radio_present(true);
    let step = app.borrow_mut().next_link_step(0, 0);
    let LinkStep::RunFollower {
        params: follower_params,
        failsafe,
        failsafe_us,
    } = step
    else {
        panic!("a bound receiver follows: {step:?}");
    };
    assert_eq!(follower_params, params);
    // The module holds every channel; its PPM output applies its own failsafe setting.
    assert_eq!(failsafe, FailsafeValues([Failsafe::Hold; MAX_CHANNELS]));
    assert_eq!(failsafe_us, DEFAULT_FAILSAFE_US);
    let executor = Executor::new(time.clone());
    let mut radio = MockRadio::new(medium.clone(), tx_node);
    let mut clock = SimClock::new(time.clone(), 55_555, 0.0);
    executor.spawn(async move {
        let mut master = Master::new(params);
        let _ = run_master(&mut radio, &mut clock, &mut master, &mut Transmitter).await;
    });
    let mut radio = MockRadio::new(medium.clone(), rx_node);
    let mut clock = SimClock::new(time.clone(), 7_777_777, 0.0);
    let mut hooks = Receiver { app: app.clone() };
    executor.spawn(async move {
        let mut follower = Follower::new(params, failsafe, failsafe_us);
        let _ = run_follower(&mut radio, &mut clock, &mut follower, &mut hooks).await;
    });
    let (tick_app, tick_time) = (app.clone(), time.clone());
    executor.spawn(async move {
        let mut t = 0;
        loop {
            t += 100_000;
            tick_time.sleep_until(t).await;
            tick_app.borrow_mut().on_tick();
        }
    });
    let frames = Rc::new(RefCell::new(Vec::new()));
    let (ppm_app, ppm_time, log) = (app.clone(), time.clone(), frames.clone());
    executor.spawn(async move {
        // The PWM task asks at every frame boundary; 22.5 ms while pulses run.
        let mut t = 0;
        loop {
            t += 22_500;
            ppm_time.sleep_until(t).await;
            let frame = ppm_app.borrow_mut().next_ppm_frame();
            let periods = frame.map(|f| f.slots().iter().map(|s| s.period_us).collect());
            log.borrow_mut().push((t, periods));
        }
    });
    let cut_time = time.clone();
    executor.spawn(async move {
        cut_time.sleep_until(CUT_US).await;
        medium.set_cut(tx_node, rx_node, true);
    });
    executor.run_until_us(RUN_US);
    frames.take()
}

fn check_channels(periods: &[u16]) {
    for (channel, (&period, &width)) in periods.iter().zip(&WIDTHS_US).enumerate() {
        assert!(
            period.abs_diff(width) <= 1,
            "channel {channel}: sent {width} µs, PPM period {period} µs"
        );
    }
}

#[test]
fn receiver_outputs_the_channels_and_holds_them_on_failsafe() {
    let frames = run(FailsafeOutput::HoldLast);
    // Pulses within 0.5 s of boot.
    let first = frames.iter().position(|(_, f)| f.is_some()).unwrap();
    assert!(
        frames[first].0 < 500_000,
        "first PPM frame at {} µs",
        frames[first].0
    );
    for (_, periods) in &frames[first..] {
        let periods = periods.as_ref().expect("pulses never stop with HoldLast");
        assert_eq!(periods.len(), 10, "8 channels, sync, pulse-free tail");
        check_channels(periods);
        // 22.5 ms frame: the sync gap (sync slot + tail) fills it up, never under 4.5 ms.
        assert_eq!(periods.iter().map(|&p| u32::from(p)).sum::<u32>(), 22_500);
        assert!(u32::from(periods[8]) + u32::from(periods[9]) >= 4_500);
    }
}

#[test]
fn receiver_stops_the_pulses_on_failsafe_when_set() {
    let frames = run(FailsafeOutput::StopPulses);
    let before: Vec<_> = frames
        .iter()
        .filter(|(t, _)| *t > 500_000 && *t < CUT_US)
        .collect();
    assert!(before.len() > 60);
    for (_, periods) in &before {
        check_channels(periods.as_ref().unwrap());
    }
    // Failsafe: 250 ms of silence, then at most one 100 ms tick and one frame.
    let stopped_from = CUT_US + DEFAULT_FAILSAFE_US + 100_000 + 22_500;
    let after: Vec<_> = frames.iter().filter(|(t, _)| *t > stopped_from).collect();
    assert!(after.len() > 20);
    assert!(
        after.iter().all(|(_, f)| f.is_none()),
        "pulses after failsafe"
    );
}
