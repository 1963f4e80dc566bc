//! The binding phrase at chip level: both applications (the module's `App` and the flight
//! side's `FlightApp`) build their link ends from their own settings on virtual Si4432s.
//! The same phrase on both ends links (channels and telemetry flow); different phrases, or
//! a phrase on one end only, never do — not one channel frame is accepted — although both
//! ends store the same bind (rate, band, bind ID) as after an over-the-air bind.
#![allow(clippy::unwrap_used)]

use flight_sitl::scenario::default_airframe;
use flight_sitl::{PilotInput, Scenario, Sitl, run};
use telemetry::link::LinkKey;

const PHRASE: &str = "correct horse battery staple";

fn world(module_phrase: Option<&str>, flight_phrase: Option<&str>) -> Sitl {
    let (quad, mut settings) = default_airframe();
    settings.set_link_key(flight_phrase.map(LinkKey::from_phrase));
    let mut scenario = Scenario::new(settings, quad, 3.0, Box::new(|_| PilotInput::default()));
    scenario.module_settings = Some(module_core::settings::Settings {
        link_key: module_phrase.map(LinkKey::from_phrase),
        ..module_core::settings::Settings::default()
    });
    run(scenario)
}

fn link_up(sitl: &Sitl) -> usize {
    sitl.samples.iter().filter(|s| s.link_up).count()
}

#[test]
fn the_same_phrase_on_both_ends_links() {
    let sitl = world(Some(PHRASE), Some(PHRASE));
    assert_eq!(sitl.settings.link_key(), Some(LinkKey::from_phrase(PHRASE)));
    assert!(
        sitl.samples.iter().all(|s| s.link_up),
        "channels all the time: {} of {}",
        link_up(&sitl),
        sitl.samples.len()
    );
    assert!(!sitl.module_rx.is_empty(), "telemetry reaches the module");
}

#[test]
fn different_phrases_never_link() {
    for (module, flight) in [
        (Some(PHRASE), Some("correct horse battery stapler")),
        (Some(PHRASE), None),
        (None, Some(PHRASE)),
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
