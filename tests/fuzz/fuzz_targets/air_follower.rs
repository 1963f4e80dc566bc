//! Uplink air frames into the follower's state machine (`telemetry::link::core::Follower`),
//! each re-sealed with the link's keyed CRC so acquisition, tracking, failsafe and the
//! stream are all reached, interleaved with planning, sending, skipped slots and stream use.
//!
//! Invariants: a packet changes the channel output only when it decodes as an uplink, and
//! then the output is exactly the frame's channels; outputs stay 11-bit; every planned step
//! uses a grid channel, every planned downlink decodes under the bind ID and fits the rate's
//! frame; LQ stays a percentage; the received stream never outgrows its buffer.
#![no_main]

use libfuzzer_sys::fuzz_target;
use taulink_fuzz::{Input, seal};
use telemetry::channels::{CHANNEL_MAX, ChannelFormat, FailsafeValues};
use telemetry::frame::{
    CRC_BYTES, Frame, LinkReport, Received, StreamHeader, Uplink, decode, encode,
};
use telemetry::link::core::{Follower, STREAM_RX_BYTES, Step};
use telemetry::link::{Band, HOP_CHANNELS, LinkParams, LinkRx, RateMode};

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let params = params(&mut input);
    let failsafe_us = u64::from(input.u16()) * 16;
    let mut follower = Follower::new(params, FailsafeValues::default(), failsafe_us);
    let mut now = 0u64;
    let mut buf = [0u8; 64];
    while !input.is_empty() {
        now = now.saturating_add(u64::from(input.u16()));
        match input.u8() % 6 {
            0 | 1 => {
                let frame = if input.bool() {
                    seal(input.chunk(64), params.bind_id)
                } else {
                    uplink(&mut input, &params, &follower)
                };
                let rssi_dbm = i16::from(input.u8() as i8);
                let before = *follower.output();
                let updates = follower.updates();
                let outcome = LinkRx::Packet {
                    len: frame.len(),
                    rssi_dbm,
                };
                follower.on_received(outcome, &frame, now);
                if follower.updates() != updates {
                    let Received::Accepted(Frame::Uplink(up)) = decode(&frame, params.bind_id)
                    else {
                        panic!("a frame that is no uplink refreshed the outputs");
                    };
                    let mut expected = before;
                    assert!(up.channels_into(&mut expected));
                    assert_eq!(follower.output(), &expected);
                    assert!(!follower.in_failsafe());
                } else if !follower.in_failsafe() {
                    assert_eq!(
                        follower.output(),
                        &before,
                        "outputs moved without an update"
                    );
                }
            }
            2 => {
                let outcome = if input.bool() {
                    LinkRx::Corrupted
                } else {
                    LinkRx::Timeout
                };
                follower.on_received(outcome, &[], now);
            }
            3 | 4 => match follower.plan(now, &mut buf) {
                Step::Transmit { channel, len, .. } => {
                    assert!(usize::from(channel) < HOP_CHANNELS);
                    assert!(len <= params.rate.max_frame_bytes());
                    assert!(matches!(
                        decode(&buf[..len], params.bind_id),
                        Received::Accepted(Frame::Downlink(_))
                    ));
                    if input.bool() {
                        follower.on_sent();
                    } else {
                        follower.on_skipped();
                    }
                }
                Step::Listen {
                    channel,
                    from_us,
                    until_us,
                } => {
                    assert!(usize::from(channel) < HOP_CHANNELS);
                    assert!(until_us >= from_us || until_us >= now);
                }
                Step::Idle => follower.on_skipped(),
            },
            _ => {
                follower.downlink_stream.write(input.chunk(64));
                let mut out = [0u8; 64];
                follower.uplink_stream.read(&mut out);
            }
        }
        assert!(follower.output().iter().all(|&v| v <= CHANNEL_MAX));
        assert!(follower.uplink_lq() <= 100);
        assert!(follower.uplink_stream.available() <= STREAM_RX_BYTES);
        if let Some((_, channel)) = follower.tracked_slot() {
            assert!(usize::from(channel) < HOP_CHANNELS);
        }
        if let Some(report) = follower.remote_report() {
            assert!(report.lq_percent <= 100);
        }
    }
});

/// A well-formed uplink (slot mostly the one the follower expects, fuzzed fields, stream data)
/// with up to two fuzzed byte flips, sealed: the way deep into tracking, failsafe values and
/// the stream.
fn uplink(input: &mut Input, params: &LinkParams, follower: &Follower) -> Vec<u8> {
    let slot = match (input.u8(), follower.tracked_slot()) {
        (0..=191, Some((slot, _))) => slot,
        (0..=127, None) => 0,
        (_, _) => input.u8(),
    };
    let mut packed = [0u8; 22];
    let packed = &mut packed[..params.format.packed_bytes()];
    for byte in packed.iter_mut() {
        *byte = input.u8();
    }
    let report = input.bool().then(|| LinkReport {
        rssi_dbm: input.u8() as i8,
        lq_percent: input.u8() % 101,
    });
    let up = Uplink {
        slot,
        stream: StreamHeader {
            seq: input.u8(),
            ack: input.u8(),
        },
        report,
        save_failsafe: input.u8() < 32,
        input_lost: input.u8() < 16,
        format: params.format,
        packed_channels: packed,
        data: input.chunk(40),
    };
    let mut buf = [0u8; 128];
    let n = encode(&Frame::Uplink(up), params.bind_id, &mut buf).expect("fits 128 bytes");
    let body = &mut buf[..n - CRC_BYTES];
    for _ in 0..input.u8() % 3 {
        let at = usize::from(input.u8()) % body.len();
        body[at] ^= input.u8();
    }
    seal(body, params.bind_id)
}

/// Link parameters from the input: any bind ID, every band, rate, format and ratio.
pub fn params(input: &mut Input) -> LinkParams {
    LinkParams {
        bind_id: input.u32(),
        band: Band::from_code(input.u8() % 3).unwrap_or(Band::Mhz433),
        rate: RateMode::from_code(input.u8() % 5).unwrap_or(RateMode::F500),
        format: ChannelFormat::from_code(input.u8() % 3).unwrap_or(ChannelFormat::Full16),
        telemetry_ratio: 2 << (input.u8() % 7),
    }
}
