//! The link loops hand control back to their application often: the flight firmware checks
//! in with its 250 ms watchdog from `FollowerHooks::on_step`, so no link state — acquiring,
//! tracking, failsafe after a cut, re-acquiring — may go longer than one bounded listen
//! window ([`MAX_LISTEN_US`]) without a hook call, at any rate mode.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

mod common;

use std::cell::RefCell;
use std::rc::Rc;

use telemetry::channels::FailsafeValues;
use telemetry::link::RateMode;
use telemetry::link::core::follower::SyncState;
use telemetry::link::core::{Follower, MAX_LISTEN_US, Master};
use telemetry::link::follower::{FollowerHooks, run_follower};
use telemetry::link::master::{MasterHooks, run_master};
use telemetry::mock::{MockRadio, SimClock};

/// Largest gap allowed between two hook calls: one listen window plus slack for the radio's
/// turnaround and a packet completed past the window's end.
const MAX_GAP_US: u64 = 60_000;

#[derive(Default)]
struct Log {
    /// (time, tracking, failsafe) at every follower step.
    follower: Vec<(u64, bool, bool)>,
    /// Time of every master slot hook.
    master: Vec<u64>,
}

struct FlightHooks(Rc<RefCell<Log>>);

impl FollowerHooks for FlightHooks {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        self.0.borrow_mut().follower.push((
            now_us,
            follower.sync_state() == SyncState::Tracking,
            follower.in_failsafe(),
        ));
    }
}

struct ModuleHooks(Rc<RefCell<Log>>);

impl MasterHooks for ModuleHooks {
    fn on_slot(&mut self, now_us: u64, _master: &mut Master) {
        self.0.borrow_mut().master.push(now_us);
    }
}

fn max_gap(times: impl Iterator<Item = u64>) -> u64 {
    let times: Vec<u64> = times.collect();
    times.windows(2).map(|w| w[1] - w[0]).max().unwrap_or(0)
}

const FOLLOWER_BOOT_US: u64 = 123_457;
const CUT_US: u64 = 2_000_000;
const RESTORE_US: u64 = 4_000_000;
const END_US: u64 = 7_000_000;

fn run(rate: RateMode) -> Log {
    let world = common::pair(rate, 11);
    let (time, medium, params) = (world.time.clone(), world.medium.clone(), world.params);
    let (module_node, flight_node) = (world.module_node, world.flight_node);
    let log = Rc::new(RefCell::new(Log::default()));
    let mut hooks = ModuleHooks(log.clone());
    let mut radio = MockRadio::new(medium.clone(), module_node);
    let mut clock = SimClock::new(time.clone(), 0, 0.0);
    world.executor.spawn(async move {
        let mut master = Master::new(params);
        let _ = run_master(&mut radio, &mut clock, &mut master, &mut hooks).await;
    });
    let mut hooks = FlightHooks(log.clone());
    let mut radio = MockRadio::new(medium.clone(), flight_node);
    let mut clock = SimClock::new(time.clone(), 0, 0.0);
    let boot = time.clone();
    world.executor.spawn(async move {
        boot.sleep_until(FOLLOWER_BOOT_US).await;
        let mut follower = Follower::new(params, FailsafeValues::default(), 250_000);
        let _ = run_follower(&mut radio, &mut clock, &mut follower, &mut hooks).await;
    });
    world.executor.run_until_us(CUT_US);
    medium.set_cut(module_node, flight_node, true);
    world.executor.run_until_us(RESTORE_US);
    medium.set_cut(module_node, flight_node, false);
    world.executor.run_until_us(END_US);
    drop(world);
    Rc::try_unwrap(log).ok().unwrap().into_inner()
}

#[test]
fn hooks_run_at_least_every_listen_window_in_every_state_and_rate() {
    const { assert!(MAX_LISTEN_US < MAX_GAP_US) };
    let mut too_long = Vec::new();
    for rate in RateMode::ALL {
        let log = run(rate);
        let f = &log.follower;
        let tracked_at = |from: u64| f.iter().find(|s| s.0 >= from && s.1).map(|s| s.0);
        // Every phase happened: acquisition, tracking, failsafe in the cut, re-acquisition.
        let first_lock = tracked_at(0).unwrap_or_else(|| panic!("{rate:?}: never locked"));
        assert!(first_lock < CUT_US, "{rate:?}");
        assert!(
            f.iter()
                .any(|s| s.0 > CUT_US && s.0 < RESTORE_US && !s.1 && s.2),
            "{rate:?}: no acquiring failsafe during the cut"
        );
        let relock = tracked_at(RESTORE_US).unwrap_or_else(|| panic!("{rate:?}: no relock"));
        let follower_gap = max_gap(f.iter().map(|s| s.0));
        let master_gap = max_gap(log.master.iter().copied());
        println!(
            "{rate:?}: lock after {:.0} ms, relock after {:.0} ms, max gap follower {:.1} ms, master {:.1} ms",
            (first_lock - FOLLOWER_BOOT_US) as f64 / 1e3,
            (relock - RESTORE_US) as f64 / 1e3,
            follower_gap as f64 / 1e3,
            master_gap as f64 / 1e3
        );
        assert!(f.first().is_some_and(|s| s.0 <= FOLLOWER_BOOT_US + 1_000));
        assert!(f.last().is_some_and(|s| s.0 >= END_US - MAX_GAP_US));
        if follower_gap.max(master_gap) > MAX_GAP_US {
            too_long.push((rate, follower_gap, master_gap));
        }
    }
    assert!(
        too_long.is_empty(),
        "(rate, follower, master) gaps µs: {too_long:?}"
    );
}
