//! The module's telemetry records (`module_core::records`): the link's telemetry stream split
//! into records, as the module does before fanning them out to the handset and the phone.
//!
//! Invariants: every record the splitter hands out fits `MAX_RECORD_LEN` and passes its CRC;
//! put back on a stream (`to_stream`) it splits to the same record; a record that decodes to
//! a message is re-encoded from it to a record that decodes to the same encoding.
#![no_main]

use libfuzzer_sys::fuzz_target;
use module_core::hm10::relay::MAX_RECORD_LEN;
use module_core::records::{MAX_STREAM_FRAME_LEN, Splitter, decode, encode, payload, to_stream};

fuzz_target!(|data: &[u8]| {
    let mut splitter = Splitter::new();
    let mut record = [0u8; MAX_RECORD_LEN];
    for &byte in data {
        let Some(record) = splitter.push(byte, &mut record) else {
            continue;
        };
        assert!(payload(record).is_ok(), "a split record fails its CRC");
        let mut stream = [0u8; MAX_STREAM_FRAME_LEN];
        let m = to_stream(record, &mut stream)
            .expect("a record goes back on the stream")
            .len();
        let mut again = Splitter::new();
        let mut copy = [0u8; MAX_RECORD_LEN];
        let n = record.len();
        let back: Vec<usize> = stream[..m]
            .iter()
            .filter_map(|&b| again.push(b, &mut copy).map(<[u8]>::len))
            .collect();
        assert_eq!(back, vec![n]);
        assert_eq!(&copy[..n], record);
        if let Ok(message) = decode(record) {
            let mut out = [0u8; MAX_RECORD_LEN];
            let first = encode(&message, &mut out).expect("a decoded message encodes");
            let mut out2 = [0u8; MAX_RECORD_LEN];
            let decoded = decode(first).expect("and decodes");
            let second = encode(&decoded, &mut out2).expect("again");
            assert_eq!(first, second);
        }
    }
});
