//! Radio errors inside a link session (a bus error, a chip that reset, a TX timeout) do not
//! end it: both loops re-configure the radio and carry on, failsafe comes only from the
//! silence as always, and only `MAX_CONSECUTIVE_RADIO_ERRORS` errors in a row give up.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

mod common;

use std::cell::{Cell, RefCell};
use std::rc::Rc;

use telemetry::channels::FailsafeValues;
use telemetry::link::core::follower::SyncState;
use telemetry::link::core::{Follower, MAX_CONSECUTIVE_RADIO_ERRORS, Master};
use telemetry::link::follower::{FollowerHooks, run_follower};
use telemetry::link::master::{MasterHooks, run_master};
use telemetry::link::{LinkRx, PacketRadio, RadioConfig, RateMode};
use telemetry::mock::{MockRadio, SimClock};

/// The error of [`Flaky`].
#[derive(Debug)]
struct BusError;

/// A mock radio whose next `fail` calls (of any kind) fail.
struct Flaky {
    inner: MockRadio,
    fail: Rc<Cell<u32>>,
}

impl Flaky {
    fn check(&self) -> Result<(), BusError> {
        match self.fail.get() {
            0 => Ok(()),
            n => {
                self.fail.set(n - 1);
                Err(BusError)
            }
        }
    }
}

impl PacketRadio for Flaky {
    type Error = BusError;

    async fn configure(&mut self, config: &RadioConfig) -> Result<(), BusError> {
        self.check()?;
        self.inner.configure(config).await.map_err(|e| match e {})
    }

    async fn set_channel(&mut self, channel: u8) -> Result<(), BusError> {
        self.check()?;
        self.inner
            .set_channel(channel)
            .await
            .map_err(|e| match e {})
    }

    async fn transmit(&mut self, frame: &[u8]) -> Result<(), BusError> {
        self.check()?;
        self.inner.transmit(frame).await.map_err(|e| match e {})
    }

    async fn begin_transmit(&mut self, len: usize) -> Result<(), BusError> {
        self.check()?;
        self.inner.begin_transmit(len).await.map_err(|e| match e {})
    }

    async fn finish_transmit(&mut self, frame: &[u8]) -> Result<(), BusError> {
        self.check()?;
        self.inner
            .finish_transmit(frame)
            .await
            .map_err(|e| match e {})
    }

    async fn receive(&mut self, buf: &mut [u8], timeout_us: u32) -> Result<LinkRx, BusError> {
        self.check()?;
        self.inner
            .receive(buf, timeout_us)
            .await
            .map_err(|e| match e {})
    }
}

#[derive(Default)]
struct Log {
    failsafe_at: Vec<u64>,
    tracking_at_end: bool,
    follower_errors: u32,
    master_errors: u32,
    follower_ended: bool,
    master_ended: bool,
}

struct FlightHooks(Rc<RefCell<Log>>, bool);

impl FollowerHooks for FlightHooks {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        let mut log = self.0.borrow_mut();
        if follower.in_failsafe() && !self.1 {
            log.failsafe_at.push(now_us);
        }
        self.1 = follower.in_failsafe();
        log.tracking_at_end = follower.sync_state() == SyncState::Tracking;
        log.follower_errors = follower.counters().radio_errors;
    }
}

struct ModuleHooks(Rc<RefCell<Log>>);

impl MasterHooks for ModuleHooks {
    fn on_slot(&mut self, _now_us: u64, master: &mut Master) {
        self.0.borrow_mut().master_errors = master.counters().radio_errors;
    }
}

/// Both ends at `rate`; at 2 s the follower's radio fails `follower_fails` calls in a row, at
/// 4 s the master's `master_fails`; runs to 6 s.
fn run(rate: RateMode, follower_fails: u32, master_fails: u32) -> Log {
    let world = common::pair(rate, 5);
    let (time, medium, params) = (world.time.clone(), world.medium.clone(), world.params);
    let (module_node, flight_node) = (world.module_node, world.flight_node);
    let log = Rc::new(RefCell::new(Log::default()));
    let (master_fail, follower_fail) = (Rc::new(Cell::new(0)), Rc::new(Cell::new(0)));
    let mut radio = Flaky {
        inner: MockRadio::new(medium.clone(), module_node),
        fail: master_fail.clone(),
    };
    let mut clock = SimClock::new(time.clone(), 0, 0.0);
    let (module_log, mut hooks) = (log.clone(), ModuleHooks(log.clone()));
    world.executor.spawn(async move {
        let mut master = Master::new(params);
        let _ = run_master(&mut radio, &mut clock, &mut master, &mut hooks).await;
        module_log.borrow_mut().master_ended = true;
    });
    let mut radio = Flaky {
        inner: MockRadio::new(medium.clone(), flight_node),
        fail: follower_fail.clone(),
    };
    let mut clock = SimClock::new(time.clone(), 0, 0.0);
    let (flight_log, mut hooks) = (log.clone(), FlightHooks(log.clone(), true));
    world.executor.spawn(async move {
        let mut follower = Follower::new(params, FailsafeValues::default(), 250_000);
        let _ = run_follower(&mut radio, &mut clock, &mut follower, &mut hooks).await;
        flight_log.borrow_mut().follower_ended = true;
    });
    world.executor.run_until_us(2_000_000);
    follower_fail.set(follower_fails);
    world.executor.run_until_us(4_000_000);
    master_fail.set(master_fails);
    world.executor.run_until_us(6_000_000);
    drop(world);
    Rc::try_unwrap(log).ok().unwrap().into_inner()
}

#[test]
fn a_few_radio_errors_on_either_end_do_not_end_the_session_or_cause_failsafe() {
    let fails = MAX_CONSECUTIVE_RADIO_ERRORS - 3;
    for rate in RateMode::ALL {
        let log = run(rate, fails, fails);
        assert!(
            !log.follower_ended && !log.master_ended,
            "{rate:?}: session ended"
        );
        assert_eq!(
            (log.follower_errors, log.master_errors),
            (fails, fails),
            "{rate:?}"
        );
        // No failsafe after the first lock: the outages (a few retries of RADIO_RETRY_US)
        // are shorter than the failsafe time.
        assert!(
            log.failsafe_at.is_empty(),
            "{rate:?}: {:?}",
            log.failsafe_at
        );
        assert!(log.tracking_at_end, "{rate:?}");
    }
}

#[test]
fn a_radio_that_keeps_failing_ends_the_session_after_the_bound() {
    let log = run(RateMode::F250, u32::MAX, 0);
    assert!(log.follower_ended);
    assert!(!log.master_ended);
}
