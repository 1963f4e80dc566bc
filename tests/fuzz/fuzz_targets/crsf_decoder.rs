//! CRSF decoder under libFuzzer: the first byte picks a chunk size, the rest is the line. Every
//! delivered frame must re-encode within 64 bytes and decode again to itself, and every typed
//! message that decodes must re-encode to a frame that decodes to the same message (bytes a
//! decoder ignores, such as text after a NUL, may differ).
#![no_main]

use libfuzzer_sys::fuzz_target;
use taulink_handset::crsf::{Decoded, Decoder, Message};

fuzz_target!(|data: &[u8]| {
    let Some((&chunk, line)) = data.split_first() else {
        return;
    };
    let chunk = usize::from(chunk % 64) + 1;
    let mut decoder = Decoder::new();
    let mut frames = Vec::new();
    for piece in line.chunks(chunk) {
        for decoded in decoder.feed(piece) {
            if let Decoded::Frame(frame) = decoded {
                frames.push(frame);
            }
        }
        assert!(decoder.pending_len() < 64);
    }
    frames.extend(decoder.idle().filter_map(|d| match d {
        Decoded::Frame(frame) => Some(frame),
        Decoded::Rejected(_) => None,
    }));
    assert_eq!(decoder.pending_len(), 0);
    for frame in frames {
        let mut out = [0u8; 64];
        let written = frame
            .encode(&mut out)
            .expect("a decoded frame fits 64 bytes")
            .len();
        let again: Vec<Decoded> = Decoder::new().feed(&out[..written]).collect();
        assert_eq!(again, vec![Decoded::Frame(frame.clone())]);
        if let Ok(message) = Message::from_frame(&frame) {
            let rebuilt = message.to_frame(frame.address).expect("re-encodes");
            assert_eq!(Message::from_frame(&rebuilt), Ok(message));
        }
    }
});
