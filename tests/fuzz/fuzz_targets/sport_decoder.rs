//! S.Port decoder under libFuzzer: every delivered frame checks, re-encodes and decodes again.
#![no_main]

use libfuzzer_sys::fuzz_target;
use taulink_handset::sport::{self, Decoder, Event};

fuzz_target!(|data: &[u8]| {
    let mut decoder = Decoder::new();
    decoder.push_all(data, |event| {
        if let Event::Frame(frame) = event {
            let mut out = [0u8; sport::MAX_WIRE_LEN];
            // Physical IDs 0x7D/0x7E cannot be produced by the decoder's framing.
            let written = frame
                .encode(&mut out)
                .expect("decoded frame re-encodes")
                .len();
            taulink_fuzz::assert_decodes_to(&out[..written], Event::Frame(frame), |wire, sink| {
                Decoder::new().push_all(wire, sink)
            });
        }
    });
});
