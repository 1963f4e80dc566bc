//! The binding phrase on the flight side: the console's `phrase`, the stored key, the keyed
//! follower and the link restart.

use super::tests::{armed_in_the_air, some_link};
use super::*;
use telemetry::link::LinkKey;

const PHRASE: &str = "correct horse battery staple";

fn bound_app() -> FlightApp {
    let mut settings = Settings::default();
    let Ok(()) = crate::pipeline::store_link(&mut settings, &some_link()) else {
        panic!("a valid link");
    };
    let Some(app) = FlightApp::new(settings, 0) else {
        panic!("factory settings make a setup");
    };
    app
}

fn console(app: &mut FlightApp, line: &str) -> String {
    let mut out = heapless::String::<512>::new();
    let _ = app.on_console_line(line, &mut out);
    out.as_str().to_owned()
}

#[test]
fn the_console_sets_the_phrase_as_a_key_saves_it_and_restarts_the_link_keyed() {
    let mut app = bound_app();
    assert_eq!(app.next_link_step(), LinkStep::Follow(some_link()));
    let unkeyed = app.follower(some_link(), FAILSAFE_US);
    assert_eq!(unkeyed.params().bind_id, some_link().bind_id);
    assert!(!app.link_restart_due());

    let out = console(&mut app, &format!("phrase {PHRASE}"));
    let key = LinkKey::from_phrase(PHRASE);
    assert_eq!(app.settings().link_key(), Some(key));
    assert!(
        out.contains(&key.fingerprint().to_string()),
        "fingerprint shown: {out}"
    );
    assert!(!out.contains("horse"), "the phrase is never printed: {out}");
    assert!(app.link_restart_due(), "the running follower must stop");
    let Some((to_write, _)) = app.take_save() else {
        panic!("a save is due");
    };
    assert_eq!(to_write.link_key(), Some(key));
    // The next follower is keyed: its identity is the key's, not the bind's.
    assert_eq!(app.next_link_step(), LinkStep::Follow(some_link()));
    assert!(!app.link_restart_due());
    let keyed = app.follower(some_link(), FAILSAFE_US);
    assert_eq!(keyed.params().bind_id, key.bind_id());
    assert_eq!(keyed.params().rate, some_link().rate);

    // Shown again (without the phrase), in `phrase` and in `status`.
    for line in ["phrase", "status"] {
        let out = console(&mut app, line);
        assert!(
            out.contains(&key.fingerprint().to_string()),
            "{line}: {out}"
        );
    }

    let out = console(&mut app, "phrase clear");
    assert_eq!(app.settings().link_key(), None);
    assert!(out.contains("unauthenticated"), "{out}");
    assert!(app.link_restart_due());
    assert!(app.take_save().is_some());
    let _ = app.next_link_step();
    assert_eq!(
        app.follower(some_link(), FAILSAFE_US).params().bind_id,
        some_link().bind_id
    );
    assert!(console(&mut app, "status").contains("unauthenticated"));
}

#[test]
fn the_phrase_cannot_change_in_flight_and_bad_phrases_are_refused() {
    let mut app = bound_app();
    armed_in_the_air(&mut app);
    let out = console(&mut app, &format!("phrase {PHRASE}"));
    assert!(out.contains("refused"), "{out}");
    assert!(console(&mut app, "phrase clear").contains("refused"));
    assert_eq!(app.settings().link_key(), None);
    assert!(!app.link_restart_due());

    let mut app = bound_app();
    let out = console(&mut app, &format!("phrase {}", "x".repeat(65)));
    assert!(out.contains("refused"), "{out}");
    assert_eq!(app.settings().link_key(), None);
    assert!(!app.link_restart_due());
    assert!(app.take_save().is_none());
}

#[test]
fn factory_defaults_drop_the_key_and_restart_the_link() {
    let mut app = bound_app();
    console(&mut app, &format!("phrase {PHRASE}"));
    let _ = app.next_link_step();
    console(&mut app, "defaults");
    assert_eq!(app.settings().link_key(), None);
    assert!(app.link_restart_due());
}
