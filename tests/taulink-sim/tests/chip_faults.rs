//! Both link ends on the real rfm22b driver over virtual Si4432s with SPI time, when the
//! hardware misbehaves: SPI bus errors on the flight side and a brown-out (power-on reset)
//! of the module's chip. The sessions ride through (the radio is re-configured, counted in
//! `Counters::radio_errors`), and failsafe comes only if the outage is longer than the
//! failsafe time.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Duration;

use radio_rfm22b::{Rfm22b, TxPower};
use si4432_sim::{RadioConfig as Placement, Simulation};
use taulink_sim::driver::{LinkRadio, SimClock};
use telemetry::channels::{ChannelFormat, FailsafeValues};
use telemetry::link::core::follower::SyncState;
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::{FollowerHooks, run_follower};
use telemetry::link::master::{MasterHooks, run_master};
use telemetry::link::{Band, LinkParams, RateMode};

#[derive(Default, Debug)]
struct Log {
    /// Times the follower entered failsafe (after its first lock).
    failsafes: Vec<u64>,
    locked: bool,
    tracking: bool,
    follower_errors: u32,
    master_errors: u32,
    follower_ended: bool,
    master_ended: bool,
}

struct Flight(Rc<RefCell<Log>>, bool);

impl FollowerHooks for Flight {
    fn on_step(&mut self, now_us: u64, f: &mut Follower) {
        let mut log = self.0.borrow_mut();
        if f.in_failsafe() && !self.1 && log.locked {
            log.failsafes.push(now_us);
        }
        self.1 = f.in_failsafe();
        log.locked |= !f.in_failsafe();
        log.tracking = f.sync_state() == SyncState::Tracking;
        log.follower_errors = f.counters().radio_errors;
    }
}

struct Module(Rc<RefCell<Log>>);

impl MasterHooks for Module {
    fn on_slot(&mut self, _now_us: u64, m: &mut Master) {
        self.0.borrow_mut().master_errors = m.counters().radio_errors;
    }
}

#[test]
fn spi_errors_and_a_brown_out_are_ridden_through_without_ending_the_session() {
    let sim = Simulation::new(3);
    let medium = sim.medium();
    let module = medium.add_radio(Placement::at([0.0, 0.0, 0.0]));
    let flight = medium.add_radio(Placement::at([200.0, 0.0, 0.0]));
    let (module_chip, flight_chip) = (module.chip.clone(), flight.chip.clone());
    let params = LinkParams::new(
        0x1234_5678,
        Band::Mhz433,
        RateMode::F250,
        ChannelFormat::Full16,
        4,
    );
    let log = Rc::new(RefCell::new(Log::default()));
    let mut clock = SimClock::new(medium.time(), 0, 0.0);
    let mut radio = LinkRadio::new(
        Rfm22b::new(module.spi, module.nirq, module.sdn, module.delay),
        TxPower::MAX,
    );
    let (l, mut hooks) = (log.clone(), Module(log.clone()));
    sim.spawn(async move {
        let mut master = Master::new(params);
        let _ = run_master(&mut radio, &mut clock, &mut master, &mut hooks).await;
        l.borrow_mut().master_ended = true;
    });
    let mut clock = SimClock::new(medium.time(), 0, 0.0);
    let mut radio = LinkRadio::new(
        Rfm22b::new(flight.spi, flight.nirq, flight.sdn, flight.delay),
        TxPower::MAX,
    );
    let (l, mut hooks) = (log.clone(), Flight(log.clone(), true));
    sim.spawn(async move {
        let mut follower = Follower::new(params, FailsafeValues::default(), 250_000);
        let _ = run_follower(&mut radio, &mut clock, &mut follower, &mut hooks).await;
        l.borrow_mut().follower_ended = true;
    });
    sim.run_for(Duration::from_secs(2));
    assert!(log.borrow().tracking, "{:?}", log.borrow());
    // Three failed SPI transactions on the flight side.
    flight_chip.fail_spi_transactions(3);
    sim.run_for(Duration::from_secs(1));
    // The module's chip browns out: registers lost, 15 ms power-on reset.
    module_chip.power_on_reset();
    sim.run_for(Duration::from_secs(2));
    let log = log.borrow();
    println!("{log:?}");
    assert!(!log.follower_ended && !log.master_ended, "{log:?}");
    assert!(log.follower_errors >= 1, "{log:?}");
    assert!(log.master_errors >= 1, "{log:?}");
    assert!(
        log.failsafes.is_empty(),
        "outages shorter than failsafe: {log:?}"
    );
    assert!(log.tracking, "{log:?}");
    assert_eq!(flight_chip.spi_stats().failed, 3);
}
