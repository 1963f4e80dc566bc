//! Property tests for the module core's decoders of outside bytes added with the handset and
//! link integration: the link's telemetry stream (`records::Splitter`), records
//! (`records::decode`, the handset's `FlightState`), and the radio's CRSF bytes on the JR
//! line as the core takes them (`App::on_handset_bytes` / `on_handset_idle`). No input may
//! panic, and nothing already accepted may be lost. (PPM timing, the HM-10 stream, AT
//! replies, COBS, queues and settings records have theirs next to their code.)

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

use module_core::app::App;
use module_core::channels::ChannelFrame;
use module_core::handset::{FlightState, Handset, MAX_LINE_BURST};
use module_core::hm10::relay::MAX_RECORD_LEN;
use module_core::ports::{LinkPort, LinkStats};
use module_core::records::{self, Splitter};
use module_core::settings::{InputProtocol, OutputProtocol, Settings};
use proptest::prelude::*;
use taulink_handset::crsf::{self, Decoded, RcChannels, address};
use telemetry::messages::{Attitude, Battery, Message, encode_message};

fn battery(voltage_mv: u16, current_ca: i16) -> Message {
    Message::Battery(Battery {
        voltage_mv,
        current_ca,
        used_mah: 1,
        remaining_percent: 50,
    })
}

/// Splits `bytes` into chunks whose lengths cycle through `cuts`.
fn chunks<'a>(bytes: &'a [u8], cuts: &[usize]) -> Vec<&'a [u8]> {
    let mut out = Vec::new();
    let mut rest = bytes;
    let mut i = 0;
    while !rest.is_empty() {
        let n = cuts[i % cuts.len()].clamp(1, rest.len());
        let (head, tail) = rest.split_at(n);
        out.push(head);
        rest = tail;
        i += 1;
    }
    out
}

#[derive(Default)]
struct Link {
    channels: Vec<ChannelFrame>,
}

impl LinkPort for Link {
    fn send_channels(&mut self, channels: &ChannelFrame) {
        self.channels.push(*channels);
    }
    fn set_input_timeout_ms(&mut self, _timeout_ms: u16) {}
    fn can_send_record(&self) -> bool {
        false
    }
    fn send_record(&mut self, _record: &[u8]) {}
    fn stats(&self) -> LinkStats {
        LinkStats::default()
    }
    fn start_bind(&mut self) {}
}

fn crsf_app() -> App<Link, Handset> {
    let settings = Settings {
        input: InputProtocol::Crsf,
        output: OutputProtocol::Crsf,
        bind_id: 1,
        ..Settings::default()
    };
    App::new(settings, Link::default(), Handset::new(&settings), false).unwrap()
}

proptest! {
    #[test]
    fn stream_frames_survive_garbage_and_chunking(
        garbage_a in proptest::collection::vec(any::<u8>(), 0..200),
        garbage_b in proptest::collection::vec(any::<u8>(), 0..200),
        voltage_mv in any::<u16>(),
        current_ca in any::<i16>(),
        roll in any::<i16>(),
        cuts in proptest::collection::vec(1usize..40, 1..8),
    ) {
        let first = battery(voltage_mv, current_ca);
        let second = Message::Attitude(Attitude { roll_cdeg: roll, pitch_cdeg: 1, yaw_cdeg: -1 });
        let mut stream = garbage_a.clone();
        // A sender that joins a stream always starts with a delimiter.
        stream.push(0);
        let mut frame = [0u8; 64];
        let n = encode_message(&first, &mut frame).unwrap().len();
        stream.extend_from_slice(&frame[..n]);
        stream.extend_from_slice(&garbage_b);
        stream.push(0);
        let n = encode_message(&second, &mut frame).unwrap().len();
        stream.extend_from_slice(&frame[..n]);

        let mut splitter = Splitter::new();
        let mut got = Vec::new();
        let mut record = [0u8; MAX_RECORD_LEN];
        for chunk in chunks(&stream, &cuts) {
            for &b in chunk {
                if let Some(len) = splitter.push(b, &mut record).map(<[u8]>::len) {
                    // Every record the splitter hands out carries a valid CRC.
                    prop_assert!(records::payload(&record[..len]).is_ok());
                    if let Ok(m) = records::decode(&record[..len]) {
                        got.push(m);
                    }
                }
            }
        }
        // Both messages arrive, in order (garbage may add a frame with a lucky CRC).
        let at_first = got.iter().position(|m| *m == first);
        prop_assert!(at_first.is_some());
        prop_assert!(got[at_first.unwrap()..].contains(&second));
    }

    #[test]
    fn any_record_bytes_are_decoded_or_counted(
        records_in in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..80), 0..20),
    ) {
        let mut state = FlightState::new(7);
        let mut unknown = 0;
        for record in &records_in {
            if records::decode(record).is_err() {
                unknown += 1;
            }
            state.on_record(record);
        }
        prop_assert_eq!(state.unknown_records, unknown);
        let _ = state.report();
    }

    #[test]
    fn crsf_line_never_panics_and_replies_are_whole_frames(
        bursts in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..80), 1..30),
    ) {
        let mut app = crsf_app();
        let mut now_us = 10_000u64;
        for burst in &bursts {
            app.on_handset_bytes(now_us, burst);
            app.on_handset_idle(now_us + 20);
            let mut out = [0u8; MAX_LINE_BURST];
            let len = app.next_handset_bytes(now_us + 50, &mut out).len();
            prop_assert!(len <= MAX_LINE_BURST);
            let mut decoder = crsf::Decoder::new();
            let mut frames = 0;
            for decoded in decoder.feed(&out[..len]) {
                match decoded {
                    Decoded::Frame(_) => frames += 1,
                    Decoded::Rejected(r) => prop_assert!(false, "reply rejected: {:?}", r),
                }
            }
            prop_assert_eq!(len == 0, frames == 0);
            now_us += 4_000;
        }
    }

    #[test]
    fn channels_after_garbage_and_idle_are_delivered(
        garbage in proptest::collection::vec(any::<u8>(), 0..120),
        widths in proptest::collection::vec(988u16..=2012, 16),
        cut in 1usize..26,
    ) {
        let mut app = crsf_app();
        app.on_handset_bytes(1_000, &garbage);
        app.on_handset_idle(1_100);
        let channels = RcChannels::from_us(&widths.clone().try_into().unwrap());
        let mut frame = [0u8; 64];
        let n = crsf::Message::RcChannels(channels)
            .encode(address::TX_MODULE, &mut frame)
            .unwrap()
            .len();
        let (a, b) = frame[..n].split_at(cut.min(n));
        app.on_handset_bytes(5_000, a);
        app.on_handset_bytes(5_050, b);
        app.on_handset_idle(5_100);
        let sent = &app.link().channels;
        prop_assert_eq!(sent.last().map(|c| c.as_slice().to_vec()), Some(channels.ticks.to_vec()));
    }
}
