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

/// Feeds `message` into the app as the follower's uplink stream delivers it.
fn uplink(app: &mut FlightApp, message: &telemetry::messages::Message, at_us: u64) {
    use telemetry::channels::FailsafeValues;
    use telemetry::link::core::Follower;
    let mut bytes = [0u8; 64];
    let n = telemetry::messages::encode_message(message, &mut bytes)
        .unwrap()
        .len();
    let mut follower = Follower::new(some_link(), FailsafeValues::default(), FAILSAFE_US);
    follower.uplink_stream.on_data(0, &bytes[..n]);
    app.on_link_step(at_us, &mut follower);
}

/// Before spec §12.5 any `SettingChange` on the uplink was applied while disarmed (so
/// anyone who could inject into the stream could change gains and the failsafe): now only a
/// change signed with the phrase's key is.
#[test]
fn an_unsigned_change_is_refused_and_a_signed_one_applied() {
    use crate::report::f32_value;
    use crate::settings::{PARAMS, handles};
    use telemetry::change_auth::ChangeKey;
    use telemetry::messages::{Message, SettingChange};
    let mut app = bound_app();
    console(&mut app, &format!("phrase {PHRASE}"));
    app.seed_change_session(0xABCD_0001);
    let _ = app.take_design_request();
    let id = PARAMS
        .iter()
        .position(|p| p.name == "failsafe.descent_mps")
        .unwrap() as u16;
    let change = SettingChange {
        id,
        value: f32_value(0.9),
    };
    let before = app.settings().get(handles::FAILSAFE_DESCENT_MPS);
    uplink(&mut app, &Message::SettingChange(change), 100_000);
    assert_eq!(app.settings().get(handles::FAILSAFE_DESCENT_MPS), before);
    assert_eq!(app.take_design_request(), None);

    let key = ChangeKey::from_link_key(&LinkKey::from_phrase(PHRASE));
    let signed = key.sign(0xABCD_0001, 1, change);
    uplink(&mut app, &Message::SignedChange(signed), 200_000);
    assert_eq!(app.settings().get(handles::FAILSAFE_DESCENT_MPS), 0.9);
    assert!(app.take_design_request().is_some());
}
