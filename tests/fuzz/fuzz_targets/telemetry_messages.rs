//! The telemetry stream's framing and messages: bytes into `MessageReader` (COBS deframing,
//! CRC, postcard), any payload through `framing::frame` and the `Deframer`, and through the
//! flight side's `decode_change`.
//!
//! Invariants: every decoded message re-encodes into a frame that decodes to the same bytes
//! again (compared as encodings: a NaN float is not equal to itself); a framed payload always
//! comes back unchanged and contains no delimiter inside; `decode_change` reads a payload as
//! `decode_payload` does when that is a setting change (plain or signed), else not at all.
#![no_main]

use libfuzzer_sys::fuzz_target;
use taulink_fuzz::Input;
use telemetry::framing::{Deframed, Deframer, frame, framed_len};
use telemetry::messages::{
    Decoded, FRAMED_MAX_BYTES, MESSAGE_MAX_BYTES, Message, MessageReader, decode_change,
    decode_payload, encode_message,
};

fuzz_target!(|data: &[u8]| {
    let mut reader = MessageReader::new();
    for &byte in data {
        if let Some(Decoded::Message(message)) = reader.push(byte) {
            let mut encoded = [0u8; FRAMED_MAX_BYTES];
            let n = encode_message(&message, &mut encoded)
                .expect("a decoded message encodes")
                .len();
            let mut again = MessageReader::new();
            let back: Vec<_> = encoded[..n].iter().filter_map(|&b| again.push(b)).collect();
            let [Decoded::Message(copy)] = back[..] else {
                panic!("re-encoded message did not decode: {back:?}");
            };
            let mut encoded_again = [0u8; FRAMED_MAX_BYTES];
            let m = encode_message(&copy, &mut encoded_again)
                .expect("encodes")
                .len();
            assert_eq!(encoded[..n], encoded_again[..m]);
        }
    }

    // Framing round trip of an arbitrary payload up to the largest message.
    let mut input = Input::new(data);
    let payload = input.chunk(MESSAGE_MAX_BYTES * 2);
    let mut out = vec![0u8; framed_len(payload.len())];
    let n = frame(payload, &mut out)
        .expect("framed_len is enough")
        .len();
    assert_eq!(out[n - 1], 0);
    assert!(!out[..n - 1].contains(&0));
    let mut deframer = Deframer::<{ MESSAGE_MAX_BYTES * 2 + 8 }>::new();
    let outcomes: Vec<_> = out[..n].iter().filter_map(|&b| deframer.push(b)).collect();
    assert_eq!(
        outcomes,
        vec![Deframed::Frame {
            payload_len: payload.len()
        }]
    );
    assert_eq!(deframer.payload(), payload);

    // The flight side's reading of the same payload.
    let change = decode_payload(payload)
        .filter(|m| matches!(m, Message::SettingChange(_) | Message::SignedChange(_)));
    assert_eq!(decode_change(payload), change);
});
