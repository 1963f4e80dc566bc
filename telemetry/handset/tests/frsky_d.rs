//! FrSky D hub frames byte-exact against openLRSng's `frskytx.h` output (frsky.json,
//! transcribed below) and worked frames composed from openLRSng `frskytx.h` and EdgeTX
//! `radio/src/telemetry/frsky_d.cpp` (link frame `7E FE A1 A2 RSSI TXRSSI 00 00 00 00 7E`,
//! user frame `7E FD n 00 b0…b5 7E`, hub records `5E id lo hi` with 0x5D escapes XOR 0x60,
//! as EdgeTX `parseTelemHubByte` undoes them); decoders and property tests.

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

use proptest::prelude::*;
use taulink_handset::HandsetTelemetry;
use taulink_handset::frsky_d::hub::{SenderConfig, id};
use taulink_handset::frsky_d::{
    self, Decoder, Event, Frame, HubDecoder, HubRecord, LinkFrame, Rejection, Sender,
};
use taulink_handset::report::{BatteryReport, FlightModeReport, LinkReport, VerticalReport};

fn hex(text: &str) -> Vec<u8> {
    let text: String = text.split_whitespace().collect();
    (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&text[i..i + 2], 16).unwrap())
        .collect()
}

fn encode(frame: &Frame) -> Vec<u8> {
    let mut out = [0u8; frsky_d::MAX_WIRE_LEN];
    let n = frame.encode(&mut out).unwrap().len();
    out[..n].to_vec()
}

fn decode(bytes: &[u8]) -> Vec<Event> {
    let mut decoder = Decoder::new();
    let mut events = Vec::new();
    decoder.push_all(bytes, |e| events.push(e));
    events
}

fn user(data: &[u8]) -> Frame {
    Frame::User(heapless::Vec::from_slice(data).unwrap())
}

fn check(frame: Frame, wire: &str) {
    let wire = hex(wire);
    assert_eq!(encode(&frame), wire, "{frame:?}");
    assert_eq!(decode(&wire), vec![Event::Frame(frame)]);
}

/// `frskySendFrame` link frames: A1, A2, RSSI = rx >> 1 (openLRSng halves its 0…255 RSSI), TX.
#[test]
fn openlrsng_link_frames() {
    // (a1, a2, rx, tx, bytes)
    let vectors: [(u8, u8, u8, u8, &str); 5] = [
        (0, 0, 0, 0, "7efe00000000000000007e"),
        (120, 33, 255, 200, "7efe78217fc8000000007e"),
        (126, 125, 252, 126, "7efe7d5e7d5d7d5e7d5e000000007e"),
        (255, 255, 128, 127, "7efeffff407f000000007e"),
        (10, 20, 30, 40, "7efe0a140f28000000007e"),
    ];
    for (a1, a2, rx, tx, bytes) in vectors {
        check(
            Frame::Link(LinkFrame {
                a1,
                a2,
                rssi: rx >> 1,
                tx_rssi: tx,
            }),
            bytes,
        );
    }
}

/// User frames: openLRSng takes up to 6 queued bytes per frame and pads with 0x00.
#[test]
fn openlrsng_user_frames() {
    check(user(&hex("5e1022005e")), "7efd05005e1022005e007e");
    check(user(&hex("7e7d01")), "7efd03007d5e7d5d010000007e");
    let queued = hex("010203040506070809");
    let frames: Vec<Vec<u8>> = queued.chunks(6).map(|c| encode(&user(c))).collect();
    assert_eq!(
        frames,
        vec![hex("7efd06000102030405067e"), hex("7efd03000708090000007e")]
    );
}

#[test]
fn worked_frames() {
    check(
        Frame::Link(LinkFrame {
            a1: 0x8C,
            a2: 0x7E,
            rssi: 0x5A,
            tx_rssi: 0xB4,
        }),
        "7E FE 8C 7D 5E 5A B4 00 00 00 00 7E",
    );
    let fuel = HubRecord {
        id: id::FUEL,
        value: 80,
    };
    assert_eq!(fuel.encode().as_slice(), hex("5E 04 50 00"));
    check(user(&fuel.encode()), "7E FD 04 00 5E 04 50 00 00 00 7E");
}

#[test]
fn hub_records_by_hand() {
    // VFAS 11.10 V in high precision: 1110 + 2000 = 3110 = 0x0C26 → 5E 39 26 0C.
    assert_eq!(
        HubRecord::vfas_mv(11_104).encode().as_slice(),
        hex("5E 39 26 0C")
    );
    // Value 0x5E5D: low 0x5D → 5D 3D (0x5D ^ 0x60), high 0x5E → 5D 3E.
    let record = HubRecord {
        id: id::CURRENT,
        value: 0x5E5D,
    };
    let wire = record.encode();
    assert_eq!(wire.as_slice(), hex("5E 28 5D 3D 5D 3E"));
    let mut decoder = HubDecoder::new();
    let got: Vec<HubRecord> = wire.iter().filter_map(|&b| decoder.push(b)).collect();
    assert_eq!(got, vec![record]);
}

#[test]
fn hub_decoder_follows_edgetx() {
    let mut decoder = HubDecoder::new();
    // ID 0x40 is past FRSKY_LAST_ID: dropped; a 5E mid-record restarts.
    let stream = hex("5E 40 01 02 5E 04 50 5E 02 07 00");
    let got: Vec<HubRecord> = stream.iter().filter_map(|&b| decoder.push(b)).collect();
    assert_eq!(
        got,
        vec![HubRecord {
            id: id::TEMP1,
            value: 7
        }]
    );
    assert_eq!(decoder.dropped(), 1);
}

#[test]
fn decoder_rejections() {
    let events = decode(&hex(
        "7E FE 01 02 7E FC 00 00 00 00 00 00 00 00 7E FD 07 00 00 00 00 00 00 00 7E",
    ));
    assert_eq!(
        events,
        vec![
            Event::Rejected(Rejection::Truncated { held: 3 }),
            Event::Rejected(Rejection::UnknownType { frame_type: 0xFC }),
            Event::Rejected(Rejection::BadUserLength { length: 7 }),
        ]
    );
}

fn telemetry() -> HandsetTelemetry {
    HandsetTelemetry {
        link: Some(LinkReport {
            uplink_lq_percent: 97,
            downlink_lq_percent: 90,
            ..LinkReport::default()
        }),
        battery: Some(BatteryReport {
            voltage_mv: 11_104,
            current_ma: 5_260,
            used_capacity_mah: 0,
            remaining_percent: 64,
        }),
        flight_mode: Some(FlightModeReport {
            name: heapless::String::try_from("ANGLE").unwrap(),
            number: 2,
        }),
        ..HandsetTelemetry::default()
    }
}

#[test]
fn sender_paces_and_decodes_back() {
    let mut sender = Sender::new(SenderConfig::default());
    let mut line = Vec::new();
    let mut frames = 0;
    for now in (0..1_800_000u64).step_by(1_000) {
        if let Some(frame) = sender.next_frame(now, &telemetry()) {
            frames += 1;
            line.extend(encode(&frame));
        }
    }
    assert_eq!(frames, 60); // one per 30 ms
    let mut links = Vec::new();
    let mut hub = HubDecoder::new();
    let mut records = Vec::new();
    decode(&line).into_iter().for_each(|e| match e {
        Event::Frame(Frame::Link(link)) => links.push(link),
        Event::Frame(Frame::User(data)) => records.extend(data.iter().filter_map(|&b| hub.push(b))),
        Event::Rejected(r) => panic!("{r:?}"),
    });
    assert_eq!(links.len(), 10); // every 6th slot
    // A1 = 11.104 V · 255 / 13.2 V = 214.5 → 214; RSSI = downlink LQ 90; TX RSSI = uplink LQ.
    assert_eq!(
        links[0],
        LinkFrame {
            a1: 214,
            a2: 97,
            rssi: 90,
            tx_rssi: 97
        }
    );
    let value = |wanted: u8| records.iter().find(|r| r.id == wanted).unwrap().value;
    assert_eq!(value(id::VFAS), 3110);
    assert_eq!(value(id::CURRENT), 53);
    assert_eq!(value(id::FUEL), 64);
    assert_eq!(value(id::TEMP1), 2);
    assert!(records.len() >= 4 * 10, "{}", records.len());
}

#[test]
fn sender_without_link_sends_rssi_zero_link_frames_only() {
    let mut sender = Sender::new(SenderConfig::default());
    let down = HandsetTelemetry {
        link: None,
        ..telemetry()
    };
    for slot in 0..12u64 {
        let frame = sender.next_frame(slot * 30_000, &down).unwrap();
        assert_eq!(
            frame,
            Frame::Link(LinkFrame {
                a1: 214,
                a2: 0,
                rssi: 0,
                tx_rssi: 0
            })
        );
    }
}

#[test]
fn sender_without_hub_data_sends_link_frames() {
    let mut sender = Sender::new(SenderConfig::default());
    let bare = HandsetTelemetry {
        battery: None,
        flight_mode: None,
        ..telemetry()
    };
    for slot in 0..12u64 {
        let frame = sender.next_frame(slot * 30_000, &bare).unwrap();
        assert_eq!(
            frame,
            Frame::Link(LinkFrame {
                a1: 0,
                a2: 97,
                rssi: 90,
                tx_rssi: 97
            })
        );
    }
}

/// Everything the hub carries, a 3S pack included: more than five user frames per round.
fn full_telemetry() -> HandsetTelemetry {
    HandsetTelemetry {
        vertical: Some(VerticalReport {
            altitude_cm: -1_234,
            vario_cm_s: -56,
        }),
        cells: Some(3),
        ..telemetry()
    }
}

/// The hub stream (user-frame data, in order) of `slots` slots.
fn hub_stream(sender: &mut Sender, telemetry: &HandsetTelemetry, slots: u64) -> Vec<u8> {
    let mut stream = Vec::new();
    for slot in 0..slots {
        if let Some(Frame::User(data)) = sender.next_frame(slot * 30_000, telemetry) {
            stream.extend_from_slice(&data);
        }
    }
    stream
}

#[test]
fn sender_never_cuts_a_record() {
    // The link frame every sixth slot used to clear the queue, cutting the record in flight
    // (EdgeTX then drops it at the next 0x5E).
    let mut sender = Sender::new(SenderConfig::default());
    let stream = hub_stream(&mut sender, &full_telemetry(), 600);
    let starts = stream.iter().filter(|&&b| b == 0x5E).count();
    let mut hub = HubDecoder::new();
    let records = stream.iter().filter_map(|&b| hub.push(b)).count();
    assert!(records > 100, "{records}");
    // Every record started was completed, but perhaps the last one still queued.
    assert!(
        starts - records <= 1,
        "{starts} started, {records} complete"
    );
}

#[test]
fn sender_never_cuts_a_record_when_the_link_drops() {
    let mut sender = Sender::new(SenderConfig::default());
    let down = HandsetTelemetry {
        link: None,
        ..full_telemetry()
    };
    let mut stream = Vec::new();
    for slot in 0..400u64 {
        // The link comes and goes at odd moments.
        let telemetry = if slot % 7 == 3 || slot % 11 == 5 {
            &down
        } else {
            &full_telemetry()
        };
        if let Some(Frame::User(data)) = sender.next_frame(slot * 30_000, telemetry) {
            stream.extend_from_slice(&data);
        }
    }
    let starts = stream.iter().filter(|&&b| b == 0x5E).count();
    let mut hub = HubDecoder::new();
    let records = stream.iter().filter_map(|&b| hub.push(b)).count();
    assert!(records > 50, "{records}");
    assert!(
        starts - records <= 1,
        "{starts} started, {records} complete"
    );
}

/// EdgeTX `processHubPacket`, VOLTS_ID: index = bits 4–7, the 12-bit 1/500 V value's top
/// nibble in bits 0–3 and its low byte in bits 8–15. Returns (index, mV).
fn edgetx_cell(value: u16) -> (u16, u16) {
    let index = (value & 0x00F0) >> 4;
    let raw = ((value & 0xFF00) >> 8) + ((value & 0x000F) << 8);
    (index, raw * 2)
}

#[test]
fn cell_records_follow_edgetx() {
    // 4.2 V = 2100 · 2 mV = 0x834: low byte 0x34 in the high byte, top nibble 8 in bits 0–3.
    let record = HubRecord::cell(5, 4_200);
    assert_eq!(record.id, id::CELLS);
    assert_eq!(record.value, 0x3458);
    assert_eq!(edgetx_cell(record.value), (5, 4_200));
    // Odd millivolts go down to the 2 mV step; above 8.19 V saturates at 12 bits.
    assert_eq!(edgetx_cell(HubRecord::cell(0, 3_701).value), (0, 3_700));
    assert_eq!(edgetx_cell(HubRecord::cell(15, 9_000).value), (15, 8_190));
}

#[test]
fn sender_sends_every_cell_in_turn() {
    let mut sender = Sender::new(SenderConfig::default());
    let stream = hub_stream(&mut sender, &full_telemetry(), 300);
    let mut hub = HubDecoder::new();
    let cells: Vec<(u16, u16)> = stream
        .iter()
        .filter_map(|&b| hub.push(b))
        .filter(|r| r.id == id::CELLS)
        .map(|r| edgetx_cell(r.value))
        .collect();
    // 11.104 V over 3 cells = 3701 mV → 3700 in 2 mV steps, for each of cells 0, 1, 2.
    assert!(cells.len() > 20, "{}", cells.len());
    assert!(
        cells.iter().all(|&(i, mv)| i < 3 && mv == 3_700),
        "{cells:?}"
    );
    for index in 0..3 {
        assert!(
            cells.iter().filter(|c| c.0 == index).count() > 5,
            "{cells:?}"
        );
    }
}

fn arbitrary_frame() -> impl Strategy<Value = Frame> {
    prop_oneof![
        any::<[u8; 4]>().prop_map(|[a1, a2, rssi, tx_rssi]| Frame::Link(LinkFrame {
            a1,
            a2,
            rssi,
            tx_rssi
        })),
        prop::collection::vec(any::<u8>(), 0..=6).prop_map(|d| user(&d)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..300)) {
        let mut hub = HubDecoder::new();
        for event in decode(&bytes) {
            if let Event::Frame(Frame::User(data)) = event {
                prop_assert!(data.len() <= 6);
                data.iter().for_each(|&b| { hub.push(b); });
            }
        }
        for &b in &bytes {
            if let Some(record) = hub.push(b) {
                prop_assert!(record.id <= 0x3F);
            }
        }
    }

    #[test]
    fn frame_round_trip(frame in arbitrary_frame()) {
        let wire = encode(&frame);
        prop_assert!(wire.len() >= 11 && wire.len() <= frsky_d::MAX_WIRE_LEN);
        prop_assert_eq!(decode(&wire), vec![Event::Frame(frame)]);
    }

    #[test]
    fn hub_record_round_trip_in_garbage(
        record_id in 0u8..=0x3F,
        value in any::<u16>(),
        before in prop::collection::vec(any::<u8>(), 0..30),
    ) {
        let record = HubRecord { id: record_id, value };
        let stream: Vec<u8> = before.iter().copied().chain(record.encode()).collect();
        let mut hub = HubDecoder::new();
        let got: Vec<HubRecord> = stream.iter().filter_map(|&b| hub.push(b)).collect();
        prop_assert_eq!(got.last(), Some(&record));
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
            prop_assert!(events.contains(&Event::Frame(frame.clone())), "split {}", split);
        }
    }
}
