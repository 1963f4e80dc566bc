//! The CRSF responder driven by simulated EdgeTX frames in virtual time.

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]
// 1.5708 rad is the worked ATTITUDE frame's value (`crsf_frames.rs`, frame E), not a
// stand-in for π/2.
#![allow(clippy::approx_constant)]

use proptest::prelude::*;
use taulink_handset::HandsetTelemetry;
use taulink_handset::crsf::responder::{Config, LinkSchedule, Responder, taulink_device_info};
use taulink_handset::crsf::{Decoded, Decoder, Frame, Message, RcChannels};
use taulink_handset::report::{
    AttitudeReport, BatteryReport, FlightModeReport, GpsReport, LinkReport, LinkSecurityReport,
};

const PING: [u8; 6] = [0xC8, 0x04, 0x28, 0x00, 0xEA, 0x54];

fn rc_frame() -> Frame {
    RcChannels::CENTRED.to_frame()
}

fn ping_frame() -> Frame {
    Frame::new(0xC8, 0x28, &PING[3..5]).unwrap()
}

fn decode_all(bytes: &[u8]) -> Vec<Message> {
    let mut decoder = Decoder::new();
    let decoded: Vec<Decoded> = decoder.feed(bytes).collect();
    assert_eq!(
        decoder.pending_len(),
        0,
        "reply must hold whole frames only"
    );
    decoded
        .into_iter()
        .map(|d| match d {
            Decoded::Frame(f) => {
                assert_eq!(f.address, 0xC8);
                Message::from_frame(&f).unwrap()
            }
            Decoded::Rejected(r) => panic!("{r:?}"),
        })
        .collect()
}

fn full_telemetry() -> HandsetTelemetry {
    HandsetTelemetry {
        link: Some(LinkReport {
            uplink_rssi_dbm: -67,
            uplink_lq_percent: 98,
            uplink_snr_db: 8,
            downlink_rssi_dbm: -71,
            downlink_lq_percent: 95,
            downlink_snr_db: 6,
            tx_power_mw: 100,
            rf_mode: 1,
        }),
        battery: Some(BatteryReport {
            voltage_mv: 11_104,
            current_ma: 5_260,
            used_capacity_mah: 1_234,
            remaining_percent: 80,
        }),
        attitude: Some(AttitudeReport {
            roll_rad: -0.2,
            pitch_rad: 0.1,
            yaw_rad: 1.5708,
        }),
        flight_mode: Some(FlightModeReport {
            name: heapless::String::try_from("HORIZON-RESCUE").unwrap(),
            number: 3,
        }),
        gps: Some(GpsReport {
            latitude_e7: 473_977_419,
            longitude_e7: 85_455_938,
            groundspeed_cm_s: 1_000,
            course_cdeg: 9_000,
            altitude_m: 488,
            satellites: 12,
        }),
        ..HandsetTelemetry::default()
    }
}

fn responder(baud: u32) -> Responder {
    Responder::new(Config::new(baud, taulink_device_info(0, 1, 0)))
}

/// A responder asking for the 1 ms lead the timing tests below were worked out with.
fn responder_lead_1ms(baud: u32) -> Responder {
    let mut config = Config::new(baud, taulink_device_info(0, 1, 0));
    config.timing_lead_us = 1_000;
    Responder::new(config)
}

/// Runs `seconds` of radio frames every `period_us`, returns every reply's messages.
fn run(
    responder: &mut Responder,
    period_us: u64,
    seconds: u64,
    telemetry: &HandsetTelemetry,
) -> Vec<(u64, Vec<Message>)> {
    let mut replies = Vec::new();
    let mut now = 0;
    while now < seconds * 1_000_000 {
        responder.on_frame(now, &rc_frame());
        let mut out = [0u8; 256];
        let n = responder
            .reply(now + 50, telemetry, &mut out)
            .unwrap()
            .len();
        assert!(n <= 128);
        replies.push((now, decode_all(&out[..n])));
        now += period_us;
    }
    replies
}

fn count(replies: &[(u64, Vec<Message>)], pick: impl Fn(&Message) -> bool) -> usize {
    replies
        .iter()
        .flat_map(|(_, m)| m.iter())
        .filter(|m| pick(m))
        .count()
}

#[test]
fn silent_without_a_radio_frame() {
    let mut responder = responder(400_000);
    let mut out = [0u8; 128];
    assert!(
        responder
            .reply(0, &full_telemetry(), &mut out)
            .unwrap()
            .is_empty()
    );
    responder.on_frame(0, &rc_frame());
    assert!(
        !responder
            .reply(10, &full_telemetry(), &mut out)
            .unwrap()
            .is_empty()
    );
    // One window per radio frame.
    assert!(
        responder
            .reply(20, &full_telemetry(), &mut out)
            .unwrap()
            .is_empty()
    );
    // A window not used within half the radio period (4 ms default at 400 kBd) is missed.
    responder.on_frame(4_000, &rc_frame());
    assert!(
        responder
            .reply(6_001, &full_telemetry(), &mut out)
            .unwrap()
            .is_empty()
    );
    // 2 ms late is still inside; link statistics are due again 100 ms after the first ones.
    responder.on_frame(100_000, &rc_frame());
    assert!(
        !responder
            .reply(102_000, &full_telemetry(), &mut out)
            .unwrap()
            .is_empty()
    );
}

#[test]
fn ping_is_answered_with_taulink_device_info_once() {
    let mut responder = responder(400_000);
    let telemetry = HandsetTelemetry::default();
    assert!(matches!(
        responder.on_frame(0, &ping_frame()),
        Some(Message::DevicePing(_))
    ));
    let mut out = [0u8; 128];
    let n = responder.reply(10, &telemetry, &mut out).unwrap().len();
    let messages = decode_all(&out[..n]);
    let Message::DeviceInfo(info) = &messages[0] else {
        panic!("{messages:?}")
    };
    assert_eq!(info.name.as_str(), "TauLink");
    assert_eq!((info.destination, info.origin), (0xEA, 0xEE));
    assert_ne!(&info.serial, b"ELRS");
    responder.on_frame(4_000, &rc_frame());
    let n = responder.reply(4_010, &telemetry, &mut out).unwrap().len();
    assert!(
        !decode_all(&out[..n])
            .iter()
            .any(|m| matches!(m, Message::DeviceInfo(_)))
    );
}

#[test]
fn ping_is_answered_even_in_a_short_window() {
    // 115 200 Bd at a 5 ms radio period leaves 50 − 6 = 44 bytes after a ping, 24 after a
    // channel frame; DEVICE_INFO (28 bytes) goes out either way.
    let mut responder = responder(115_200);
    responder.on_frame(0, &rc_frame());
    responder.on_frame(5_000, &ping_frame());
    assert_eq!(responder.reply_budget(6), 44);
    assert_eq!(responder.reply_budget(26), 24);
    let mut out = [0u8; 128];
    let n = responder
        .reply(5_010, &HandsetTelemetry::default(), &mut out)
        .unwrap()
        .len();
    assert!(matches!(
        decode_all(&out[..n])[..],
        [Message::DeviceInfo(_), ..]
    ));
    // Ping again, answered in a window shortened by a (hypothetical) 26-byte radio frame.
    let mut responder = responder_at_5ms_with_ping_after_channels();
    let n = responder
        .reply(10_010, &full_telemetry(), &mut out)
        .unwrap()
        .len();
    assert_eq!(n, 28);
    assert!(matches!(
        decode_all(&out[..n])[..],
        [Message::DeviceInfo(_)]
    ));
}

/// A responder at 115 200 Bd with the radio at 5 ms, whose ping (heard at 0 ms, reply window
/// missed) is still pending when a 26-byte channel frame opens a 24-byte window at 10 ms.
fn responder_at_5ms_with_ping_after_channels() -> Responder {
    let mut responder = responder(115_200);
    responder.on_frame(0, &ping_frame());
    responder.on_frame(5_000, &rc_frame());
    responder.on_frame(10_000, &rc_frame());
    responder
}

#[test]
fn ping_for_someone_else_is_ignored() {
    let mut responder = responder(400_000);
    responder.on_frame(0, &Frame::new(0xC8, 0x28, &[0xEC, 0xEA]).unwrap());
    let mut out = [0u8; 128];
    let n = responder
        .reply(10, &HandsetTelemetry::default(), &mut out)
        .unwrap()
        .len();
    assert!(
        !decode_all(&out[..n])
            .iter()
            .any(|m| matches!(m, Message::DeviceInfo(_)))
    );
}

#[test]
fn model_select_is_remembered() {
    let mut responder = responder(400_000);
    let frame = Frame::new(0xC8, 0x32, &[0xEE, 0xEA, 0x10, 0x05, 0x07, 0x8E]).unwrap();
    responder.on_frame(0, &frame);
    assert_eq!(responder.model_id(), Some(7));
}

#[test]
fn link_statistics_at_10_hz_and_sensors_at_5_hz() {
    let mut responder = responder(400_000);
    let replies = run(&mut responder, 4_000, 1, &full_telemetry());
    assert_eq!(
        count(
            &replies,
            |m| matches!(m, Message::LinkStatistics(s) if s.uplink_lq_percent == 98)
        ),
        10
    );
    assert_eq!(count(&replies, |m| matches!(m, Message::Battery(_))), 5);
    assert_eq!(count(&replies, |m| matches!(m, Message::Attitude(_))), 5);
    assert_eq!(count(&replies, |m| matches!(m, Message::FlightMode(_))), 5);
    assert_eq!(count(&replies, |m| matches!(m, Message::Gps(_))), 5);
    // Values as the report says: 11.104 V → 111, 5.26 A → 53, 10 m/s = 36.0 km/h → 360,
    // 488 m → 1488, flight mode cut to EdgeTX's 13 visible characters.
    let all: Vec<&Message> = replies.iter().flat_map(|(_, m)| m.iter()).collect();
    assert!(
        all.iter()
            .any(|m| matches!(m, Message::Battery(b) if b.voltage_dv == 111 && b.current_da == 53))
    );
    assert!(all.iter().any(|m| matches!(m, Message::Gps(g) if g.groundspeed_dkmh == 360 && g.altitude_m_plus_1000 == 1488)));
    assert!(
        all.iter()
            .any(|m| matches!(m, Message::FlightMode(f) if f.name.as_str() == "HORIZON-RESCU"))
    );
    assert!(all.iter().any(|m| matches!(m, Message::LinkStatistics(s) if s.uplink_rssi1_dbm == -67 && s.uplink_tx_power_index == 3)));
}

/// Issue 30: a tag alert shows on the FM sensor as "TAG ALERT" for as long as it stands
/// (even with no flight mode known), and the mode comes back after it.
#[test]
fn a_tag_alert_is_the_flight_mode_while_it_stands() {
    let modes = |telemetry: &HandsetTelemetry| -> Vec<String> {
        let mut responder = responder(400_000);
        run(&mut responder, 4_000, 1, telemetry)
            .iter()
            .flat_map(|(_, m)| m.iter())
            .filter_map(|m| match m {
                Message::FlightMode(f) => Some(f.name.as_str().to_owned()),
                _ => None,
            })
            .collect()
    };
    let alert = Some(LinkSecurityReport {
        tag_failures: 412,
        alert: true,
    });
    let alerted = HandsetTelemetry {
        link_security: alert,
        ..full_telemetry()
    };
    assert_eq!(modes(&alerted), vec!["TAG ALERT"; 5]);
    let no_mode = HandsetTelemetry {
        flight_mode: None,
        ..alerted
    };
    assert_eq!(modes(&no_mode), vec!["TAG ALERT"; 5]);
    let counted_only = HandsetTelemetry {
        link_security: Some(LinkSecurityReport {
            tag_failures: 3,
            alert: false,
        }),
        ..full_telemetry()
    };
    assert_eq!(modes(&counted_only), vec!["HORIZON-RESCU"; 5]);
}

#[test]
fn no_link_sends_lq_zero_and_no_sensors() {
    let mut responder = responder(400_000);
    let telemetry = HandsetTelemetry {
        link: None,
        ..full_telemetry()
    };
    let replies = run(&mut responder, 4_000, 1, &telemetry);
    assert_eq!(
        count(
            &replies,
            |m| matches!(m, Message::LinkStatistics(s) if s.uplink_lq_percent == 0)
        ),
        10
    );
    assert_eq!(
        count(&replies, |m| !matches!(m, Message::LinkStatistics(_))),
        0
    );
}

#[test]
fn reply_budget_follows_baud_and_period() {
    let mut responder = responder(115_200);
    // Default before measuring: 16 ms at 115 200 → 11 520 B/s · 16 ms · 0.87 = 160 → cap 128.
    assert_eq!(responder.reply_budget(26), 128);
    // Radio at 5 ms: 57.6 B · 0.87 = 50, minus the radio's 26-byte frame = 24.
    responder.on_frame(0, &rc_frame());
    responder.on_frame(5_000, &rc_frame());
    assert_eq!(responder.radio_period_us(), 5_000);
    assert_eq!(responder.reply_budget(26), 24);
    // 24 bytes hold a 14-byte LINK_STATISTICS but not a 12-byte battery after it.
    let replies = run(&mut responder, 5_000, 1, &full_telemetry());
    for (_, messages) in &replies {
        let bytes: usize = messages
            .iter()
            .map(|m| m.to_frame(0xC8).unwrap().wire_len())
            .sum();
        assert!(bytes <= 24, "{bytes}");
    }
    assert_eq!(
        count(&replies, |m| matches!(m, Message::LinkStatistics(_))),
        10
    );
}

#[test]
fn timing_offset_by_hand() {
    // Air packets at k · 20 ms, lead 1 ms: channel frames should end at 19 ms (mod 20).
    // A frame ending at 5 ms is 6 ms late for the 19 ms slot before it (−1 ms):
    // offset = ((19 000 − 5 000) mod 20 000) = 14 000 ≥ 10 000 → −6 000 µs = −60 000 × 0.1 µs.
    let mut responder = responder_lead_1ms(400_000);
    responder.set_link_schedule(Some(LinkSchedule {
        period_us: 20_000,
        phase_us: 0,
    }));
    responder.on_frame(5_000, &rc_frame());
    let timing = responder.timing_correction().unwrap();
    assert_eq!(timing.interval_100ns, 200_000);
    assert_eq!(timing.offset_100ns, -60_000);
    // A frame ending at 17 ms: 2 ms early → +20 000.
    responder.on_frame(17_000, &rc_frame());
    assert_eq!(responder.timing_correction().unwrap().offset_100ns, 20_000);
    // A 1 ms air period is below the 2 ms the line allows at 400 kBd: ask for 2 ms.
    responder.set_link_schedule(Some(LinkSchedule {
        period_us: 1_000,
        phase_us: 0,
    }));
    assert_eq!(
        responder.timing_correction().unwrap().interval_100ns,
        20_000
    );
}

/// EdgeTX as `radio/src/telemetry/crossfire.cpp` handles the 0x3A/0x10 timing frame (the
/// "OpenTX sync" sub-type of the CRSF spec): runs its mixer at the interval it is told and
/// shifts its next frame by the offset (positive = it was early, so it waits longer).
#[test]
fn radio_locks_onto_the_air_schedule() {
    let mut responder = responder_lead_1ms(400_000);
    let schedule = LinkSchedule {
        period_us: 10_000,
        phase_us: 3_000,
    };
    responder.set_link_schedule(Some(schedule));
    let telemetry = full_telemetry();
    let mut radio_period_us: i64 = 4_000;
    let mut next_send: i64 = 1_234;
    let mut last_arrival = 0;
    let mut corrections = 0;
    while next_send < 3_000_000 {
        let arrival = next_send as u64 + 650; // 26 bytes at 400 kBd
        responder.on_frame(arrival, &rc_frame());
        let mut out = [0u8; 128];
        let n = responder
            .reply(arrival + 20, &telemetry, &mut out)
            .unwrap()
            .len();
        next_send += radio_period_us;
        for message in decode_all(&out[..n]) {
            if let Message::TimingCorrection(t) = message {
                radio_period_us = i64::from(t.interval_100ns / 10);
                next_send += i64::from(t.offset_100ns / 10);
                corrections += 1;
            }
        }
        last_arrival = arrival;
    }
    assert!(corrections >= 14, "{corrections}");
    assert_eq!(radio_period_us, 10_000);
    // Locked: the last frame ended exactly 1 ms (the lead) before an air packet at 3 ms + k·10 ms.
    assert_eq!((last_arrival + 1_000 - 3_000) % 10_000, 0);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Whatever the radio sends and whenever we are asked, a reply is whole valid frames, at
    /// most 128 bytes and within the caller's buffer, and only a lone DEVICE_INFO may exceed
    /// the window budget.
    #[test]
    fn replies_are_whole_frames_within_budget(
        baud in prop::sample::select(vec![115_200u32, 400_000, 921_600]),
        steps in prop::collection::vec((0u64..30_000, 0u8..4, 0u64..3_000, 0usize..200), 1..120),
        with_link in any::<bool>(),
        schedule_period_us in prop::option::of(500u32..40_000),
    ) {
        let mut responder = responder(baud);
        responder.set_link_schedule(schedule_period_us.map(|period_us| LinkSchedule { period_us, phase_us: 777 }));
        let telemetry = if with_link { full_telemetry() } else { HandsetTelemetry { link: None, ..full_telemetry() } };
        let mut now = 0;
        for (gap_us, kind, delay_us, out_len) in steps {
            now += gap_us;
            let frame = match kind {
                0 => rc_frame(),
                1 => ping_frame(),
                2 => Frame::new(0xC8, 0x32, &[0xEE, 0xEA, 0x10, 0x05, 0x07, 0x8E]).unwrap(),
                _ => Frame::new(0xC8, 0x2D, &[0xEE, 0xEF, 0x11, 0x01]).unwrap(),
            };
            responder.on_frame(now, &frame);
            let budget_after = responder.reply_budget(frame.wire_len());
            let mut out = vec![0u8; out_len];
            let n = responder.reply(now + delay_us, &telemetry, &mut out).unwrap().len();
            prop_assert!(n <= out_len && n <= 128);
            let messages = decode_all(&out[..n]);
            if n > budget_after {
                prop_assert!(matches!(messages[..], [Message::DeviceInfo(_)]), "{} > {}", n, budget_after);
            }
            if let Some(t) = messages.iter().find_map(|m| match m { Message::TimingCorrection(t) => Some(*t), _ => None }) {
                // Offset within half an air period; interval a whole multiple of the air period
                // no shorter than the line allows (5 ms at 115 200 Bd, else 2 ms), or 50 ms.
                let period_us = schedule_period_us.unwrap();
                prop_assert!((t.offset_100ns / 10).unsigned_abs() <= period_us / 2);
                let interval_us = t.interval_100ns / 10;
                let min_us = if baud <= 115_200 { 5_000 } else { 2_000 };
                prop_assert!(interval_us >= min_us && interval_us <= 50_000);
                prop_assert!(interval_us % period_us == 0 || interval_us == 50_000);
            }
        }
    }
}
