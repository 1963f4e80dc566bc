//! Downlink air frames into the master's state machine (`telemetry::link::core::Master`),
//! each re-sealed with the link's keyed CRC, interleaved with planning, sending, skipped
//! slots, new channel values, save-failsafe requests and stream use.
//!
//! Invariants: every planned uplink decodes under the bind ID, carries the current slot and
//! exactly the channels last set (in the link's format), and fits the rate's frame; the
//! master only counts a downlink it can decode and that answers the current slot; LQ and the
//! remote report stay percentages; the received stream never outgrows its buffer.
#![no_main]

use libfuzzer_sys::fuzz_target;
use taulink_fuzz::{Input, seal};
use telemetry::channels::{ChannelFormat, Channels};
use telemetry::frame::{
    CRC_BYTES, Downlink, Frame, LinkReport, Received, StreamHeader, decode, encode,
};
use telemetry::link::core::{Master, STREAM_RX_BYTES, Step};
use telemetry::link::{Band, HOP_CHANNELS, LinkParams, LinkRx, RateMode};

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let params = LinkParams {
        bind_id: input.u32(),
        band: Band::from_code(input.u8() % 3).unwrap_or(Band::Mhz433),
        rate: RateMode::from_code(input.u8() % 5).unwrap_or(RateMode::F500),
        format: ChannelFormat::from_code(input.u8() % 3).unwrap_or(ChannelFormat::Full16),
        telemetry_ratio: 2 << (input.u8() % 7),
    };
    // As every real link is built (`LinkParams::new`, module-core's `link_params`): the
    // format the rate carries (F700 flies `Sticks16`; the others never do).
    let params = LinkParams {
        format: telemetry::link::bind::format_for(params.rate, params.format),
        ..params
    };
    let mut master = Master::new(params);
    let mut channels: Channels = [992; 16];
    let mut now = 0u64;
    let mut buf = [0u8; 64];
    while !input.is_empty() {
        now = now.saturating_add(u64::from(input.u16()));
        match input.u8() % 7 {
            0 | 1 => {
                let frame = if input.bool() {
                    seal(input.chunk(64), params.bind_id)
                } else {
                    downlink(&mut input, &params, &master)
                };
                let received = master.counters().received;
                let slot = master.slot();
                let outcome = LinkRx::Packet {
                    len: frame.len(),
                    rssi_dbm: i16::from(input.u8() as i8),
                };
                master.on_received(outcome, &frame, now);
                if master.counters().received != received {
                    let Received::Accepted(Frame::Downlink(down)) = decode(&frame, params.bind_id)
                    else {
                        panic!("the master counted a frame that is no downlink");
                    };
                    assert_eq!(down.slot, slot as u8);
                    assert_eq!(master.last_downlink_us(), Some(now));
                }
            }
            2 => {
                let outcome = if input.bool() {
                    LinkRx::Corrupted
                } else {
                    LinkRx::Timeout
                };
                master.on_received(outcome, &[], now);
            }
            3 | 4 => {
                let slot = master.slot();
                match master.plan(now, &mut buf) {
                    Step::Transmit { channel, len, .. } => {
                        assert!(usize::from(channel) < HOP_CHANNELS);
                        assert!(len <= params.rate.max_frame_bytes());
                        let Received::Accepted(Frame::Uplink(up)) =
                            decode(&buf[..len], params.bind_id)
                        else {
                            panic!("the master planned a frame that is no uplink");
                        };
                        assert_eq!(up.slot, slot as u8);
                        assert_eq!(up.format, params.format);
                        taulink_fuzz::assert_uplink_channels(&up, &channels);
                        if input.bool() {
                            master.on_sent();
                        } else {
                            master.on_skipped();
                        }
                    }
                    Step::Listen {
                        channel,
                        from_us,
                        until_us,
                    } => {
                        assert!(usize::from(channel) < HOP_CHANNELS);
                        assert!(from_us <= until_us);
                        if input.bool() {
                            master.finish_listen();
                        } else {
                            master.on_skipped();
                        }
                    }
                    Step::Idle => master.on_skipped(),
                }
            }
            5 => {
                for value in channels.iter_mut() {
                    *value = input.u16();
                }
                master.set_channels(&channels);
                if input.bool() {
                    master.request_save_failsafe();
                }
            }
            _ => {
                master.uplink_stream.write(input.chunk(64));
                let mut out = [0u8; 64];
                master.downlink_stream.read(&mut out);
            }
        }
        assert!(master.downlink_lq() <= 100);
        assert!(master.downlink_stream.available() <= STREAM_RX_BYTES);
        if let Some(report) = master.remote_report() {
            assert!(report.lq_percent <= 100);
        }
    }
});

/// A well-formed downlink (slot mostly the master's current one, fuzzed report and stream)
/// with up to two fuzzed byte flips, sealed.
fn downlink(input: &mut Input, params: &LinkParams, master: &Master) -> Vec<u8> {
    let slot = if input.u8() < 192 {
        master.slot() as u8
    } else {
        input.u8()
    };
    let report = input.bool().then(|| LinkReport {
        rssi_dbm: input.u8() as i8,
        lq_percent: input.u8() % 101,
    });
    let down = Downlink {
        slot,
        stream: StreamHeader {
            seq: input.u8(),
            ack: input.u8(),
        },
        report,
        data: input.chunk(50),
    };
    let mut buf = [0u8; 128];
    let n = encode(&Frame::Downlink(down), params.bind_id, &mut buf).expect("fits 128 bytes");
    let body = &mut buf[..n - CRC_BYTES];
    for _ in 0..input.u8() % 3 {
        let at = usize::from(input.u8()) % body.len();
        body[at] ^= input.u8();
    }
    seal(body, params.bind_id)
}
