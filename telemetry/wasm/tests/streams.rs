//! The streams both decoders are checked on: `tests/streams.json` holds, for each stream, its
//! bytes (hex) in the chunks they arrive in and the JSON the Rust reader makes of every chunk.
//! This test rebuilds the file from the Rust side (the reference: `MessageReader` and
//! serde_json, not this crate's decoder) and fails when the committed file differs
//! (`TAULINK_BLESS=1` rewrites it); `ground-station/test/wasm-decoder.test.ts` feeds the
//! same chunks to the WebAssembly build and requires the same text, byte for byte.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

use module_core::hm10::Relay;
use module_core::hm10::relay::MAX_FRAME_LEN;
use module_core::records;
use telemetry::messages::{
    ArmState, Attitude, Axis, Battery, Decoded, FRAMED_MAX_BYTES, FlightMode, Gps, GpsFix, Home,
    LinkStats, Message, MessageReader, SettingChange, SysIdResult, encode_message,
};
use telemetry_wasm::stream::StreamDecoder;

const FIXTURE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/streams.json");

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

fn random_message(rng: &mut Rng) -> Message {
    let r = rng.next();
    let f = |rng: &mut Rng| f32::from_bits(rng.next() as u32 & 0x7F7F_FFFF) * 1e-30;
    match rng.below(8) {
        0 => Message::Attitude(Attitude {
            roll_cdeg: r as i16,
            pitch_cdeg: (r >> 16) as i16,
            yaw_cdeg: (r >> 32) as i16,
        }),
        1 => Message::Battery(Battery {
            voltage_mv: r as u16,
            current_ca: (r >> 16) as i16,
            used_mah: (r >> 32) as u16,
            remaining_percent: (r >> 48) as u8,
        }),
        2 => Message::LinkStats(LinkStats {
            uplink_rssi_dbm: r as i8,
            uplink_lq: (r >> 8) as u8,
            downlink_rssi_dbm: (r >> 16) as i8,
            downlink_lq: (r >> 24) as u8,
            rate_mode: (r >> 32) as u8 & 3,
            received: rng.next() as u32,
            missed: rng.next() as u32 >> (r % 32),
            failsafes: (r >> 40) as u16,
        }),
        3 => Message::FlightMode(FlightMode::ALL[(r % 8) as usize]),
        4 => Message::ArmState(ArmState {
            armed: r & 1 == 1,
            failsafe: r & 2 == 2,
            arming_blockers: (r >> 8) as u16,
        }),
        5 => Message::Gps(Gps {
            latitude_e7: r as i32,
            longitude_e7: (r >> 32) as i32,
            altitude_cm: rng.next() as i32,
            ground_speed_cm_s: (r >> 7) as u16,
            course_cdeg: (r >> 23) as u16,
            satellites: (r >> 50) as u8,
            fix: [GpsFix::None, GpsFix::Fix2d, GpsFix::Fix3d][(r % 3) as usize],
        }),
        6 => Message::SysIdResult(SysIdResult {
            axis: [Axis::Roll, Axis::Pitch, Axis::Yaw][(r % 3) as usize],
            beta1: f(rng) * 1e30,
            beta2: f(rng),
            tau_s: (r % 1000) as f32 / 7.0,
            noise: f(rng) * 1e20,
        }),
        _ => Message::SettingChange(SettingChange {
            id: r as u16,
            value: (r >> 16) as i32,
        }),
    }
}

fn framed(m: &Message) -> Vec<u8> {
    let mut buf = [0u8; FRAMED_MAX_BYTES];
    let n = encode_message(m, &mut buf).unwrap().len();
    buf[..n].to_vec()
}

/// Splits `bytes` into chunks of 1..=max bytes.
fn chunked(bytes: &[u8], max: u64, rng: &mut Rng) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    let mut rest = bytes;
    while !rest.is_empty() {
        let n = (1 + rng.below(max) as usize).min(rest.len());
        out.push(rest[..n].to_vec());
        rest = &rest[n..];
    }
    out
}

/// The phone's stream of `messages` as the module's HM-10 relay sends it, in BLE-sized
/// (≤ 20 byte) notifications.
fn through_relay(messages: &[Message], rng: &mut Rng) -> Vec<Vec<u8>> {
    let mut relay = Relay::new(true);
    let mut phone = Vec::new();
    for m in messages {
        let mut record = [0u8; 64];
        let len = records::encode(m, &mut record).unwrap().len();
        relay.on_link_record(&record[..len]);
        let mut frame = [0u8; MAX_FRAME_LEN];
        while let Some(n) = relay.next_frame_to_phone(&mut frame) {
            phone.extend_from_slice(&frame[..n]);
        }
    }
    chunked(&phone, 20, rng)
}

fn streams() -> Vec<(&'static str, Vec<Vec<u8>>)> {
    let mut rng = Rng(18);
    let messages: Vec<Message> = (0..250).map(|_| random_message(&mut rng)).collect();
    let whole: Vec<u8> = messages.iter().flat_map(framed).collect();
    // Damage: flipped bits, lost bytes, garbage and a join in the middle of a frame.
    let mut damaged = whole[7..].to_vec();
    for _ in 0..40 {
        let at = rng.below(damaged.len() as u64) as usize;
        match rng.below(3) {
            0 => damaged[at] ^= 1 << rng.below(8),
            1 => {
                damaged.remove(at);
            }
            _ => damaged.insert(at, rng.next() as u8),
        }
    }
    let garbage: Vec<u8> = (0..300).map(|_| rng.next() as u8).collect();
    let mut oversize = vec![0x01u8; 2 * FRAMED_MAX_BYTES];
    oversize.push(0);
    oversize.extend(framed(&messages[0]));
    vec![
        ("one frame per chunk", messages.iter().map(framed).collect()),
        ("serial reads", chunked(&whole, 64, &mut rng)),
        (
            "hm10 relay notifications",
            through_relay(&messages, &mut rng),
        ),
        ("damaged, joined mid-frame", chunked(&damaged, 20, &mut rng)),
        ("garbage", chunked(&garbage, 32, &mut rng)),
        ("oversize frame then a good one", vec![oversize]),
        // Appended after the random streams (their RNG draws stay the same).
        (
            "home",
            vec![framed(&Message::Home(Home {
                latitude_e7: 470_654_321,
                longitude_e7: -80_123_456,
                altitude_cm: 50_000,
                set: true,
            }))],
        ),
        // An older flight side's six-mode flight mode (retired message 3): the page ignores it.
        (
            "retired flight mode",
            vec![framed(&Message::RetiredFlightMode(1))],
        ),
    ]
}

/// The reference: the Rust reader directly, each message as serde_json renders it.
fn reference(chunks: &[Vec<u8>]) -> Vec<String> {
    let mut reader = MessageReader::new();
    chunks
        .iter()
        .map(|chunk| {
            let events: Vec<serde_json::Value> = chunk
                .iter()
                .filter_map(|&b| reader.push(b))
                .map(|d| match d {
                    Decoded::Message(m) => serde_json::to_value(m).unwrap(),
                    Decoded::Dropped => "Dropped".into(),
                })
                .collect();
            serde_json::Value::Array(events).to_string()
        })
        .collect()
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn fixture() -> String {
    let items: Vec<serde_json::Value> = streams()
        .into_iter()
        .map(|(name, chunks)| {
            let decoded = reference(&chunks);
            let hex: Vec<String> = chunks.iter().map(|c| hex(c)).collect();
            serde_json::json!({"name": name, "chunks": hex, "decoded": decoded})
        })
        .collect();
    serde_json::to_string_pretty(&items).unwrap() + "\n"
}

#[test]
fn committed_streams_are_the_rust_readers_output() {
    let want = fixture();
    if std::env::var_os("TAULINK_BLESS").is_some() {
        std::fs::write(FIXTURE, &want).unwrap();
    }
    let have = std::fs::read_to_string(FIXTURE).unwrap_or_default();
    assert!(
        have == want,
        "{FIXTURE} is stale: rerun with TAULINK_BLESS=1"
    );
}

#[test]
fn the_exported_decoder_matches_the_reader_on_every_stream() {
    for (name, chunks) in streams() {
        let mut decoder = StreamDecoder::new();
        let got: Vec<String> = chunks.iter().map(|c| decoder.push(c)).collect();
        assert_eq!(got, reference(&chunks), "{name}");
    }
}

#[test]
fn the_streams_exercise_messages_and_drops() {
    for (name, chunks) in streams() {
        let all = reference(&chunks).concat();
        let kind = |k: &str| all.matches(k).count();
        match name {
            "garbage" => assert!(kind("Dropped") > 0 && kind("{") == 0, "{name}"),
            "oversize frame then a good one" => {
                assert!(all.starts_with("[\"Dropped\",{\"Attitude\""), "{name}")
            }
            "home" => assert_eq!(
                all,
                "[{\"Home\":{\"altitude_cm\":50000,\"latitude_e7\":470654321,\"longitude_e7\":-80123456,\"set\":true}}]",
                "{name}: the JSON the ground station's `Home` type describes"
            ),
            "retired flight mode" => assert_eq!(
                all, "[{\"RetiredFlightMode\":1}]",
                "{name}: the JSON the ground station's model ignores"
            ),
            "damaged, joined mid-frame" => {
                assert!(kind("Dropped") >= 20 && kind("{\"") >= 180, "{name}")
            }
            _ => assert!(
                kind("\"SysIdResult\"") > 10 && kind("\"Gps\"") > 10,
                "{name}"
            ),
        }
    }
}
