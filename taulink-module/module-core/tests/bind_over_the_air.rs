//! A bind over the (mock) air between two module cores, as the firmware's link task runs it
//! (long press → the session stops → the core's bind step → its outcome back to the core):
//! the transmitter draws a bind ID and offers the link parameters of its settings; the
//! receiver accepts and stores the offer. Afterwards both ends' settings must give the same
//! link parameters, so the link comes back after a reboot of either.

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

use std::cell::RefCell;
use std::rc::Rc;

use module_core::air::{AirLink, link_params, new_bind_params};
use module_core::app::{Action, App};
use module_core::button::ButtonEvent;
use module_core::handset::Handset;
use module_core::session::{BindOutcome, LinkStep, SessionEnd};
use module_core::settings::{Band, RateMode, Role, Settings};
use telemetry::link::follower::bind_follower;
use telemetry::link::master::bind_master;
use telemetry::mock::{ChannelModel, Executor, Medium, MockRadio, Node, SimClock, VirtualTime};

fn core(settings: Settings) -> App<AirLink, Handset> {
    App::new(settings, AirLink::new(), Handset::new(&settings), false).unwrap()
}

/// Probe, idle unbound, long press: the bind step the core asks for.
fn press_bind(app: &mut App<AirLink, Handset>, random: u32) -> LinkStep {
    assert_eq!(app.next_link_step(0, 0), LinkStep::Probe);
    app.on_radio_present(true);
    assert_eq!(app.next_link_step(0, 0), LinkStep::WaitForBind);
    assert_eq!(app.poll_session(50), None);
    app.on_button(ButtonEvent::LongPress);
    assert_eq!(app.poll_session(100), Some(SessionEnd::BindRequested));
    app.on_session_end(SessionEnd::BindRequested);
    app.next_link_step(100, random)
}

#[test]
fn both_ends_store_the_same_link() {
    let tx_settings = Settings {
        rate: RateMode::M100,
        band: Band::Mhz868,
        ..Settings::default()
    };
    // The receiver starts with other rate and band settings; only its band's bind channel
    // has to match (the bind frequency is per band).
    let rx_settings = Settings {
        role: Role::Receiver,
        rate: RateMode::L50,
        band: Band::Mhz868,
        ..Settings::default()
    };
    let tx = Rc::new(RefCell::new(core(tx_settings)));
    let rx = Rc::new(RefCell::new(core(rx_settings)));
    let time = VirtualTime::new();
    let medium = Medium::new(time.clone(), ChannelModel::default(), 3);
    let tx_node = medium.add_node(Node::default());
    let rx_node = medium.add_node(Node {
        position_m: 5.0,
        ..Node::default()
    });
    let executor = Executor::new(time.clone());
    let saved = Rc::new(RefCell::new(Vec::new()));
    let (tx_app, tx_saved) = (tx.clone(), saved.clone());
    let mut radio = MockRadio::new(medium.clone(), tx_node);
    let mut clock = SimClock::new(time.clone(), 1_000, 0.0);
    let LinkStep::BindMaster { params, timeout_us } = press_bind(&mut tx.borrow_mut(), 0x7777_1234)
    else {
        panic!("a transmitter binds as master");
    };
    assert_eq!(params, new_bind_params(&tx_settings, 0x7777_1234));
    executor.spawn(async move {
        let result = bind_master(&mut radio, &mut clock, &params, timeout_us).await;
        let action = tx_app
            .borrow_mut()
            .on_bind_outcome(BindOutcome::offered(result));
        tx_saved.borrow_mut().push(("tx", action));
    });
    let (rx_app, rx_saved) = (rx.clone(), saved.clone());
    let mut radio = MockRadio::new(medium, rx_node);
    let mut clock = SimClock::new(time.clone(), 2_000_000, 0.0);
    let LinkStep::BindFollower { band, timeout_us } = press_bind(&mut rx.borrow_mut(), 1) else {
        panic!("a receiver binds as follower");
    };
    executor.spawn(async move {
        let result = bind_follower(&mut radio, &mut clock, band, timeout_us).await;
        let action = rx_app
            .borrow_mut()
            .on_bind_outcome(BindOutcome::listened(result));
        rx_saved.borrow_mut().push(("rx", action));
    });
    executor.run_until_us(12_000_000);

    let saved = saved.borrow();
    assert_eq!(saved.len(), 2, "both ends bound: {saved:?}");
    let settings_of = |end: &str| {
        saved
            .iter()
            .find_map(|(e, a)| match a {
                Some(Action::Save(s)) if *e == end => Some(*s),
                _ => None,
            })
            .unwrap()
    };
    let (tx_saved, rx_saved) = (settings_of("tx"), settings_of("rx"));
    assert_eq!(tx_saved.bind_id, 0x7777_1234);
    assert_eq!(rx_saved.bind_id, 0x7777_1234);
    assert_eq!(rx_saved.rate, RateMode::M100, "the offer's rate");
    assert_eq!(rx_saved.role, Role::Receiver);
    let tx_link = link_params(&tx_saved).unwrap();
    assert_eq!(link_params(&rx_saved), Some(tx_link));
    assert_eq!(*tx.borrow().settings(), tx_saved);
    assert_eq!(*rx.borrow().settings(), rx_saved);
}
