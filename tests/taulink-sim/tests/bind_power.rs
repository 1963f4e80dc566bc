//! Binding is a close-range act: both ends, on the real rfm22b driver over virtual Si4432s,
//! transmit their bind frames at the chip's lowest power step, whatever power the link
//! itself uses, and go back to the link's power once bound — with the key agreement on a
//! phrase, both ending with the module's link key.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Duration;

use radio_rfm22b::{Rfm22b, TxPower};
use si4432_sim::{RadioConfig as Placement, Simulation};
use taulink_sim::driver::{LinkRadio, SimClock};
use telemetry::channels::ChannelFormat;
use telemetry::link::follower::{FollowerBind, bind_follower};
use telemetry::link::master::{MasterBind, bind_master};
use telemetry::link::{
    Band, BindAuth, FollowerAuth, LinkKey, LinkParams, PacketRadio, PhraseSecret, RateMode,
};

const PHRASE: &str = "amber kettle under the oak";

/// Si4432 TX power register; bits 2..0 are the power step.
const TX_POWER_REG: u8 = 0x6D;

#[test]
fn both_ends_bind_at_the_lowest_power_step_and_link_at_their_own() {
    let sim = Simulation::new(5);
    let medium = sim.medium();
    let module = medium.add_radio(Placement::at([0.0, 0.0, 0.0]));
    let flight = medium.add_radio(Placement::at([2.0, 0.0, 0.0]));
    let (module_chip, flight_chip) = (module.chip.clone(), flight.chip.clone());
    let params = LinkParams::new(
        0x0B1D_0B1D,
        Band::Mhz433,
        RateMode::F250,
        ChannelFormat::Full16,
        4,
    );
    // Power step seen on each chip while it transmitted bind frames, and after binding.
    let seen = Rc::new(RefCell::new((None, None, None, None)));
    let key = LinkKey::from_bytes([0x6B; 16]);
    let auth = BindAuth::Phrase(PhraseSecret::derive(PHRASE, [3; 8]));

    let mut clock = SimClock::new(medium.time(), 0, 0.0);
    let mut radio = LinkRadio::new(
        Rfm22b::new(module.spi, module.nirq, module.sdn, module.delay),
        TxPower::MAX,
    );
    let (s, chip) = (seen.clone(), module_chip.clone());
    sim.spawn(async move {
        let bound = bind_master(
            &mut radio,
            &mut clock,
            &params,
            &auth,
            &key,
            &[0x11; 32],
            2_000_000,
        )
        .await;
        s.borrow_mut().0 = Some((bound.unwrap(), chip.peek(TX_POWER_REG) & 0x07));
        radio.configure(&params.radio_config()).await.unwrap();
        s.borrow_mut().1 = Some(chip.peek(TX_POWER_REG) & 0x07);
    });
    let mut clock = SimClock::new(medium.time(), 0, 0.0);
    let mut radio = LinkRadio::new(
        Rfm22b::new(flight.spi, flight.nirq, flight.sdn, flight.delay),
        TxPower::MAX,
    );
    let (s, chip) = (seen.clone(), flight_chip.clone());
    sim.spawn(async move {
        let follower = FollowerAuth {
            phrase: Some(PHRASE),
            stored: None,
            allow_plain: false,
        };
        let offered = bind_follower(
            &mut radio,
            &mut clock,
            Band::Mhz433,
            &follower,
            &[0x22; 32],
            2_000_000,
        )
        .await;
        s.borrow_mut().2 = Some((offered.unwrap(), chip.peek(TX_POWER_REG) & 0x07));
        radio.configure(&params.radio_config()).await.unwrap();
        s.borrow_mut().3 = Some(chip.peek(TX_POWER_REG) & 0x07);
    });
    sim.run_for(Duration::from_secs(3));
    let seen = seen.borrow();
    assert_eq!(
        seen.0,
        Some((MasterBind::Bound(Some(key)), TxPower::MIN.step())),
        "module bind power"
    );
    assert_eq!(
        seen.2,
        Some((
            FollowerBind::Bound {
                params,
                key: Some(key)
            },
            TxPower::MIN.step()
        )),
        "flight bind power"
    );
    assert_eq!(seen.1, Some(TxPower::MAX.step()), "module link power");
    assert_eq!(seen.3, Some(TxPower::MAX.step()), "flight link power");
}
