//! The binding phrase and the link key on the flight side (spec §12.1, §12.5): `bind
//! PHRASE` holds the phrase for the window only, the bind's agreed key is stored and the
//! link restarts keyed with it, an unauthenticated link runs only by the explicit setting,
//! and phone changes are checked under that key.

use super::tests::{armed_in_the_air, bound, some_link};
use super::*;
use telemetry::link::LinkKey;
use telemetry::link::follower::FollowerBind;

const PHRASE: &str = "amber kettle under the oak";

fn bound_app() -> FlightApp {
    let Some(mut app) = FlightApp::new(Settings::default(), 0) else {
        panic!("factory settings make a setup");
    };
    app.seed_random(&[0x5E; 32]);
    assert!(app.request_bind("").is_ok());
    let _ = app.take_bind_request();
    assert!(app.on_bind_result(&bound(some_link())));
    let _ = app.take_save();
    let _ = app.next_link_step();
    app
}

fn console(app: &mut FlightApp, line: &str) -> String {
    let mut out = heapless::String::<512>::new();
    let _ = app.on_console_line(line, &mut out);
    out.as_str().to_owned()
}

#[test]
fn bind_with_a_phrase_holds_it_for_the_window_only_and_stores_the_agreed_key() {
    let Some(mut app) = FlightApp::new(Settings::default(), 0) else {
        panic!("a setup");
    };
    app.seed_random(&[1; 32]);
    let out = console(&mut app, &format!("bind {PHRASE}"));
    assert!(out.contains("with the phrase"), "{out}");
    assert!(
        !out.contains("kettle"),
        "the phrase is never printed: {out}"
    );
    let request = app.take_bind_request().expect("a window");
    assert_eq!(request.phrase.as_deref(), Some(PHRASE));
    assert_eq!(request.auth().phrase, Some(PHRASE));
    assert!(!request.auth().allow_plain);
    let key = LinkKey::from_bytes([0x42; 16]);
    assert!(app.on_bind_result(&FollowerBind::Bound {
        params: some_link(),
        key: Some(key),
    }));
    assert_eq!(app.settings().link_key(), Some(key));
    assert!(app.link_restart_due(), "the link restarts with the new key");
    let Some((to_write, _)) = app.take_save() else {
        panic!("a save is due");
    };
    assert_eq!(to_write.link_key(), Some(key));
    assert_eq!(app.next_link_step(), LinkStep::Follow(some_link()));
    assert!(app.follower(some_link(), FAILSAFE_US).has_key());
    let status = console(&mut app, "status");
    assert!(status.contains(&key.fingerprint().to_string()), "{status}");
    assert!(!status.contains("kettle"), "{status}");
    // The window is over: a second one without a phrase does not keep the first's.
    let _ = console(&mut app, "bind");
    assert_eq!(app.take_bind_request().expect("a window").phrase, None);
}

#[test]
fn bind_is_refused_in_flight_and_for_weak_or_famous_phrases() {
    let mut app = bound_app();
    armed_in_the_air(&mut app);
    assert!(console(&mut app, &format!("bind {PHRASE}")).contains("refused"));
    assert!(!app.bind_requested());
    let mut app = bound_app();
    for weak in [
        "short one",
        "correct horse battery staple",
        "aaaaaaaaaaaaaaaa",
    ] {
        let out = console(&mut app, &format!("bind {weak}"));
        assert!(out.contains("refused"), "{weak}: {out}");
        assert!(!app.bind_requested());
    }
}

#[test]
fn a_refused_bind_stores_nothing_and_says_why() {
    let mut app = bound_app();
    let key = app.settings().link_key();
    let _ = console(&mut app, "bind");
    let _ = app.take_bind_request();
    let refused = FollowerBind::Refused(telemetry::link::BindRefusal::PhraseWanted);
    assert!(!app.on_bind_result(&refused));
    assert_eq!(app.settings().link_key(), key);
    assert_eq!(app.link_params(), Some(some_link()));
    let status = console(&mut app, "status");
    assert!(status.contains("phrase"), "{status}");
}

#[test]
fn an_unauthenticated_link_runs_only_by_the_explicit_setting() {
    let Some(mut app) = FlightApp::new(Settings::default(), 0) else {
        panic!("a setup");
    };
    let _ = console(&mut app, "bind");
    assert!(!app.take_bind_request().expect("a window").allow_plain);
    // Stored anyway (the module offered it and the follower took it by the setting, say,
    // which was then switched off): it does not run.
    assert!(app.on_bind_result(&FollowerBind::Bound {
        params: some_link(),
        key: None,
    }));
    assert_eq!(app.link_params(), None);
    assert_eq!(app.next_link_step(), LinkStep::WaitForBind);
    console(&mut app, "set link.unauthenticated 1");
    assert_eq!(app.link_params(), Some(some_link()));
    assert!(!app.follower(some_link(), FAILSAFE_US).has_key());
    assert!(console(&mut app, "status").contains("unauthenticated"));
    let _ = console(&mut app, "bind");
    assert!(app.take_bind_request().expect("a window").allow_plain);
}

#[test]
fn factory_defaults_drop_the_key_and_the_link_and_restart_it() {
    let mut app = bound_app();
    assert!(app.settings().link_key().is_some());
    console(&mut app, "defaults");
    assert_eq!(app.settings().link_key(), None);
    assert_eq!(app.link_params(), None);
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
/// change signed with the change key of the link's key is.
#[test]
fn an_unsigned_change_is_refused_and_a_signed_one_applied() {
    use crate::report::f32_value;
    use crate::settings::{PARAMS, handles};
    use telemetry::change_auth::ChangeKey;
    use telemetry::messages::{ChangeRefused, Message, SettingChange};
    let mut app = bound_app();
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

    // The phone learns the session from the refusal and signs with the link key's change key.
    let mut phone = telemetry::change_auth::Signer::new(ChangeKey::from_link_key(
        &app.settings().link_key().expect("keyed"),
    ));
    let first = phone.sign(change);
    uplink(&mut app, &Message::SignedChange(first), 150_000);
    let refused = ChangeRefused {
        id,
        reason: telemetry::messages::RefuseReason::NotAuthenticated,
        session: app.change_session(),
        counter: 0,
    };
    assert!(phone.on_refused(&refused));
    uplink(
        &mut app,
        &Message::SignedChange(phone.sign(change)),
        200_000,
    );
    assert_eq!(app.settings().get(handles::FAILSAFE_DESCENT_MPS), 0.9);
    assert!(app.take_design_request().is_some());
    // Saved: the phone has no `save` command, and a change must survive a power cycle.
    let Some((to_write, _)) = app.take_save() else {
        panic!("an applied phone change is saved");
    };
    assert_eq!(to_write.get(handles::FAILSAFE_DESCENT_MPS), 0.9);
}
