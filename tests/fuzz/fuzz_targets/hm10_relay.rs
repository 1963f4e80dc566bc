//! The HM-10 relay (`module_core::hm10::relay`): bytes from the phone side (COBS records,
//! `OK+CONN` / `OK+LOST` notifications, noise) and link records for the phone, in fuzzed
//! order.
//!
//! Invariants: every record handed to the flight side fits `MAX_RECORD_LEN` and survives a
//! COBS round trip; every frame sent to the phone is one COBS frame with its delimiter and
//! reads back, through a fresh `PhoneReader`, as one record of at most `MAX_RECORD_LEN`;
//! nothing goes to the phone while it is not connected.
#![no_main]

use libfuzzer_sys::fuzz_target;
use module_core::hm10::relay::{MAX_FRAME_LEN, MAX_RECORD_LEN, PhoneEvent, PhoneReader, Relay};
use taulink_fuzz::Input;
use telemetry::cobs;

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let mut relay = Relay::new(input.bool());
    while !input.is_empty() {
        match input.u8() % 4 {
            0 => relay.on_phone_bytes(input.chunk(100)),
            1 => relay.on_link_record(input.chunk(80)),
            2 => {
                let mut out = [0u8; MAX_RECORD_LEN];
                if let Some(n) = relay.next_record_to_flight(&mut out) {
                    let record = &out[..n];
                    let mut frame = [0u8; MAX_FRAME_LEN];
                    let m = cobs::encode(record, &mut frame).expect("a record encodes");
                    let len = cobs::decode_in_place(&mut frame[..m]).expect("and decodes");
                    assert_eq!(&frame[..len], record);
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
