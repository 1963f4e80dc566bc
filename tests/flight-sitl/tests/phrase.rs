//! The link key at chip level: both applications (the module's `App` and the flight side's
//! `FlightApp`) build their link ends from their own settings on virtual Si4432s. The key
//! the bind handed over (the module key's for that link) links — channels and telemetry
//! flow; another key, or a key on one end only, never does — not one channel frame is
//! accepted — although both ends store the same bind (rate, band, bind ID).
#![allow(clippy::unwrap_used)]

use flight_app::settings::handles;
use flight_sitl::scenario::default_airframe;
use flight_sitl::{PilotInput, Scenario, Sitl, run};
use telemetry::link::LinkKey;

const MODULE_KEY: LinkKey = LinkKey::from_bytes(*b"the module's key");

/// What the flight side holds.
#[derive(Clone, Copy, Debug)]
enum Flight {
    /// What the bind handed over.
    Bound,
    /// Another key (a bind with another module).
    Key(LinkKey),
    /// No key, the unauthenticated setting on.
    Plain,
}

fn world(module_key: Option<LinkKey>, flight: Flight) -> Sitl {
    let (quad, mut settings) = default_airframe();
    match flight {
        Flight::Bound => {}
        Flight::Key(k) => settings.set_link_key(Some(k)),
        Flight::Plain => {
            settings
                .apply(&[handles::LINK_UNAUTHENTICATED.to(1)])
                .unwrap();
        }
    }
    let mut scenario = Scenario::new(settings, quad, 3.0, Box::new(|_| PilotInput::default()));
    scenario.module_settings = Some(module_core::settings::Settings {
        link_key: module_key,
        plain: module_key.is_none(),
        ..module_core::settings::Settings::default()
    });
    run(scenario)
}

fn link_up(sitl: &Sitl) -> usize {
    sitl.samples.iter().filter(|s| s.link_up).count()
}

#[test]
fn the_key_the_bind_handed_over_links() {
    let sitl = world(Some(MODULE_KEY), Flight::Bound);
    let bind_id = flight_app::pipeline::stored_link(&sitl.settings)
        .unwrap()
        .bind_id;
    assert_eq!(sitl.settings.link_key(), Some(MODULE_KEY.for_link(bind_id)));
    assert!(
        sitl.samples.iter().all(|s| s.link_up),
        "channels all the time: {} of {}",
        link_up(&sitl),
        sitl.samples.len()
    );
    assert!(!sitl.module_rx.is_empty(), "telemetry reaches the module");
}

#[test]
fn another_key_or_a_key_on_one_end_never_links() {
    for (module, flight) in [
        (
            Some(MODULE_KEY),
            Flight::Key(LinkKey::from_bytes([0x0E; 16])),
        ),
        (Some(MODULE_KEY), Flight::Plain),
        (None, Flight::Key(MODULE_KEY)),
    ] {
        let sitl = world(module, flight);
        assert_eq!(
            link_up(&sitl),
            0,
            "module {module:?}, flight {flight:?}: no channels accepted"
        );
        assert!(
            sitl.module_rx.is_empty(),
            "module {module:?}, flight {flight:?}: no telemetry accepted"
        );
    }
}
