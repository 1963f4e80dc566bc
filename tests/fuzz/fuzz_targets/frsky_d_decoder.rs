//! FrSky D frame decoder and hub parser under libFuzzer: frames re-encode and decode to
//! themselves; hub records from user data re-encode and parse to themselves.
#![no_main]

use libfuzzer_sys::fuzz_target;
use taulink_handset::frsky_d::{self, Decoder, Event, Frame, HubDecoder};

fuzz_target!(|data: &[u8]| {
    let mut decoder = Decoder::new();
    let mut hub = HubDecoder::new();
    decoder.push_all(data, |event| {
        if let Event::Frame(frame) = event {
            let mut out = [0u8; frsky_d::MAX_WIRE_LEN];
            let written = frame
                .encode(&mut out)
                .expect("decoded frame re-encodes")
                .len();
            taulink_fuzz::assert_decodes_to(
                &out[..written],
                Event::Frame(frame.clone()),
                |wire, sink| Decoder::new().push_all(wire, sink),
            );
            if let Frame::User(bytes) = frame {
                for byte in bytes {
                    if let Some(record) = hub.push(byte) {
                        assert!(record.id <= 0x3F);
                        let mut parser = HubDecoder::new();
                        let parsed: Vec<_> = record
                            .encode()
                            .iter()
                            .filter_map(|&b| parser.push(b))
                            .collect();
                        assert_eq!(parsed, vec![record]);
                    }
                }
            }
        }
    });
});
