//! One set of flight telemetry through all three handset paths (CRSF replies, S.Port push,
//! FrSky D hub), each decoded back from the bytes with the matching decoder: the radio must
//! see the same voltage, current, link quality and flight mode whichever path it listens to.

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

use proptest::prelude::*;
use taulink_handset::HandsetTelemetry;
use taulink_handset::crsf::responder::{Config, LinkSchedule, Responder, taulink_device_info};
use taulink_handset::crsf::{self, Decoded, Message, RcChannels};
use taulink_handset::frsky_d::{self, HubDecoder, Sender, hub};
use taulink_handset::report::{BatteryReport, FlightModeReport, LinkReport};
use taulink_handset::sport::{self, Scheduler, schedule, value_id};

fn telemetry(voltage_mv: u32, current_ma: u32, lq: u8, mode: u8) -> HandsetTelemetry {
    HandsetTelemetry {
        link: Some(LinkReport {
            uplink_rssi_dbm: -85,
            uplink_lq_percent: lq,
            downlink_rssi_dbm: -88,
            downlink_lq_percent: lq,
            tx_power_mw: 100,
            ..LinkReport::default()
        }),
        battery: Some(BatteryReport {
            voltage_mv,
            current_ma,
            used_capacity_mah: 321,
            remaining_percent: 55,
        }),
        flight_mode: Some(FlightModeReport {
            name: heapless::String::try_from("ACRO").unwrap(),
            number: mode,
        }),
        ..HandsetTelemetry::default()
    }
}

/// What a radio would display, in common units: (volts × 100, amps × 10, LQ %, mode).
type Seen = (Option<u32>, Option<u32>, Option<u32>, Option<String>);

fn via_crsf(t: &HandsetTelemetry) -> Seen {
    let mut responder = Responder::new(Config::new(400_000, taulink_device_info(0, 1, 0)));
    responder.set_link_schedule(Some(LinkSchedule {
        period_us: 20_000,
        phase_us: 0,
    }));
    let mut line = Vec::new();
    for k in 0..250u64 {
        let now = k * 4_000;
        responder.on_frame(now, &RcChannels::CENTRED.to_frame());
        let mut out = [0u8; 128];
        let n = responder.reply(now + 30, t, &mut out).unwrap().len();
        line.extend_from_slice(&out[..n]);
    }
    let mut seen: Seen = (None, None, None, None);
    let mut decoder = crsf::Decoder::new();
    for chunk in line.chunks(7) {
        for decoded in decoder.feed(chunk) {
            let Decoded::Frame(frame) = decoded else {
                panic!("{decoded:?}")
            };
            match Message::from_frame(&frame).unwrap() {
                // 0.1 V → ×10 to get centivolts (the CRSF resolution is coarser).
                Message::Battery(b) => {
                    seen.0 = Some(u32::from(b.voltage_dv) * 10);
                    seen.1 = Some(u32::from(b.current_da));
                }
                Message::LinkStatistics(s) => seen.2 = Some(u32::from(s.uplink_lq_percent)),
                Message::FlightMode(m) => seen.3 = Some(m.name.to_string()),
                _ => {}
            }
        }
    }
    seen
}

fn via_sport(t: &HandsetTelemetry) -> Seen {
    let mut scheduler = Scheduler::new(schedule::Config::default());
    let mut line = Vec::new();
    for now in (0..1_000_000u64).step_by(1_000) {
        if let Some(frame) = scheduler.next_frame(now, t) {
            let mut out = [0u8; sport::MAX_WIRE_LEN];
            let n = frame.encode(&mut out).unwrap().len();
            line.extend_from_slice(&out[..n]);
        }
    }
    let mut seen: Seen = (None, None, None, None);
    let mut decoder = sport::Decoder::new();
    decoder.push_all(&line, |event| {
        let sport::Event::Frame(frame) = event else {
            panic!("{event:?}")
        };
        match frame.value_id {
            value_id::VFAS => seen.0 = Some(frame.value),
            value_id::CURRENT => seen.1 = Some(frame.value),
            value_id::TAULINK_LQ => seen.2 = Some(frame.value),
            value_id::TAULINK_FLIGHT_MODE => seen.3 = Some(format!("mode {}", frame.value)),
            _ => {}
        }
    });
    seen
}

fn via_frsky_d(t: &HandsetTelemetry) -> Seen {
    let mut sender = Sender::new(hub::SenderConfig::default());
    let mut line = Vec::new();
    for now in (0..2_000_000u64).step_by(1_000) {
        if let Some(frame) = sender.next_frame(now, t) {
            let mut out = [0u8; frsky_d::MAX_WIRE_LEN];
            let n = frame.encode(&mut out).unwrap().len();
            line.extend_from_slice(&out[..n]);
        }
    }
    let mut seen: Seen = (None, None, None, None);
    let mut decoder = frsky_d::Decoder::new();
    let mut hub_decoder = HubDecoder::new();
    decoder.push_all(&line, |event| match event {
        frsky_d::Event::Frame(frsky_d::Frame::Link(link)) => seen.2 = Some(u32::from(link.a2)),
        frsky_d::Event::Frame(frsky_d::Frame::User(data)) => {
            for record in data.iter().filter_map(|&b| hub_decoder.push(b)) {
                match record.id {
                    // EdgeTX: ≥ 2000 means 0.01 V + 2000.
                    hub::id::VFAS => seen.0 = Some(u32::from(record.value - 2000)),
                    hub::id::CURRENT => seen.1 = Some(u32::from(record.value)),
                    hub::id::TEMP1 => seen.3 = Some(format!("mode {}", record.value)),
                    _ => {}
                }
            }
        }
        frsky_d::Event::Rejected(r) => panic!("{r:?}"),
    });
    seen
}

#[test]
fn the_three_paths_agree_by_hand() {
    // 11.10 V, 5.3 A, LQ 98, mode 2 "ACRO".
    let t = telemetry(11_100, 5_300, 98, 2);
    assert_eq!(
        via_crsf(&t),
        (Some(1110), Some(53), Some(98), Some("ACRO".into()))
    );
    assert_eq!(
        via_sport(&t),
        (Some(1110), Some(53), Some(98), Some("mode 2".into()))
    );
    assert_eq!(
        via_frsky_d(&t),
        (Some(1110), Some(53), Some(98), Some("mode 2".into()))
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn the_three_paths_agree(voltage_mv in 0u32..60_000, current_ma in 0u32..200_000, lq in 1u8..=100, mode in any::<u8>()) {
        let t = telemetry(voltage_mv, current_ma, lq, mode);
        let crsf = via_crsf(&t);
        let sport = via_sport(&t);
        let frsky_d = via_frsky_d(&t);
        // Centivolts: S.Port and FrSky D carry 0.01 V; CRSF 0.1 V, so it agrees to 5 cV.
        let centivolts = (voltage_mv + 5) / 10;
        prop_assert_eq!(sport.0, Some(centivolts));
        prop_assert_eq!(frsky_d.0, Some(centivolts));
        prop_assert!(crsf.0.unwrap().abs_diff(centivolts) <= 5);
        // Deciamps and LQ are exact everywhere.
        let deciamps = (current_ma + 50) / 100;
        for seen in [&crsf, &sport, &frsky_d] {
            prop_assert_eq!(seen.1, Some(deciamps));
            prop_assert_eq!(seen.2, Some(u32::from(lq)));
        }
        prop_assert_eq!(sport.3, Some(format!("mode {mode}")));
        prop_assert_eq!(frsky_d.3, Some(format!("mode {mode}")));
    }
}
