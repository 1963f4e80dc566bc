//! A forger on air, chip level: both ends authenticate their frames with one link key
//! (`Master::with_key`, `Follower::with_key`); a third radio in the medium knows the link's
//! header and hop sequence (public: heard on air) but not the key, and transmits uplinks with
//! full throttle and the save-failsafe flag on every hop channel in turn, sealed under a
//! guessed key and as version 1 frames with the (public) bind ID's CRC. None is accepted:
//! the follower's output never shows the forged throttle and its failsafe values stay.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Duration;

use radio_rfm22b::{Rfm22b, TxPower};
use si4432_sim::{RadioConfig as Placement, Simulation};
use taulink_sim::driver::{LinkRadio, SimClock};
use telemetry::channels::{ChannelFormat, Channels, FailsafeValues, pack};
use telemetry::frame::{Frame, StreamHeader, Uplink, encode, seal};
use telemetry::link::auth::TagContext;
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::{FollowerHooks, run_follower};
use telemetry::link::master::{MasterHooks, run_master};
use telemetry::link::{
    Band, HOP_CHANNELS, HopSequence, LinkKey, LinkParams, PacketRadio, RateMode,
};

const FORGED_THROTTLE: u16 = 1811;

#[derive(Default, Debug)]
struct Log {
    forged_seen: bool,
    failsafe_changed: bool,
    updates: u32,
    rejected: u32,
    lq: u8,
    attacker_sent: u32,
}

struct Flight(Rc<RefCell<Log>>, FailsafeValues);

impl FollowerHooks for Flight {
    fn on_step(&mut self, _now_us: u64, f: &mut Follower) {
        let mut log = self.0.borrow_mut();
        log.forged_seen |= f.output()[2] == FORGED_THROTTLE;
        log.failsafe_changed |= *f.failsafe_values() != self.1;
        log.updates = f.updates();
        log.rejected = f.counters().rejected;
        log.lq = f.uplink_lq();
    }
}

struct Module;

impl MasterHooks for Module {
    fn on_slot(&mut self, _now_us: u64, m: &mut Master) {
        m.set_channels(&[992; 16]);
    }
}

#[test]
fn forged_uplinks_from_a_third_radio_are_never_accepted() {
    let sim = Simulation::new(11);
    let medium = sim.medium();
    let module = medium.add_radio(Placement::at([0.0, 0.0, 0.0]));
    let flight = medium.add_radio(Placement::at([200.0, 0.0, 0.0]));
    // Closer to the flight side than the module is: it wins every collision it causes.
    let attacker = medium.add_radio(Placement::at([150.0, 0.0, 0.0]));
    let params = LinkParams::new(
        0x1234_5678,
        Band::Mhz433,
        RateMode::F250,
        ChannelFormat::Full16,
        4,
    );
    let key = LinkKey::from_bytes(*b"sixteen byte key");
    let log = Rc::new(RefCell::new(Log::default()));

    let mut clock = SimClock::new(medium.time(), 0, 0.0);
    let mut radio = LinkRadio::new(
        Rfm22b::new(module.spi, module.nirq, module.sdn, module.delay),
        TxPower::MAX,
    );
    sim.spawn(async move {
        let mut master = Master::new(params).with_key(key);
        let _ = run_master(&mut radio, &mut clock, &mut master, &mut Module).await;
    });
    let mut clock = SimClock::new(medium.time(), 0, 0.0);
    let mut radio = LinkRadio::new(
        Rfm22b::new(flight.spi, flight.nirq, flight.sdn, flight.delay),
        TxPower::MAX,
    );
    let failsafe = FailsafeValues::default();
    let mut hooks = Flight(log.clone(), failsafe);
    sim.spawn(async move {
        let mut follower = Follower::new(params, failsafe, 250_000).with_key(key);
        let _ = run_follower(&mut radio, &mut clock, &mut follower, &mut hooks).await;
    });

    // The attacker: the victim's public identity and hop order, a guessed key.
    let victim = Master::new(params).with_key(key);
    let config = victim.radio_config();
    let bind_id = victim.params().bind_id;
    let hops = HopSequence::new(bind_id);
    let mut clock = SimClock::new(medium.time(), 0, 0.0);
    let mut radio = LinkRadio::new(
        Rfm22b::new(attacker.spi, attacker.nirq, attacker.sdn, attacker.delay),
        TxPower::MAX,
    );
    let l = log.clone();
    sim.spawn(async move {
        radio.configure(&config).await.unwrap();
        let mut evil: Channels = [992; 16];
        evil[2] = FORGED_THROTTLE;
        let mut packed = [0u8; 22];
        pack(&evil, ChannelFormat::Full16, &mut packed);
        let guess = LinkKey::from_bytes(*b"a guessed keyXYZ");
        for n in 0u32.. {
            let slot = (n % 256) as u8;
            if slot % 4 == 3 {
                continue; // downlink slots
            }
            let up = Frame::Uplink(Uplink {
                slot,
                stream: StreamHeader::default(),
                report: None,
                save_failsafe: true,
                input_lost: false,
                format: ChannelFormat::Full16,
                packed_channels: &packed,
                data: &[],
            });
            let mut buf = [0u8; 64];
            let len = if n % 2 == 0 {
                let counter = TagContext::Counter(u64::from(slot));
                seal(&up, &guess, &counter, &mut buf).unwrap()
            } else {
                encode(&up, bind_id, &mut buf).unwrap()
            };
            radio
                .set_channel(hops.channel(usize::from(slot) % HOP_CHANNELS))
                .await
                .unwrap();
            radio.transmit(&buf[..len]).await.unwrap();
            l.borrow_mut().attacker_sent += 1;
            let next = clock.now_us() + 3_000;
            clock.sleep_until_us(next).await;
        }
    });
    sim.run_for(Duration::from_secs(10));
    let log = log.borrow();
    println!("{log:?}");
    assert!(log.attacker_sent > 1_000, "{log:?}");
    assert!(!log.forged_seen, "forged throttle flown: {log:?}");
    assert!(!log.failsafe_changed, "failsafe overwritten: {log:?}");
    assert!(
        log.rejected > 20,
        "forgeries reached the link code: {log:?}"
    );
    assert!(log.updates > 0, "the real link still flies: {log:?}");
}
