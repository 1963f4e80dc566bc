//! The ground station's module-phrase records against the module's own code: what the phone
//! sends passes the HM-10 relay to the module core (`module_core::phrase::PhoneKeys`), and
//! the module's answer comes back through the stream decoder as a `KeyAnswer` event.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

use module_core::hm10::Relay;
use module_core::params::Commands;
use module_core::phrase::PhoneKeys;
use module_core::records;
use telemetry::framing::frame;
use telemetry::link::LinkKey;
use telemetry::module_record::{self, KeyAnswer, KeyOutcome, KeyRefusal, ModuleRecord};
use telemetry_wasm::settings::{Phone, phrase_fingerprint, propose_module_phrase};
use telemetry_wasm::stream::StreamDecoder;

/// `frame` through the relay: the module record the core takes from it.
fn at_module(framed: &[u8]) -> ModuleRecord {
    let mut relay = Relay::new(true);
    relay.on_phone_bytes(framed);
    let mut flight = [0u8; 64];
    assert_eq!(
        relay.next_record_to_flight(&mut flight),
        None,
        "stops at the module"
    );
    let mut out = [0u8; 64];
    let n = relay.next_record_to_module(&mut out).unwrap();
    module_record::decode(records::payload(&out[..n]).unwrap()).unwrap()
}

/// The module's answer as the ground station's decoder reports it, and its JSON body.
fn decoded(answer: KeyAnswer) -> String {
    let mut payload = [0u8; module_record::MAX_PAYLOAD_BYTES];
    let n = module_record::encode(&ModuleRecord::KeyAnswer(answer), &mut payload).unwrap();
    let mut framed = [0u8; 64];
    let bytes = frame(&payload[..n], &mut framed).unwrap();
    let events: serde_json::Value =
        serde_json::from_str(&StreamDecoder::new().push(bytes)).unwrap();
    events[0]["KeyAnswer"].to_string()
}

#[test]
fn a_proposal_reaches_the_module_and_its_answer_decodes() {
    let framed = propose_module_phrase("  tr0ub4dor and 3 ").unwrap();
    let key = LinkKey::from_phrase("tr0ub4dor and 3");
    assert_eq!(at_module(&framed), ModuleRecord::ProposeKey(key.to_bytes()));
    assert_eq!(
        phrase_fingerprint("tr0ub4dor and 3").unwrap(),
        key.fingerprint().to_string()
    );
    assert!(
        propose_module_phrase("   ").is_err(),
        "an empty phrase is no proposal"
    );

    let mut keys = PhoneKeys::new(5);
    let mut link_key = None;
    let mut commands = Commands::default();
    let outcome = keys
        .on_record(&at_module(&framed), &mut link_key, &mut commands)
        .unwrap();
    let json = decoded(outcome.answer);
    let back: KeyAnswer = serde_json::from_str(&json).unwrap();
    assert_eq!(back.outcome, KeyOutcome::AwaitingConfirmation);
    assert_eq!(back.fingerprint, Some(key.fingerprint().0));
}

#[test]
fn a_phone_that_knows_the_phrase_sets_the_module_phrase_after_one_refusal() {
    let old = LinkKey::from_phrase("correct horse battery staple");
    let new = LinkKey::from_phrase("tr0ub4dor and 3");
    let mut phone = Phone::new("correct horse battery staple").unwrap();
    let mut keys = PhoneKeys::new(0xABCD);
    let mut link_key = Some(old);
    let mut commands = Commands::default();

    let first = phone.sign_module_phrase("tr0ub4dor and 3").unwrap();
    let refused = keys
        .on_record(&at_module(&first), &mut link_key, &mut commands)
        .unwrap();
    assert_eq!(
        refused.answer.outcome,
        KeyOutcome::Refused(KeyRefusal::NotAuthenticated)
    );
    let again = phone.on_module_answer(&decoded(refused.answer));
    assert!(!again.is_empty(), "signed again with the module's session");
    let applied = keys
        .on_record(&at_module(&again), &mut link_key, &mut commands)
        .unwrap();
    assert_eq!(applied.answer.outcome, KeyOutcome::Applied);
    assert!(applied.changed);
    assert_eq!(link_key, Some(new));
    assert!(phone.on_module_answer(&decoded(applied.answer)).is_empty());

    // A phone with another phrase stops after its one retry.
    let mut stranger = Phone::new("guess").unwrap();
    let mut link_key = Some(old);
    let first = stranger.sign_module_phrase("mine now").unwrap();
    let answer = keys
        .on_record(&at_module(&first), &mut link_key, &mut commands)
        .unwrap()
        .answer;
    let retry = stranger.on_module_answer(&decoded(answer));
    let answer = keys
        .on_record(&at_module(&retry), &mut link_key, &mut commands)
        .unwrap()
        .answer;
    assert_eq!(
        answer.outcome,
        KeyOutcome::Refused(KeyRefusal::NotAuthenticated)
    );
    assert!(stranger.on_module_answer(&decoded(answer)).is_empty());
    assert_eq!(link_key, Some(old));
}
