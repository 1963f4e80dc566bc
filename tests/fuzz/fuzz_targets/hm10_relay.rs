//! The HM-10 relay (`module_core::hm10::relay`): bytes from the phone side (COBS records,
//! `OK+CONN` / `OK+LOST` notifications, noise) and link records for the phone, in fuzzed
//! order.
//!
//! Invariants: every record handed to the flight side fits `MAX_RECORD_LEN` and survives a
//! COBS round trip; every frame sent to the phone is one COBS frame with its delimiter and
//! reads back, through a fresh `PhoneReader`, as one record of at most `MAX_RECORD_LEN`;
//! nothing goes to the phone while it is not connected; module-addressed records
//! (`telemetry::module_record`, marker first) go to the module and nothing else does, and what
//! decodes of them round-trips and, handed to the module's phone logic
//! (`phrase::PhoneAccess`), never changes the stored phrase while armed and changes it only
//! with an `Applied` answer; no answer ever carries a key but the `Granted` one, which comes
//! only after a `Response` (no key on BLE without the phrase's proof, issue 30).
#![no_main]

use libfuzzer_sys::fuzz_target;
use module_core::hm10::relay::{MAX_FRAME_LEN, MAX_RECORD_LEN, PhoneEvent, PhoneReader, Relay};
use module_core::phrase::PhoneAccess;
use module_core::settings::Settings;
use taulink_fuzz::Input;
use telemetry::change_auth::ChangeKey;
use telemetry::cobs;
use telemetry::link::LinkKey;
use telemetry::module_record::{self, Answer, ModuleRecord, Outcome};

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let mut relay = Relay::new(input.bool());
    let mut access = PhoneAccess::default();
    let mut settings = Settings::default();
    if input.bool() {
        // The derivation's bytes stand in for a phrase's (its slow derivation would make
        // every execution slow).
        settings.phrase_salt = [7; 8];
        settings.phrase_prs = Some([input.u8(); 32]);
    }
    let change_key = input
        .bool()
        .then(|| ChangeKey::from_link_key(&LinkKey::from_bytes([input.u8(); 16])));
    while !input.is_empty() {
        match input.u8() % 5 {
            0 => relay.on_phone_bytes(input.chunk(100)),
            1 => relay.on_link_record(input.chunk(80)),
            2 => {
                let mut out = [0u8; MAX_RECORD_LEN];
                if let Some(n) = relay.next_record_to_flight(&mut out) {
                    let record = &out[..n];
                    assert!(!module_record::is_module_payload(record));
                    let mut frame = [0u8; MAX_FRAME_LEN];
                    let m = cobs::encode(record, &mut frame).expect("a record encodes");
                    let len = cobs::decode_in_place(&mut frame[..m]).expect("and decodes");
                    assert_eq!(&frame[..len], record);
                }
            }
            3 => {
                let mut out = [0u8; MAX_RECORD_LEN];
                if let Some(n) = relay.next_record_to_module(&mut out) {
                    let record = &out[..n];
                    assert!(module_record::is_module_payload(record));
                    // The module checks the CRC first; fuzzed records rarely pass it, so the
                    // decoder also sees the bytes without it.
                    let body = module_core::records::payload(record).unwrap_or(record);
                    if let Ok(decoded) = module_record::decode(body) {
                        let mut again = [0u8; module_record::MAX_PAYLOAD_BYTES];
                        let k = module_record::encode(&decoded, &mut again).expect("re-encodes");
                        assert_eq!(module_record::decode(&again[..k]), Ok(decoded));
                        let armed = input.bool();
                        let before = settings.phrase_prs;
                        let seed = input.u8();
                        access.on_tick();
                        let reply =
                            access.on_record(&decoded, &mut settings, armed, change_key, || {
                                [seed; 32]
                            });
                        if let Some(reply) = reply {
                            let changed = settings.phrase_prs != before;
                            assert!(!changed || reply.changed);
                            if changed {
                                assert!(!armed, "the phrase changed while armed");
                                assert!(matches!(
                                    reply.reply,
                                    ModuleRecord::Answer(Answer {
                                        outcome: Outcome::Applied,
                                        ..
                                    })
                                ));
                            }
                            if let ModuleRecord::Granted(_) = reply.reply {
                                assert!(matches!(decoded, ModuleRecord::Response(_)));
                            }
                        } else {
                            assert_eq!(settings.phrase_prs, before);
                        }
                    }
                }
            }
            _ => {
                let connected = relay.is_connected();
                let mut out = [0u8; MAX_FRAME_LEN];
                if let Some(n) = relay.next_frame_to_phone(&mut out) {
                    assert!(connected, "a frame for a phone that is not connected");
                    assert!(n <= MAX_FRAME_LEN);
                    assert_eq!(out[n - 1], 0);
                    assert!(!out[..n - 1].contains(&0));
                    let mut reader = PhoneReader::new();
                    let mut records = 0;
                    for &byte in &out[..n] {
                        match reader.push_byte(byte) {
                            Some(PhoneEvent::Record(r)) => {
                                assert!(r.len() <= MAX_RECORD_LEN);
                                records += 1;
                            }
                            // A record may itself contain the text of a notification.
                            Some(PhoneEvent::Connected | PhoneEvent::Disconnected) => {}
                            None => {}
                            Some(other) => panic!("our own frame read back as {other:?}"),
                        }
                    }
                    assert!(records <= 1);
                }
            }
        }
    }
});
