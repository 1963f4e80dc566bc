//! The PPM-mode S.Port push scheduler in virtual time: rates, values, link loss, and the bytes
//! decoding back to the telemetry they came from.

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

use taulink_handset::HandsetTelemetry;
use taulink_handset::report::{BatteryReport, FlightModeReport, LinkReport, LinkSecurityReport};
use taulink_handset::sport::schedule::{Config, LqEncoding, RssiSource};
use taulink_handset::sport::{self, Decoder, Event, Frame, Scheduler, value_id};

fn telemetry() -> HandsetTelemetry {
    HandsetTelemetry {
        link: Some(LinkReport {
            uplink_rssi_dbm: -80,
            uplink_lq_percent: 98,
            uplink_snr_db: 5,
            downlink_rssi_dbm: -71,
            downlink_lq_percent: 95,
            downlink_snr_db: 6,
            tx_power_mw: 100,
            rf_mode: 0,
        }),
        battery: Some(BatteryReport {
            voltage_mv: 11_104,
            current_ma: 5_260,
            used_capacity_mah: 900,
            remaining_percent: 64,
        }),
        flight_mode: Some(FlightModeReport {
            name: heapless::String::try_from("ANGLE").unwrap(),
            number: 2,
        }),
        ..HandsetTelemetry::default()
    }
}

/// Calls the scheduler every millisecond for `duration_us`; returns (time, frame) pairs.
fn run(
    scheduler: &mut Scheduler,
    duration_us: u64,
    telemetry: &HandsetTelemetry,
) -> Vec<(u64, Frame)> {
    (0..duration_us)
        .step_by(1_000)
        .filter_map(|now| scheduler.next_frame(now, telemetry).map(|f| (now, f)))
        .collect()
}

fn values(sent: &[(u64, Frame)], id: u16) -> Vec<u32> {
    sent.iter()
        .filter(|(_, f)| f.value_id == id)
        .map(|(_, f)| f.value)
        .collect()
}

#[test]
fn rates_over_one_second() {
    let mut scheduler = Scheduler::new(Config::default());
    let sent = run(&mut scheduler, 1_000_000, &telemetry());
    // Each item is due at its period and slots are 12 ms, so every item keeps its rate.
    assert_eq!(values(&sent, value_id::RSSI).len(), 10);
    assert_eq!(values(&sent, value_id::VFAS).len(), 5);
    assert_eq!(values(&sent, value_id::TAULINK_LQ).len(), 5);
    assert_eq!(values(&sent, value_id::CURRENT).len(), 2);
    assert_eq!(values(&sent, value_id::TAULINK_FLIGHT_MODE).len(), 2);
    assert_eq!(values(&sent, value_id::FUEL).len(), 1);
    for pair in sent.windows(2) {
        assert!(pair[1].0 - pair[0].0 >= 12_000, "slot spacing {pair:?}");
    }
    assert!(
        sent.iter()
            .all(|(_, f)| f.physical_id == 0x98 && f.primitive == 0x10)
    );
}

#[test]
fn rssi_never_gaps_a_second() {
    let mut scheduler = Scheduler::new(Config::default());
    let sent = run(&mut scheduler, 10_000_000, &telemetry());
    let rssi_times: Vec<u64> = sent
        .iter()
        .filter(|(_, f)| f.value_id == value_id::RSSI && f.value > 0)
        .map(|(t, _)| *t)
        .collect();
    assert_eq!(rssi_times[0], 0);
    let worst_gap = rssi_times.windows(2).map(|w| w[1] - w[0]).max().unwrap();
    assert!(worst_gap <= 112_000, "{worst_gap}");
}

#[test]
fn values_in_sensor_units() {
    let mut scheduler = Scheduler::new(Config::default());
    let sent = run(&mut scheduler, 1_000_000, &telemetry());
    // 11 104 mV → 1110 (0.01 V, rounded); 5 260 mA → 53 (0.1 A); LQ 98; FM 2; fuel 64;
    // RSSI = downlink LQ 95.
    assert_eq!(values(&sent, value_id::VFAS)[0], 1110);
    assert_eq!(values(&sent, value_id::CURRENT)[0], 53);
    assert_eq!(values(&sent, value_id::TAULINK_LQ)[0], 98);
    assert_eq!(values(&sent, value_id::TAULINK_FLIGHT_MODE)[0], 2);
    assert_eq!(values(&sent, value_id::FUEL)[0], 64);
    assert_eq!(values(&sent, value_id::RSSI)[0], 95);
}

/// Issue 30: a keyed link's tag failures and alert go out once a second under their DIY IDs;
/// without a keyed link neither is sent.
#[test]
fn tag_failures_and_alert_at_1_hz() {
    let mut scheduler = Scheduler::new(Config::default());
    let keyed = HandsetTelemetry {
        link_security: Some(LinkSecurityReport {
            tag_failures: 412,
            alert: true,
        }),
        ..telemetry()
    };
    let sent = run(&mut scheduler, 2_000_000, &keyed);
    assert_eq!(values(&sent, value_id::TAULINK_TAG_FAILURES), [412, 412]);
    assert_eq!(values(&sent, value_id::TAULINK_TAG_ALERT), [1, 1]);
    let sent = run(
        &mut Scheduler::new(Config::default()),
        2_000_000,
        &telemetry(),
    );
    assert!(values(&sent, value_id::TAULINK_TAG_FAILURES).is_empty());
    assert!(values(&sent, value_id::TAULINK_TAG_ALERT).is_empty());
}

#[test]
fn vfr_and_signal_rssi_options() {
    let config = Config {
        lq: LqEncoding::Vfr,
        rssi: RssiSource::SignalAboveFloor { floor_dbm: -120 },
        ..Config::default()
    };
    let mut scheduler = Scheduler::new(config);
    let sent = run(&mut scheduler, 1_000_000, &telemetry());
    // VFR shows 100 − value: send 100 − 98 = 2. RSSI: −71 − (−120) = 49.
    assert_eq!(values(&sent, value_id::VFR)[0], 2);
    assert!(values(&sent, value_id::TAULINK_LQ).is_empty());
    assert_eq!(values(&sent, value_id::RSSI)[0], 49);
    let weak = HandsetTelemetry {
        link: Some(LinkReport {
            downlink_rssi_dbm: -125,
            ..telemetry().link.unwrap()
        }),
        ..telemetry()
    };
    assert_eq!(scheduler.rssi_value(&weak), 1, "link up never reads as 0");
}

#[test]
fn link_down_sends_only_rssi_zero() {
    let mut scheduler = Scheduler::new(Config::default());
    let down = HandsetTelemetry {
        link: None,
        ..telemetry()
    };
    let sent = run(&mut scheduler, 1_000_000, &down);
    assert_eq!(sent.len(), 10);
    assert!(
        sent.iter()
            .all(|(_, f)| f.value_id == value_id::RSSI && f.value == 0)
    );
}

#[test]
fn bytes_decode_back_to_the_telemetry() {
    let mut scheduler = Scheduler::new(Config::default());
    let mut line = Vec::new();
    for (_, frame) in run(&mut scheduler, 1_000_000, &telemetry()) {
        let mut out = [0u8; sport::MAX_WIRE_LEN];
        let n = frame.encode(&mut out).unwrap().len();
        line.extend_from_slice(&out[..n]);
        line.push(sport::START); // openLRSng-style idle byte between frames
    }
    let mut decoder = Decoder::new();
    let mut decoded = Vec::new();
    decoder.push_all(&line, |e| match e {
        Event::Frame(f) => decoded.push(f),
        other => panic!("{other:?}"),
    });
    assert_eq!(decoded.len(), 25);
    let volts: Vec<f32> = decoded
        .iter()
        .filter(|f| f.value_id == value_id::VFAS)
        .map(|f| f.value as f32 / 100.0)
        .collect();
    assert!(volts.iter().all(|v| (v - 11.10).abs() < 1e-6));
    assert!(
        decoded
            .iter()
            .any(|f| f.value_id == value_id::RSSI && f.value == 95)
    );
    assert!(
        decoded
            .iter()
            .any(|f| f.value_id == value_id::TAULINK_LQ && f.value == 98)
    );
}
