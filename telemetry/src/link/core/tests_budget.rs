//! Every frame either end builds fits its rate mode's frame budget (spec §4.1): every rate
//! mode × every channel format a link of that mode runs (`LinkParams::new`'s `format_for`) ×
//! keyed or not × with or without the master's report, with the stream full and empty.
//! Keyed 16-channel uplinks with the report were 33 bytes at L50 and F500 (32-byte frames)
//! until sealed frames without stream data dropped their seq byte (§12.7).

use super::follower::DEFAULT_FAILSAFE_US;
use super::tests::test_key;
use super::*;
use crate::channels::{ChannelFormat, FailsafeValues};
use crate::link::Band;
use crate::link::bind::LinkParams;
use crate::link::rate::RateMode;

const FORMATS: [ChannelFormat; 3] = [
    ChannelFormat::Full16,
    ChannelFormat::Compact8,
    ChannelFormat::Sticks16,
];

/// Uplinks a master of `params` builds over two telemetry cycles; (length, carries the
/// report) of each.
fn uplinks(params: LinkParams, keyed: bool, stream: bool) -> Vec<(usize, bool)> {
    let mut master = Master::new(params);
    if keyed {
        master = master.with_key(test_key(1));
    }
    let mut built = Vec::new();
    let mut buf = [0u8; 64];
    for slot in 0..4 * u32::from(params.telemetry_ratio) {
        if stream {
            // More than any frame carries, every slot: each uplink is as long as it gets.
            master.uplink_stream.write(&[0x5A; 64]);
        }
        match master.plan(u64::from(slot) * 10_000, &mut buf) {
            Step::Transmit { len, .. } => {
                built.push((len, buf[1] & 0x08 != 0));
                master.on_sent();
            }
            Step::Listen { .. } => master.finish_listen(),
            Step::Idle => panic!("{params:?} keyed {keyed}: no uplink built in slot {slot}"),
        }
    }
    built
}

#[test]
fn every_frame_of_every_mode_fits_its_budget() {
    let mut combinations = 0;
    for rate in RateMode::ALL {
        let max = rate.max_frame_bytes();
        for wanted in FORMATS {
            let params = LinkParams::new(7, Band::Mhz433, rate, wanted, 4);
            if params.format != wanted {
                // Not a format this mode runs (F700 takes Sticks16 instead).
                continue;
            }
            for keyed in [false, true] {
                for stream in [false, true] {
                    let built = uplinks(params, keyed, stream);
                    for report in [false, true] {
                        let largest = built
                            .iter()
                            .filter(|(_, r)| *r == report)
                            .map(|(len, _)| *len)
                            .max()
                            .expect("uplinks with and without the report");
                        assert!(
                            largest <= max,
                            "{rate:?} {wanted:?} keyed {keyed} report {report} stream \
                             {stream}: a {largest}-byte uplink, the frame is {max}"
                        );
                        combinations += 1;
                    }
                }
            }
            // The follower's largest downlink and its nonce frame.
            let keyed_extra = crate::link::auth::TAG_BYTES - crate::frame::CRC_BYTES;
            assert!(crate::frame::downlink_overhead(true) + keyed_extra <= max);
            assert!(crate::frame::NONCE_FRAME_BYTES <= max);
        }
    }
    // L50, M100, F250, F500 × 3 formats, F700 × Compact8 and Sticks16 (Full16 does not fit
    // its 21 bytes); × keyed × stream × report.
    assert_eq!(combinations, (4 * 3 + 2) * 8);
}

/// The shape that did not fit: a keyed 16-channel F500 uplink with the report and no room
/// for stream data is exactly F500's 32 bytes, and an uplink with room still carries data.
#[test]
fn a_keyed_16_channel_uplink_with_the_report_fits_f500() {
    let params = LinkParams::new(7, Band::Mhz433, RateMode::F500, ChannelFormat::Full16, 4);
    assert_eq!(RateMode::F500.max_frame_bytes(), 32);
    let built = uplinks(params, true, true);
    assert!(built.contains(&(32, true)), "{built:?}");
    assert!(built.contains(&(32, false)), "{built:?}");
    assert_eq!(
        crate::frame::sealed_uplink_bytes(ChannelFormat::Full16, true, 0),
        32
    );
    // A follower's downlink fits too (same rule, both directions).
    let follower = Follower::new(params, FailsafeValues::default(), DEFAULT_FAILSAFE_US);
    assert_eq!(follower.params().rate.max_frame_bytes(), 32);
}
