//! The streaming CRSF decoder: chunking, resynchronisation, rejections, and property tests
//! (arbitrary bytes never panic; round trips; a frame inside garbage split anywhere is found).

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

use proptest::prelude::*;
use taulink_handset::crsf::{Decoded, Decoder, Frame, Rejection};

const BATTERY: [u8; 12] = [
    0xC8, 0x0A, 0x08, 0x00, 0x6F, 0x00, 0x35, 0x00, 0x04, 0xD2, 0x50, 0xB8,
];
const PING: [u8; 6] = [0xC8, 0x04, 0x28, 0x00, 0xEA, 0x54];

fn frames(decoded: &[Decoded]) -> Vec<Frame> {
    decoded
        .iter()
        .filter_map(|d| match d {
            Decoded::Frame(f) => Some(f.clone()),
            Decoded::Rejected(_) => None,
        })
        .collect()
}

fn encode(frame: &Frame) -> Vec<u8> {
    let mut out = [0u8; 64];
    let n = frame.encode(&mut out).unwrap().len();
    out[..n].to_vec()
}

#[test]
fn byte_by_byte_and_whole() {
    let stream: Vec<u8> = [&BATTERY[..], &PING[..]].concat();
    let mut whole = Decoder::new();
    let from_whole: Vec<Decoded> = whole.feed(&stream).collect();
    let mut single = Decoder::new();
    let from_single: Vec<Decoded> = stream
        .iter()
        .flat_map(|b| single.feed(core::slice::from_ref(b)).collect::<Vec<_>>())
        .collect();
    assert_eq!(from_whole, from_single);
    let got = frames(&from_whole);
    assert_eq!(got.len(), 2);
    assert_eq!(got[0].frame_type, 0x08);
    assert_eq!(got[1].frame_type, 0x28);
    assert_eq!(whole.stats().frames, 2);
    assert_eq!(whole.pending_len(), 0);
}

#[test]
fn corrupted_crc_is_rejected_and_next_frame_survives() {
    let mut bad = BATTERY;
    bad[5] ^= 0x01;
    let stream: Vec<u8> = [&bad[..], &PING[..]].concat();
    let mut decoder = Decoder::new();
    let decoded: Vec<Decoded> = decoder.feed(&stream).collect();
    assert_eq!(
        decoded[0],
        Decoded::Rejected(Rejection::CrcMismatch {
            computed: 0x20,
            received: 0xB8
        })
    );
    let got = frames(&decoded);
    assert_eq!(got.len(), 1);
    assert_eq!(encode(&got[0]), PING);
}

#[test]
fn frame_hidden_behind_a_false_start_is_found() {
    // 0xC8 0x30 claims a 50-byte frame; the real ping follows inside those 50 bytes. The
    // false candidate fails its CRC once complete and the decoder rescans from byte 1.
    let mut stream = vec![0xC8, 0x30];
    stream.extend_from_slice(&PING);
    stream.extend(core::iter::repeat_n(0x55, 60));
    let mut decoder = Decoder::new();
    let got = frames(&decoder.feed(&stream).collect::<Vec<_>>());
    assert_eq!(got.len(), 1);
    assert_eq!(encode(&got[0]), PING);
}

#[test]
fn bad_length_is_an_outcome() {
    let mut decoder = Decoder::new();
    let decoded: Vec<Decoded> = decoder.feed(&[0xEE, 0x01, 0xEE, 0x40]).collect();
    assert_eq!(
        decoded,
        vec![
            Decoded::Rejected(Rejection::BadLength { length: 0x01 }),
            Decoded::Rejected(Rejection::BadLength { length: 0x40 }),
        ]
    );
    assert_eq!(decoder.stats().rejected, 2);
}

#[test]
fn idle_gives_up_a_false_start() {
    // A false start claiming 20 bytes, then the line goes quiet after a complete ping.
    let stream: Vec<u8> = [&[0xEE, 0x14, 0x01][..], &PING[..]].concat();
    let mut decoder = Decoder::new();
    assert!(decoder.feed(&stream).next().is_none());
    assert_eq!(decoder.pending_len(), 9);
    let decoded: Vec<Decoded> = decoder.idle().collect();
    assert_eq!(
        decoded[0],
        Decoded::Rejected(Rejection::Truncated { held: 9 })
    );
    assert_eq!(frames(&decoded).len(), 1);
    assert_eq!(decoder.pending_len(), 0);
}

#[test]
fn garbage_is_skipped_and_counted() {
    let mut decoder = Decoder::new();
    let stream: Vec<u8> = [&[0x00, 0x11, 0x22][..], &PING[..]].concat();
    assert_eq!(frames(&decoder.feed(&stream).collect::<Vec<_>>()).len(), 1);
    assert_eq!(decoder.stats().skipped_bytes, 3);
}

#[test]
fn dropped_iterator_reports_unconsumed_bytes() {
    let stream: Vec<u8> = [&BATTERY[..], &PING[..]].concat();
    let mut decoder = Decoder::new();
    let mut feed = decoder.feed(&stream);
    assert!(matches!(feed.next(), Some(Decoded::Frame(_))));
    assert_eq!(feed.unconsumed(), &PING[..]);
}

fn arbitrary_frame() -> impl Strategy<Value = Frame> {
    (
        prop::sample::select(vec![0xC8u8, 0xEA, 0xEC, 0xEE]),
        any::<u8>(),
        prop::collection::vec(any::<u8>(), 0..=60),
    )
        .prop_map(|(address, frame_type, payload)| {
            Frame::new(address, frame_type, &payload).unwrap()
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn arbitrary_bytes_never_panic_and_stay_bounded(
        chunks in prop::collection::vec(prop::collection::vec(any::<u8>(), 0..80), 0..12)
    ) {
        let mut decoder = Decoder::new();
        for chunk in &chunks {
            for decoded in decoder.feed(chunk) {
                if let Decoded::Frame(frame) = decoded {
                    // Whatever comes out is a valid frame that re-encodes within 64 bytes.
                    prop_assert!(frame.wire_len() <= 64);
                }
            }
            prop_assert!(decoder.pending_len() < 64);
        }
    }

    #[test]
    fn encode_decode_round_trip(frame in arbitrary_frame()) {
        let bytes = encode(&frame);
        let mut decoder = Decoder::new();
        let got = frames(&decoder.feed(&bytes).collect::<Vec<_>>());
        prop_assert_eq!(got, vec![frame]);
    }

    /// The frame is delivered unless a false start in the garbage happens to pass its CRC
    /// (odds 1/256 per overlapping candidate) and so swallows the frame's first bytes; then
    /// that delivered frame must overlap the real one.
    #[test]
    fn frame_in_garbage_split_anywhere_is_found(
        frame in arbitrary_frame(),
        before in prop::collection::vec(any::<u8>(), 0..70),
        after in prop::collection::vec(any::<u8>(), 0..70),
    ) {
        let bytes = encode(&frame);
        let stream: Vec<u8> = [&before[..], &bytes[..], &after[..]].concat();
        for split in 0..=stream.len() {
            let mut decoder = Decoder::new();
            let (head, tail) = stream.split_at(split);
            let mut decoded: Vec<Decoded> = decoder.feed(head).collect();
            decoded.extend(decoder.feed(tail));
            decoded.extend(decoder.idle());
            prop_assert_eq!(decoder.pending_len(), 0);
            let got = frames(&decoded);
            if !got.contains(&frame) {
                let start = before.len();
                let swallowed = got.iter().any(|g| {
                    let g = encode(g);
                    (0..start).any(|at| stream[at..].starts_with(&g) && at + g.len() > start)
                });
                prop_assert!(swallowed, "split {}: {:?}", split, decoded);
            }
        }
    }
}
