//! A bind over the (mock) air between two module cores, as the firmware's link task runs it
//! (long press → the session stops → the core's bind step → its outcome back to the core):
//! the transmitter draws a bind ID and offers the link parameters of its settings with a
//! CPace share (spec §12.1); the receiver answers, the transmitter hands over the link's key
//! sealed, and both store link and key. Afterwards both ends' settings must give the same
//! link parameters and the same link key, so the link comes back after a reboot of either.

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
use telemetry::link::FollowerAuth;
use telemetry::link::follower::bind_follower;
use telemetry::link::master::bind_master;
use telemetry::mock::{ChannelModel, Executor, Medium, MockRadio, Node, SimClock, VirtualTime};

fn core(settings: Settings, seed: u8) -> App<AirLink, Handset> {
    let mut app = App::new(settings, AirLink::new(), Handset::new(&settings), false).unwrap();
    app.seed_random(&[seed; 32]);
    app
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

/// Both cores bind over the mock air; what each saved (`None`: nothing).
fn bind(tx_settings: Settings, rx_settings: Settings) -> (Option<Settings>, Option<Settings>) {
    let tx = Rc::new(RefCell::new(core(tx_settings, 1)));
    let rx = Rc::new(RefCell::new(core(rx_settings, 2)));
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
    let LinkStep::BindMaster {
        params,
        auth,
        key,
        random,
        timeout_us,
    } = press_bind(&mut tx.borrow_mut(), 0x7777_1234)
    else {
        panic!("a transmitter binds as master");
    };
    assert_eq!(params, new_bind_params(&tx_settings, 0x7777_1234));
    executor.spawn(async move {
        let result = bind_master(
            &mut radio, &mut clock, &params, &auth, &key, &random, timeout_us,
        )
        .await;
        let action = tx_app
            .borrow_mut()
            .on_bind_outcome(BindOutcome::offered(result));
        tx_saved.borrow_mut().push(("tx", action));
    });
    let (rx_app, rx_saved) = (rx.clone(), saved.clone());
    let mut radio = MockRadio::new(medium, rx_node);
    let mut clock = SimClock::new(time.clone(), 2_000_000, 0.0);
    let LinkStep::BindFollower {
        band,
        stored,
        allow_plain,
        random,
        timeout_us,
    } = press_bind(&mut rx.borrow_mut(), 1)
    else {
        panic!("a receiver binds as follower");
    };
    executor.spawn(async move {
        let auth = FollowerAuth {
            phrase: None,
            stored,
            allow_plain,
        };
        let result = bind_follower(&mut radio, &mut clock, band, &auth, &random, timeout_us).await;
        let action = rx_app
            .borrow_mut()
            .on_bind_outcome(BindOutcome::listened(result));
        rx_saved.borrow_mut().push(("rx", action));
    });
    executor.run_until_us(12_000_000);

    let saved = saved.borrow();
    let settings_of = |end: &str| {
        saved.iter().find_map(|(e, a)| match a {
            Some(Action::Save(s)) if *e == end => Some(*s),
            _ => None,
        })
    };
    (settings_of("tx"), settings_of("rx"))
}

fn settings_pair() -> (Settings, Settings) {
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
    (tx_settings, rx_settings)
}

#[test]
fn both_ends_store_the_same_link_and_key() {
    let (tx_settings, rx_settings) = settings_pair();
    let (Some(tx_saved), Some(rx_saved)) = bind(tx_settings, rx_settings) else {
        panic!("both ends bound");
    };
    assert_eq!(tx_saved.bind_id, 0x7777_1234);
    assert_eq!(rx_saved.bind_id, 0x7777_1234);
    assert_eq!(rx_saved.rate, RateMode::M100, "the offer's rate");
    assert_eq!(rx_saved.role, Role::Receiver);
    let tx_link = link_params(&tx_saved).unwrap();
    assert_eq!(link_params(&rx_saved), Some(tx_link));
    // The transmitter keeps its module key, the receiver the link's key derived from it.
    let module_key = tx_saved.link_key.expect("an agreed key");
    assert_eq!(
        rx_saved.link_key,
        Some(module_key.for_link(tx_link.bind_id))
    );
}

/// With the same phrase (the receiver's stored derivation under the transmitter's salt)
/// both ends bind; with another phrase nothing is stored on either.
#[test]
fn a_phrase_binds_only_ends_with_the_same_phrase() {
    let (mut tx_settings, mut rx_settings) = settings_pair();
    tx_settings.phrase_salt = [7; 8];
    tx_settings
        .set_text("phrase", "amber kettle under the oak")
        .unwrap();
    rx_settings.phrase_salt = [7; 8];
    rx_settings
        .set_text("phrase", "amber kettle under the oak")
        .unwrap();
    let (Some(tx_saved), Some(rx_saved)) = bind(tx_settings, rx_settings) else {
        panic!("both ends bound");
    };
    let key = tx_saved.link_key.unwrap().for_link(tx_saved.bind_id);
    assert_eq!(rx_saved.link_key, Some(key));

    rx_settings
        .set_text("phrase", "amber kettle under the elm")
        .unwrap();
    assert_eq!(
        bind(tx_settings, rx_settings),
        (None, None),
        "nothing bound"
    );
}
