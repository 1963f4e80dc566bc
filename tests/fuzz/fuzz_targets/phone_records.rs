//! The phone's records to and from the module (`telemetry::module_record`, version 2) and both
//! sides of their CPace exchange (`ModuleExchange`, `ModuleSession`, `PhoneSession`), fed a
//! true exchange on one phrase derivation whose records the input flips bytes in, and
//! fuzzed records.
//!
//! Invariants: every payload that decodes re-encodes to a payload that decodes to the same
//! record; a module takes a response, and a phone a grant, only as the other side made it
//! (any flipped byte is refused) — then the phone holds exactly the change key the module
//! sealed; a module session opens a phrase only as the phone sealed it, under a counter above
//! every one it took (a replay or an older counter is refused), and hands back exactly the
//! derivation the phone sealed; a fuzzed challenge share never panics the phone.
#![no_main]

use libfuzzer_sys::fuzz_target;
use taulink_fuzz::Input;
use telemetry::change_auth::ChangeKey;
use telemetry::link::{LinkKey, PhraseSecret};
use telemetry::module_record::{self, Answer, ModuleExchange, Outcome, PhoneSession, Refusal};

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let payload = input.chunk(120);
    if let Ok(record) = module_record::decode(payload) {
        let mut out = [0u8; module_record::MAX_PAYLOAD_BYTES];
        let n = module_record::encode(&record, &mut out).expect("a decoded record encodes");
        assert_eq!(module_record::decode(&out[..n]), Ok(record));
    }
    // The derivation's bytes stand in for a phrase's (the slow derivation is the phrase
    // module's to test): both sides hold the same, or the phone another.
    let secret = PhraseSecret {
        salt: [input.u8(); 8],
        prs: [input.u8() | 1; 32],
    };
    let phone_secret = if input.u8() < 32 {
        PhraseSecret {
            prs: [input.u8(); 32],
            ..secret
        }
    } else {
        secret
    };
    let same = phone_secret == secret;
    let module = ModuleExchange::new(&secret, &[input.u8(); 32]);
    let mut challenge = module.challenge();
    if input.u8() < 16 {
        // A fuzzed share: the phone answers only a valid element, never panics.
        for (b, s) in challenge.share.iter_mut().zip(input.bytes(32)) {
            *b = *s;
        }
        let _ = PhoneSession::respond_with(&phone_secret, &challenge, &[input.u8(); 32]);
        return;
    }
    let Some((mut phone, mut response)) =
        PhoneSession::respond_with(&phone_secret, &challenge, &[input.u8() | 2; 32])
    else {
        panic!("the phone refused a true challenge");
    };
    let flipped_response =
        flip(&mut input, &mut response.tag) | flip(&mut input, &mut response.share);
    let change_key = input
        .bool()
        .then(|| ChangeKey::from_link_key(&LinkKey::from_bytes([input.u8(); 16])));
    let Some((mut session, mut granted)) = module.respond(&response, change_key.as_ref()) else {
        assert!(!same || flipped_response, "a true response refused");
        return;
    };
    assert!(
        same && !flipped_response,
        "a response taken without the phrase"
    );
    let flipped_grant = flip(&mut input, &mut granted.tag);
    match phone.on_granted(&granted) {
        Ok(key) => {
            assert!(!flipped_grant, "a forged grant taken");
            assert_eq!(key, change_key);
        }
        Err(refusal) => {
            assert!(flipped_grant, "a true grant refused");
            assert_eq!(refusal, Refusal::NotAuthenticated);
        }
    }
    // New phrases: the phone's sealed derivation opens once, with a fresh counter.
    let mut highest = 0u32;
    while !input.is_empty() {
        let prs_sent = [input.u8(); 32];
        let Some(mut set) = phone.set_phrase_with(&PhraseSecret {
            prs: prs_sent,
            ..secret
        }) else {
            panic!("a granted phone seals no phrase");
        };
        let sealed_by_phone = set;
        let forged = flip(&mut input, &mut set.tag) | flip(&mut input, &mut set.sealed);
        if input.u8() < 32 {
            set.counter = input.u32();
        }
        let fresh = set.counter > highest;
        match session.open(&set) {
            Ok(prs) => {
                assert!(!forged && fresh && set.counter == sealed_by_phone.counter);
                assert_eq!(prs, prs_sent);
                highest = set.counter;
            }
            Err(Refusal::Replayed) => assert!(!forged && !fresh),
            Err(Refusal::NotAuthenticated) => {
                assert!(forged || set.counter != sealed_by_phone.counter)
            }
            Err(other) => panic!("refused as {other:?}"),
        }
        assert_eq!(session.highest(), highest);
        phone.on_answer(&Answer {
            outcome: Outcome::Applied,
            counter: session.highest(),
        });
    }
});

/// Flips one byte of `bytes` in one input in eight; whether it did.
fn flip(input: &mut Input, bytes: &mut [u8]) -> bool {
    if input.u8() >= 32 || bytes.is_empty() {
        return false;
    }
    let at = usize::from(input.u8()) % bytes.len();
    let mask = input.u8().max(1);
    bytes[at] ^= mask;
    true
}
