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
use taulink_fuzz::Input;
use taulink_fuzz::air::{self, Sealing};
use telemetry::channels::FailsafeValues;
use telemetry::frame::{Frame, Received, decode};
use telemetry::link::HOP_CHANNELS;
use telemetry::link::core::{Follower, Step};

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let params = air::params(&mut input, false);
    let failsafe_us = u64::from(input.u16()) * 16;
    let mut follower = Follower::new(params, FailsafeValues::default(), failsafe_us);
    let mut now = 0u64;
    let mut buf = [0u8; 64];
    while !input.is_empty() {
        now = now.saturating_add(u64::from(input.u16()));
        match input.u8() % 6 {
            0 | 1 => {
                let frame = if input.bool() {
                    taulink_fuzz::seal(input.chunk(64), params.bind_id)
                } else {
                    // A well-formed uplink, slot mostly the one the follower expects: the
                    // way deep into tracking, failsafe values and the stream.
                    let slot = air::uplink_slot(&mut input, follower.tracked_slot());
                    let mut packed = [0u8; 22];
                    let up = air::uplink(&mut input, params.format, slot, &mut packed);
                    let sealing = Sealing::Crc {
                        bind_id: params.bind_id,
                    };
                    air::sealed(&mut input, &Frame::Uplink(up), sealing)
                };
                let outcome = air::packet(&mut input, &frame);
                let before = *follower.output();
                let updates = follower.updates();
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
            2 => follower.on_received(air::nothing(&mut input), &[], now),
            3 | 4 => {
                let step = follower.plan(now, &mut buf);
                air::assert_grid(&step);
                match step {
                    Step::Transmit { len, .. } => {
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
                    step => air::follower_listen_or_idle(&mut follower, step, now),
                }
            }
            _ => air::use_follower_streams(&mut input, &mut follower),
        }
        air::assert_follower(&follower);
        if let Some((_, channel)) = follower.tracked_slot() {
            assert!(usize::from(channel) < HOP_CHANNELS);
        }
    }
});
