//! The ground station's module records against the module's own code: what the phone sends
//! passes the HM-10 relay to the module core (`module_core::phrase::PhoneAccess`), and the
//! module's answers come back through the stream decoder as events the page hands to its
//! `Phone` — the CPace exchange on the binding phrase, the grant, and a new module phrase
//! sealed in the session (spec §12.5).
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use module_core::hm10::Relay;
use module_core::phrase::PhoneAccess;
use module_core::records;
use module_core::settings::Settings;
use telemetry::change_auth::ChangeKey;
use telemetry::framing::frame;
use telemetry::link::{LinkKey, PhraseSecret};
use telemetry::module_record::{self, ModuleRecord, Outcome, Refusal};
use telemetry_wasm::settings::{Phone, Standing};
use telemetry_wasm::stream::StreamDecoder;

const PHRASE: &str = "amber kettle under the oak";

/// `framed` through the relay: the module record the core takes from it.
fn at_module(framed: &[u8]) -> ModuleRecord {
    let mut relay = Relay::new(true);
    relay.on_phone_bytes(framed);
    let mut flight = [0u8; 64];
    assert_eq!(
        relay.next_record_to_flight(&mut flight),
        None,
        "stops at the module"
    );
    let mut out = [0u8; 128];
    let n = relay.next_record_to_module(&mut out).unwrap();
    module_record::decode(records::payload(&out[..n]).unwrap()).unwrap()
}

/// The module's record as the ground station's decoder reports it (the event's JSON).
fn decoded(record: &ModuleRecord) -> String {
    let mut payload = [0u8; module_record::MAX_PAYLOAD_BYTES];
    let n = module_record::encode(record, &mut payload).unwrap();
    let mut framed = [0u8; 160];
    let bytes = frame(&payload[..n], &mut framed).unwrap();
    let events: serde_json::Value =
        serde_json::from_str(&StreamDecoder::new().push(bytes)).unwrap();
    events[0].to_string()
}

/// A module with `phrase` set, and its phone access.
fn module(phrase: &str) -> (Settings, PhoneAccess) {
    let mut settings = Settings::default();
    let secret = PhraseSecret::derive(phrase, [9; 8]);
    settings.phrase_salt = secret.salt;
    settings.phrase_prs = Some(secret.prs);
    (settings, PhoneAccess::default())
}

/// One round: the phone's frame to the module, the module's answer back to the phone.
fn round(
    phone: &mut Phone,
    framed: &[u8],
    settings: &mut Settings,
    access: &mut PhoneAccess,
    change_key: Option<ChangeKey>,
) -> (ModuleRecord, Vec<u8>) {
    let reply = access
        .on_record(&at_module(framed), settings, false, change_key, || [7; 32])
        .unwrap();
    let next = phone.on_module_record(&decoded(&reply.reply), &[8; 32]);
    (reply.reply, next)
}

#[test]
fn the_phone_with_the_phrase_is_granted_and_sets_a_new_module_phrase() {
    let (mut settings, mut access) = module(PHRASE);
    let change_key = ChangeKey::from_link_key(&LinkKey::from_bytes([4; 16]));
    let mut phone = Phone::new(PHRASE).unwrap();
    // The new phrase waits for the grant: a Hello goes first.
    let hello = phone
        .set_module_phrase("brass lantern by the weir")
        .unwrap();
    let (challenge, response) = round(
        &mut phone,
        &hello,
        &mut settings,
        &mut access,
        Some(change_key),
    );
    assert!(matches!(challenge, ModuleRecord::Challenge(_)));
    let (granted, set) = round(
        &mut phone,
        &response,
        &mut settings,
        &mut access,
        Some(change_key),
    );
    assert!(matches!(granted, ModuleRecord::Granted(_)));
    assert_eq!(phone.standing(), Standing::Granted);
    let (answer, next) = round(
        &mut phone,
        &set,
        &mut settings,
        &mut access,
        Some(change_key),
    );
    assert!(
        matches!(answer, ModuleRecord::Answer(a) if a.outcome == Outcome::Applied),
        "{answer:?}"
    );
    assert!(next.is_empty());
    assert_eq!(
        settings.phrase_prs,
        Some(PhraseSecret::derive("brass lantern by the weir", [9; 8]).prs)
    );
    // The recorded SetPhrase again: used up.
    let replay = access
        .on_record(
            &at_module(&set),
            &mut settings,
            false,
            Some(change_key),
            || [7; 32],
        )
        .unwrap();
    assert!(matches!(
        replay.reply,
        ModuleRecord::Answer(a) if a.outcome == Outcome::Refused(Refusal::Replayed)
    ));
}

#[test]
fn a_phone_with_another_phrase_is_refused_and_changes_nothing() {
    let (mut settings, mut access) = module(PHRASE);
    let before = settings.phrase_prs;
    let mut phone = Phone::new("amber kettle under the elm").unwrap();
    let hello = phone
        .set_module_phrase("brass lantern by the weir")
        .unwrap();
    let (_, response) = round(&mut phone, &hello, &mut settings, &mut access, None);
    let (answer, next) = round(&mut phone, &response, &mut settings, &mut access, None);
    assert!(matches!(
        answer,
        ModuleRecord::Answer(a) if a.outcome == Outcome::Refused(Refusal::NotAuthenticated)
    ));
    assert!(next.is_empty());
    assert_eq!(
        phone.standing(),
        Standing::Refused(Refusal::NotAuthenticated)
    );
    assert_eq!(settings.phrase_prs, before);
    assert!(phone.set_module_phrase("x").is_err(), "the phrase rule");
}
