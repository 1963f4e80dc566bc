//! S.Port frames byte-exact against worked frames and openLRSng's output
//! (`testdata/openlrs/frsky.json`, transcribed below), the decoder, and property tests.
//!
//! The worked frames were composed from the frame layout and value IDs as EdgeTX parses them
//! (`radio/src/telemetry/frsky_sport.cpp`, `frsky_defs.h`: `7E physId 10 idLo idHi v0..v3
//! crc`, 0x7D/0x20 stuffing, the CRC an end-around-carry byte sum subtracted from 0xFF over the
//! unstuffed body), with the checksums recomputed by hand; the capture line is a public
//! Taranis S.Port log line.

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

use proptest::prelude::*;
use taulink_handset::sport::{self, Decoder, Event, Frame, Rejection, physical_id, value_id};

fn hex(text: &str) -> Vec<u8> {
    let text: String = text.split_whitespace().collect();
    (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&text[i..i + 2], 16).unwrap())
        .collect()
}

fn encode(frame: &Frame) -> Vec<u8> {
    let mut out = [0u8; sport::MAX_WIRE_LEN];
    let n = frame.encode(&mut out).unwrap().len();
    out[..n].to_vec()
}

fn decode(bytes: &[u8]) -> Vec<Event> {
    let mut decoder = Decoder::new();
    let mut events = Vec::new();
    decoder.push_all(bytes, |e| events.push(e));
    events
}

fn frames(events: &[Event]) -> Vec<Frame> {
    events
        .iter()
        .filter_map(|e| match e {
            Event::Frame(f) => Some(*f),
            _ => None,
        })
        .collect()
}

/// Encodes to exactly `wire` and decodes back.
fn check(frame: Frame, wire: &str) {
    let wire = hex(wire);
    assert_eq!(encode(&frame), wire, "{frame:?}");
    assert_eq!(decode(&wire), vec![Event::Frame(frame)]);
}

#[test]
fn worked_frames() {
    check(
        Frame::data(0x98, value_id::RSSI, 80),
        "7E 98 10 01 F1 50 00 00 00 AC",
    );
    check(
        Frame::data(0x98, value_id::RXBT, 0xD2),
        "7E 98 10 04 F1 D2 00 00 00 27",
    );
    check(
        Frame::data(0x1B, value_id::VFAS, 1110),
        "7E 1B 10 10 02 56 04 00 00 83",
    );
    check(
        Frame::data(0x1B, value_id::CURRENT, 53),
        "7E 1B 10 00 02 35 00 00 00 B8",
    );
    check(
        Frame::data(0x1B, value_id::FUEL, 80),
        "7E 1B 10 00 06 50 00 00 00 99",
    );
    check(
        Frame::data(0x1B, value_id::TMP1, 12),
        "7E 1B 10 00 04 0C 00 00 00 DF",
    );
    check(
        Frame::data(0x1B, value_id::TAULINK_LQ, 98),
        "7E 1B 10 00 51 62 00 00 00 3C",
    );
    check(
        Frame::data(0x98, value_id::VFR, 2),
        "7E 98 10 10 F0 02 00 00 00 EC",
    );
    // Stuffing: value 0x7E → 7D 5E; the CRC is over the unstuffed 0x7E.
    check(
        Frame::data(0x1B, value_id::VFAS, 0x7E),
        "7E 1B 10 10 02 7D 5E 00 00 00 5F",
    );
    // A public Taranis S.Port capture line (its CRC checks with EdgeTX's algorithm).
    assert_eq!(
        frames(&decode(&hex("7E 83 10 20 07 EA 00 00 00 DD"))).len(),
        1
    );
}

#[test]
fn hand_computed_checksum_and_stuffing() {
    // VFAS 16.80 V = 1680 = 0x0690: body 10 10 02 90 06 00 00.
    // Sum with end-around carry: 0x10+0x10+0x02+0x90+0x06 = 0xB8 (no carry) → CRC 0xFF−0xB8 = 0x47.
    check(
        Frame::data(0x98, value_id::VFAS, 1680),
        "7E 98 10 10 02 90 06 00 00 47",
    );
    // Value 0x7D7D (32 125): body 10 10 02 7D 7D 00 00, sum 0x10+0x10+0x02+0x7D = 0x9F,
    // +0x7D = 0x11C → 0x1C + 1 = 0x1D, CRC 0xFF−0x1D = 0xE2; both 0x7D go out as 7D 5D.
    check(
        Frame::data(0x98, value_id::VFAS, 0x7D7D),
        "7E 98 10 10 02 7D 5D 7D 5D 00 00 E2",
    );
    // A frame that folds to 0xFF with the CRC included.
    let frame = Frame::data(0x98, value_id::RSSI, 0x1234_5678);
    let mut all = frame.body().to_vec();
    all.push(frame.crc());
    assert_eq!(sport::checksum(&all), 0x00, "complement of a fold to 0xFF");
}

#[test]
fn physical_id_table() {
    let table =
        hex("00 A1 22 83 E4 45 C6 67 48 E9 6A CB AC 0D 8E 2F D0 71 F2 53 34 95 16 B7 98 39 BA 1B");
    for (id, &expected) in table.iter().enumerate() {
        assert_eq!(
            physical_id::with_parity(id as u8),
            Some(expected),
            "id {id}"
        );
    }
    assert_eq!(physical_id::with_parity(28), None);
    assert_eq!(physical_id::with_parity(24), Some(physical_id::RECEIVER));
}

/// openLRSng `frskytx.h` SmartPort slots (frsky.json): slot 0 SWR = profile + 1, slot 1 RSSI =
/// rssi·100/256 (200 → 78, 255 → 99, 127 → 49), slot 2 RxBt = A1, slot 3 A2, slot 4 a lone 0x7E.
#[test]
fn openlrsng_smartport_frames() {
    // (slot, a1, a2, rssi, profile, bytes)
    let vectors: [(u8, u32, u32, u32, u32, &str); 20] = [
        (0, 100, 50, 200, 0, "7e981005f101000000f7"),
        (1, 100, 50, 200, 0, "7e981001f14e000000ae"),
        (2, 100, 50, 200, 0, "7e981004f16400000095"),
        (3, 100, 50, 200, 0, "7e981003f132000000c8"),
        (4, 100, 50, 200, 0, "7e"),
        (0, 126, 125, 255, 3, "7e981005f104000000f4"),
        (1, 126, 125, 255, 3, "7e981001f16300000099"),
        (2, 126, 125, 255, 3, "7e981004f17d5e0000007b"),
        (3, 126, 125, 255, 3, "7e981003f17d5d0000007d5d"),
        (4, 126, 125, 255, 3, "7e"),
        (0, 0, 0, 0, 1, "7e981005f102000000f6"),
        (1, 0, 0, 0, 1, "7e981001f100000000fc"),
        (2, 0, 0, 0, 1, "7e981004f100000000f9"),
        (3, 0, 0, 0, 1, "7e981003f100000000fa"),
        (4, 0, 0, 0, 1, "7e"),
        (0, 255, 128, 127, 2, "7e981005f103000000f5"),
        (1, 255, 128, 127, 2, "7e981001f131000000cb"),
        (2, 255, 128, 127, 2, "7e981004f1ff000000f9"),
        (3, 255, 128, 127, 2, "7e981003f1800000007a"),
        (4, 255, 128, 127, 2, "7e"),
    ];
    for (slot, a1, a2, rssi, profile, bytes) in vectors {
        let frame = match slot {
            0 => Frame::data(0x98, value_id::SWR, profile + 1),
            1 => Frame::data(0x98, value_id::RSSI, rssi * 100 / 256),
            2 => Frame::data(0x98, value_id::RXBT, a1),
            3 => Frame::data(0x98, value_id::A2, a2),
            _ => {
                assert_eq!(hex(bytes), [sport::START]);
                continue;
            }
        };
        check(frame, bytes);
    }
}

#[test]
fn corrupt_frame_is_rejected_and_next_one_decodes() {
    let mut wire = hex("7E 98 10 01 F1 50 00 00 00 AD");
    wire.extend(hex("7E 98 10 01 F1 50 00 00 00 AC"));
    let events = decode(&wire);
    assert_eq!(
        events[0],
        Event::Rejected(Rejection::CrcMismatch {
            computed: 0xAC,
            received: 0xAD
        })
    );
    assert_eq!(frames(&events), vec![Frame::data(0x98, value_id::RSSI, 80)]);
}

#[test]
fn polls_and_restarts() {
    // Master polls 0x1B (no answer), then 0x98 answers; a frame cut short by 0x7E is reported.
    let wire = hex("7E 1B 7E 98 10 01 F1 7E 98 10 01 F1 50 00 00 00 AC");
    let events = decode(&wire);
    assert_eq!(events[0], Event::Poll { physical_id: 0x1B });
    assert_eq!(events[1], Event::Rejected(Rejection::Truncated { held: 3 }));
    assert_eq!(
        events[2],
        Event::Frame(Frame::data(0x98, value_id::RSSI, 80))
    );
    assert_eq!(events.len(), 3);
}

#[test]
fn escape_byte_as_physical_id_is_rejected() {
    // Found by the cargo-fuzz target: `7E 7D …` used to decode to a frame with physical ID
    // 0x7D, which the encoder (rightly) refuses to send.
    let events = decode(&hex(
        "7E 7D 10 01 F1 50 00 00 00 AC 7E 98 10 01 F1 50 00 00 00 AC",
    ));
    assert_eq!(events[0], Event::Rejected(Rejection::ReservedPhysicalId));
    assert_eq!(frames(&events), vec![Frame::data(0x98, value_id::RSSI, 80)]);
}

#[test]
fn reserved_physical_id_is_refused() {
    let mut out = [0u8; 18];
    assert_eq!(
        Frame::data(0x7E, 1, 1).encode(&mut out),
        Err(sport::Error::ReservedPhysicalId)
    );
    // Value 0x7E7E7E7E: body 10 10 02 7E 7E 7E 7E; sum 0x22, +7E = 0xA0, +7E = 0x11E → 0x1F,
    // +7E = 0x9D, +7E = 0x11B → 0x1C; CRC 0xE3. Wire: 7E 98, 3 plain, 4 × 2 stuffed, CRC = 14.
    let frame = Frame::data(0x98, value_id::VFAS, 0x7E7E_7E7E);
    assert_eq!(frame.crc(), 0xE3);
    assert_eq!(
        frame.encode(&mut out[..13]),
        Err(sport::Error::BufferTooSmall { needed: 14 })
    );
    assert_eq!(frame.encode(&mut out).map(<[u8]>::len), Ok(14));
}

fn arbitrary_frame() -> impl Strategy<Value = Frame> {
    (
        any::<u8>().prop_filter("not framing", |p| *p != 0x7E && *p != 0x7D),
        any::<u8>(),
        any::<u16>(),
        any::<u32>(),
    )
        .prop_map(|(physical_id, primitive, value_id, value)| Frame {
            physical_id,
            primitive,
            value_id,
            value,
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..300)) {
        for event in decode(&bytes) {
            if let Event::Frame(frame) = event {
                // Every delivered frame checks and re-encodes.
                let mut all = frame.body().to_vec();
                all.push(frame.crc());
                prop_assert_eq!(sport::checksum(&all), 0);
            }
        }
    }

    #[test]
    fn encode_decode_round_trip(frame in arbitrary_frame()) {
        let wire = encode(&frame);
        prop_assert!(wire.len() >= 10 && wire.len() <= sport::MAX_WIRE_LEN);
        prop_assert_eq!(decode(&wire), vec![Event::Frame(frame)]);
    }

    #[test]
    fn frame_in_garbage_split_anywhere_is_found(
        frame in arbitrary_frame(),
        before in prop::collection::vec(any::<u8>(), 0..40),
        after in prop::collection::vec(any::<u8>(), 0..40),
    ) {
        let stream: Vec<u8> = [&before[..], &encode(&frame)[..], &after[..]].concat();
        for split in 0..=stream.len() {
            let mut decoder = Decoder::new();
            let mut events = Vec::new();
            let (head, tail) = stream.split_at(split);
            decoder.push_all(head, |e| events.push(e));
            decoder.push_all(tail, |e| events.push(e));
            prop_assert!(frames(&events).contains(&frame), "split {}", split);
        }
    }
}
