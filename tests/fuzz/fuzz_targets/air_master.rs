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
use taulink_fuzz::Input;
use taulink_fuzz::air::{self, Sealing};
use telemetry::channels::Channels;
use telemetry::frame::{Frame, Received, decode};
use telemetry::link::LinkParams;
use telemetry::link::core::{Master, Step};

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let params = air::params(&mut input, false);
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
                    taulink_fuzz::seal(input.chunk(64), params.bind_id)
                } else {
                    let slot = air::mostly(&mut input, master.slot() as u8);
                    let down = air::downlink(&mut input, slot, 50);
                    let sealing = Sealing::Crc {
                        bind_id: params.bind_id,
                    };
                    air::sealed(&mut input, &Frame::Downlink(down), sealing)
                };
                let received = master.counters().received;
                let slot = master.slot();
                master.on_received(air::packet(&mut input, &frame), &frame, now);
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
                master.on_received(air::nothing(&mut input), &[], now);
            }
            3 | 4 => {
                let slot = master.slot();
                let step = master.plan(now, &mut buf);
                air::assert_grid(&step);
                match step {
                    Step::Transmit { len, .. } => {
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
                    step => air::listen_or_idle(&mut input, &mut master, step),
                }
            }
            5 => air::new_channels(&mut input, &mut master, &mut channels),
            _ => air::use_master_streams(&mut input, &mut master),
        }
        air::assert_master(&master);
    }
});
