//! Transcript tests: real NAV-PVT captures, configuration frames checked against byte
//! strings published by others, garbage and chopped streams, ACK/NAK follow-up.

use super::config::{self, Configurator, Generation, Settings, Status};
use super::frame::{self, Parser, checksum};
use super::{FixType, Message, NavPvt};

fn hex(s: &str) -> Vec<u8> {
    let s: String = s.chars().filter(|c| !c.is_whitespace()).collect();
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap())
        .collect()
}

/// A receiver capture published by u-blox in ubxlib's decoder tests
/// (`gnss/test/u_gnss_dec_test.c`, NAV-PVT item 0), with the field values ubxlib decodes.
const UBXLIB_NAV_PVT: &str = "b56201075c00b0f3711ce707080b0c21
    20f7eb030000c2dffeff0301ea160c95
    f4ffbb8e201f5af70100a04401008f03
    000093050000f8fffffffbffffff1300
    00000900000000000000ac000000d67d
    d90076000000ee134f2f000000000000
    0000bc7f";

/// A second, independent capture (2026-09-30 04:46:10 UTC, 21 satellites, 3-D fix),
/// from a public gnss service's tests ("真机抓包", a real-receiver capture).
const SECOND_NAV_PVT: &str = "b56201075c00f85a7910ea07091e042e0a372700000022edbd230301ea15ea08
    9643254bbc0d543c00005f500000b4050000ec080000f4fffffffdffffffe9ffff
    ff0d000000b030c701d200000080a81201a90000005c414f2100000000000000001c47";

fn frames(bytes: &[u8]) -> Vec<Message> {
    let mut p = Parser::new();
    let mut out = Vec::new();
    p.feed(bytes, |f| out.push(Message::from_frame(&f)));
    out
}

fn pvt_of(m: &Message) -> NavPvt {
    match m {
        Message::NavPvt(p) => *p,
        other => panic!("not a NAV-PVT: {other:?}"),
    }
}

#[test]
fn ubxlib_capture_decodes_to_ubxlibs_values() {
    let bytes = hex(UBXLIB_NAV_PVT);
    assert_eq!(bytes.len(), 100);
    let msgs = frames(&bytes);
    assert_eq!(msgs.len(), 1);
    let p = pvt_of(&msgs[0]);
    assert_eq!(p.itow_ms, 477_230_000);
    assert_eq!(p.fix_type, FixType::Fix3D);
    assert_eq!(p.flags, 0x01);
    assert_eq!(p.num_sv, 22);
    assert_eq!(p.lon_e7, -748_276);
    assert_eq!(p.lat_e7, 522_227_387);
    assert_eq!(p.height_mm, 128_858);
    assert_eq!(p.h_msl_mm, 83_104);
    assert_eq!(p.h_acc_mm, 911);
    assert_eq!(p.v_acc_mm, 1427);
    assert_eq!(p.vel_ned_mmps, [-8, -5, 19]);
    assert_eq!(p.g_speed_mmps, 9);
    assert_eq!(p.head_mot_e5, 0);
    assert_eq!(p.s_acc_mmps, 172);
    assert_eq!(p.p_dop_e2, 118);
    assert!(p.has_3d_fix());
}

#[test]
fn second_capture_decodes() {
    let msgs = frames(&hex(SECOND_NAV_PVT));
    assert_eq!(msgs.len(), 1);
    let p = pvt_of(&msgs[0]);
    assert_eq!(p.fix_type, FixType::Fix3D);
    assert_eq!(p.num_sv, 21);
    assert!(p.has_3d_fix());
    // Guangzhou: about 23° N, 113° E.
    assert!((p.lat_e7 / 10_000_000 - 23).abs() <= 1, "{}", p.lat_e7);
    assert!((p.lon_e7 / 10_000_000 - 113).abs() <= 1, "{}", p.lon_e7);
}

#[test]
fn checksum_matches_published_config_frames() {
    // CFG-RATE 10 Hz and CFG-MSG NAV-PVT on, as printed in many public u-blox drivers.
    let m8 = config::acked_messages(Generation::M8, &Settings::default());
    assert_eq!(
        m8[1].as_slice(),
        [
            0xB5, 0x62, 0x06, 0x08, 0x06, 0x00, 0x64, 0x00, 0x01, 0x00, 0x01, 0x00, 0x7A, 0x12
        ]
    );
    assert_eq!(
        m8[2].as_slice(),
        [
            0xB5, 0x62, 0x06, 0x01, 0x03, 0x00, 0x01, 0x07, 0x01, 0x13, 0x51
        ]
    );
}

#[test]
fn valset_holds_the_documented_keys() {
    let m10 = config::acked_messages(Generation::M9M10, &Settings::default());
    assert_eq!(m10.len(), 1);
    let f = frames(&m10[0]);
    assert_eq!(
        f,
        vec![Message::Other {
            class: 0x06,
            id: 0x8A
        }]
    );
    let bytes = m10[0].as_slice();
    let payload = &bytes[6..bytes.len() - 2];
    assert_eq!(&payload[..4], &[0, 1, 0, 0]);
    // NAV-PVT on UART1 every solution, airborne 2 g, 100 ms.
    let find = |key: u32| {
        payload
            .windows(4)
            .position(|w| w == key.to_le_bytes())
            .map(|i| i + 4)
            .unwrap()
    };
    assert_eq!(payload[find(config::KEY_MSGOUT_NAV_PVT_UART1)], 1);
    assert_eq!(payload[find(config::KEY_NAVSPG_DYNMODEL)], 7);
    assert_eq!(payload[find(config::KEY_UART1OUTPROT_NMEA)], 0);
    let at = find(config::KEY_RATE_MEAS);
    assert_eq!(&payload[at..at + 2], &100u16.to_le_bytes());
    let baud = config::baud_message(Generation::M9M10, &Settings::default());
    assert_eq!(&baud[14..18], &115_200u32.to_le_bytes());
}

#[test]
fn frames_survive_garbage_false_headers_and_chopping() {
    let pvt = hex(UBXLIB_NAV_PVT);
    let pvt2 = hex(SECOND_NAV_PVT);
    let ack = frame::encode(0x05, 0x01, &[0x06, 0x8A]).unwrap();
    let mut stream = Vec::new();
    stream.extend_from_slice(b"$GPGGA,garbage*00\r\n\xB5\xB5");
    // A false header announcing a NAV-PVT: the real frame that follows sits inside its
    // "payload" and must still come out after the false checksum fails.
    stream.extend_from_slice(&[0xB5, 0x62, 0x01, 0x07, 0x5C, 0x00, 0x11]);
    stream.extend_from_slice(&pvt);
    // An oversize length.
    stream.extend_from_slice(&[0xB5, 0x62, 0x01, 0x07, 0xFF, 0xFF]);
    stream.extend_from_slice(&ack);
    // A corrupted copy (bad checksum) followed by a good one.
    let mut bad = pvt2.clone();
    bad[40] ^= 0x10;
    stream.extend_from_slice(&bad);
    stream.extend_from_slice(&pvt2);
    let mut p = Parser::new();
    let mut got = Vec::new();
    // Chopped into odd-sized pieces as a UART DMA would deliver them.
    for chunk in stream.chunks(7) {
        p.feed(chunk, |f| got.push(Message::from_frame(&f)));
    }
    assert_eq!(got.len(), 3, "{got:?}");
    assert_eq!(pvt_of(&got[0]).num_sv, 22);
    assert_eq!(
        got[1],
        Message::Ack {
            class: 0x06,
            id: 0x8A
        }
    );
    assert_eq!(pvt_of(&got[2]).num_sv, 21);
    assert!(p.stats().checksum_errors >= 2);
    assert!(p.stats().oversize >= 1);
}

#[test]
fn never_panics_and_always_resynchronises_on_random_bytes() {
    let pvt = hex(UBXLIB_NAV_PVT);
    let mut state = 0x1234_5678_u32;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        state
    };
    let mut p = Parser::new();
    let mut good = 0;
    for round in 0..200 {
        // Random bytes biased towards sync bytes and plausible headers.
        for _ in 0..(next() % 300) {
            let b = match next() % 5 {
                0 => 0xB5,
                1 => 0x62,
                _ => next() as u8,
            };
            p.push(b, &mut |_| {});
        }
        p.feed(&pvt, |f| {
            if let Message::NavPvt(x) = Message::from_frame(&f) {
                assert_eq!(x.itow_ms, 477_230_000);
                good += 1;
            }
        });
        assert_eq!(good, round + 1, "frame lost after garbage in round {round}");
    }
}

#[test]
fn short_or_long_nav_pvt_payload_is_not_a_fix() {
    let f = frame::encode(0x01, 0x07, &[0u8; 91]).unwrap();
    assert_eq!(frames(&f), vec![Message::Other { class: 1, id: 7 }]);
    assert!(NavPvt::decode(&[0u8; 93]).is_err());
}

#[test]
fn checksum_is_fletcher_over_class_to_payload() {
    let bytes = hex(UBXLIB_NAV_PVT);
    assert_eq!(checksum(&bytes[2..98]), [0xbc, 0x7f]);
}

fn ack(id: u8) -> Message {
    Message::Ack { class: 0x06, id }
}

#[test]
fn configurator_walks_m8_sequence_on_acks() {
    let mut c = Configurator::new(Generation::M8, &Settings::default());
    let ids = [0x00, 0x08, 0x01, 0x24];
    let mut t = 0;
    for (i, id) in ids.into_iter().enumerate() {
        let sent = c.poll(t).unwrap().to_vec();
        assert_eq!(sent[3], id);
        assert_eq!(c.poll(t + 10), None, "waits for the answer");
        // Unrelated traffic and an ACK of something else change nothing.
        c.on_message(&Message::Other { class: 1, id: 7 });
        c.on_message(&ack(0x55));
        assert_eq!(c.status(), Status::Pending { step: i as u8 });
        c.on_message(&ack(id));
        t += 20;
    }
    assert_eq!(c.status(), Status::Done);
    assert_eq!(c.poll(t), None);
}

#[test]
fn configurator_retries_then_reports_no_answer() {
    let mut c = Configurator::new(Generation::M9M10, &Settings::default());
    let mut sends = 0;
    for t in (0..5000).step_by(10) {
        if c.poll(t).is_some() {
            sends += 1;
        }
    }
    assert_eq!(sends, Configurator::TRIES);
    assert_eq!(c.status(), Status::NoAnswer { id: 0x8A });
}

#[test]
fn configurator_stops_on_nak() {
    let mut c = Configurator::new(Generation::M9M10, &Settings::default());
    assert!(c.poll(0).is_some());
    c.on_message(&Message::Nak {
        class: 0x06,
        id: 0x8A,
    });
    assert_eq!(c.status(), Status::Refused { id: 0x8A });
    assert_eq!(c.poll(1000), None);
}

#[test]
fn encode_round_trips_the_captures() {
    for capture in [UBXLIB_NAV_PVT, SECOND_NAV_PVT] {
        let pvt = pvt_of(&frames(&hex(capture))[0]);
        assert_eq!(NavPvt::decode(&pvt.encode()), Ok(pvt));
    }
}
