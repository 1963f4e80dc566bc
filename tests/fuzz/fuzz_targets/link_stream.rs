//! The acknowledged telemetry byte stream (`telemetry::link::stream`) between a sender and a
//! receiver over a half-duplex link that loses frames and acks as the fuzzer decides, then
//! a receiver fed arbitrary (offset, data) frames as a forger would send them.
//!
//! Invariants: what the application reads is always a prefix of what was written (exactly
//! once, in order); the sender never releases bytes the receiver did not accept; for any
//! frames, the receiver's ack advances by exactly the bytes it accepted and its buffer stays
//! bounded.
#![no_main]

use libfuzzer_sys::fuzz_target;
use taulink_fuzz::Input;
use telemetry::link::stream::{StreamReceiver, StreamSender};

const N: usize = 256;

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let split = usize::from(input.u16()) % (data.len() + 1);
    let (link, forged) = data.split_at(split.min(data.len()));
    lossy_link(Input::new(link));
    forged_frames(Input::new(forged));
});

fn lossy_link(mut input: Input) {
    let mut sender = StreamSender::<N>::new();
    let mut receiver = StreamReceiver::<N>::new();
    let mut written = Vec::new();
    let mut read = Vec::new();
    while !input.is_empty() {
        let chunk = input.chunk(100);
        let taken = sender.write(chunk);
        written.extend_from_slice(&chunk[..taken]);
        let mut frame = [0u8; 64];
        let room = usize::from(input.u8()) % 65;
        let (seq, n) = sender.fill(&mut frame[..room]);
        let flags = input.u8();
        if flags & 1 == 0 {
            receiver.on_data(seq, &frame[..n]);
        }
        if flags & 2 == 0 {
            sender.on_ack(receiver.ack());
        }
        let mut out = [0u8; 64];
        let got = receiver.read(&mut out[..usize::from(flags >> 2)]);
        read.extend_from_slice(&out[..got]);
        assert!(read.len() <= written.len());
        assert_eq!(
            read[..],
            written[..read.len()],
            "the stream reordered or duplicated"
        );
        assert!(sender.acked_total() <= receiver.received_total());
    }
}

fn forged_frames(mut input: Input) {
    let mut receiver = StreamReceiver::<N>::new();
    while !input.is_empty() {
        let seq = input.u8();
        let data = input.chunk(64);
        let ack = receiver.ack();
        let total = receiver.received_total();
        let accepted = receiver.on_data(seq, data);
        assert!(accepted <= data.len());
        assert_eq!(receiver.ack(), ack.wrapping_add(accepted as u8));
        assert_eq!(receiver.received_total(), total + accepted as u64);
        assert!(receiver.available() <= N);
        if input.bool() {
            let mut out = [0u8; 64];
            receiver.read(&mut out);
        }
    }
}
