//! The module's CRSF responder (`taulink_handset::crsf::responder`) behind the decoder:
//! radio frames from the fuzz bytes (RC channels, pings, model select, anything) at fuzzed
//! times, with a fuzzed link schedule and handset telemetry, and a reply window after each.
//!
//! Invariants: `on_frame` hands back exactly the frame's typed message; a model select sets
//! the model id; every reply fits the window's buffer and EdgeTX's 128 bytes and is a run of
//! whole CRSF frames of known types; the timing correction stays within half an air period.
#![no_main]

use libfuzzer_sys::fuzz_target;
use taulink_fuzz::Input;
use taulink_handset::crsf::responder::{
    Config, LinkSchedule, MAX_REPLY_BYTES, Responder, taulink_device_info,
};
use taulink_handset::crsf::{Decoded, Decoder, Message};
use taulink_handset::report::{
    AttitudeReport, BatteryReport, FlightModeReport, GpsReport, HandsetTelemetry, LinkReport,
    LinkSecurityReport, VerticalReport,
};

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let baud = [115_200, 400_000, 921_600, 1_870_000][usize::from(input.u8() % 4)];
    let mut responder = Responder::new(Config::new(baud, taulink_device_info(0, 1, 0)));
    let schedule = LinkSchedule {
        period_us: u32::from(input.u16()),
        phase_us: u64::from(input.u32()),
    };
    if input.bool() {
        responder.set_link_schedule(Some(schedule));
    }
    let telemetry = telemetry(&mut input);
    let mut decoder = Decoder::new();
    let mut now = 0u64;
    while !input.is_empty() {
        let chunk = input.chunk(80);
        let frames: Vec<_> = decoder
            .feed(chunk)
            .filter_map(|d| match d {
                Decoded::Frame(frame) => Some(frame),
                Decoded::Rejected(_) => None,
            })
            .collect();
        for frame in frames {
            now = now.saturating_add(u64::from(input.u16()));
            let message = responder.on_frame(now, &frame);
            assert_eq!(message, Message::from_frame(&frame).ok());
            if let Some(Message::ModelSelect(select)) = &message {
                assert_eq!(responder.model_id(), Some(select.model_id));
            }
            let size = usize::from(input.u8());
            let mut out = vec![0u8; size];
            let reply_at = now + u64::from(input.u16() % 20_000);
            let reply = responder
                .reply(reply_at, &telemetry, &mut out)
                .expect("the writer never overruns its buffer");
            assert!(reply.len() <= size.min(MAX_REPLY_BYTES));
            check_reply(reply);
            if let Some(timing) = responder.timing_correction() {
                let half_period_100ns = i64::from(schedule.period_us) * 5 + 10;
                assert!(i64::from(timing.offset_100ns).abs() <= half_period_100ns);
                assert!(timing.interval_100ns <= 500_000);
            }
        }
    }
});

/// A reply is nothing but whole, checked frames the module knows how to build.
fn check_reply(reply: &[u8]) {
    let mut decoder = Decoder::new();
    let mut decoded: Vec<_> = decoder.feed(reply).collect();
    decoded.extend(decoder.idle());
    for d in decoded {
        let Decoded::Frame(frame) = d else {
            panic!("reply holds a bad frame: {d:?} in {reply:02x?}");
        };
        assert!(Message::from_frame(&frame).is_ok(), "{frame:?}");
    }
    assert_eq!(decoder.pending_len(), 0);
}

fn telemetry(input: &mut Input) -> HandsetTelemetry {
    let present = input.u8();
    let mut name = heapless::String::new();
    for _ in 0..input.u8() % 17 {
        let _ = name.push(char::from(b' ' + input.u8() % 95));
    }
    HandsetTelemetry {
        link: (present & 1 != 0).then(|| LinkReport {
            uplink_rssi_dbm: input.u16() as i16,
            uplink_lq_percent: input.u8(),
            uplink_snr_db: input.u8() as i8,
            downlink_rssi_dbm: input.u16() as i16,
            downlink_lq_percent: input.u8(),
            downlink_snr_db: input.u8() as i8,
            tx_power_mw: input.u16(),
            rf_mode: input.u8(),
        }),
        battery: (present & 2 != 0).then(|| BatteryReport {
            voltage_mv: input.u32(),
            current_ma: input.u32(),
            used_capacity_mah: input.u32(),
            remaining_percent: input.u8(),
        }),
        attitude: (present & 4 != 0).then(|| AttitudeReport {
            roll_rad: f32::from_bits(input.u32()),
            pitch_rad: f32::from_bits(input.u32()),
            yaw_rad: f32::from_bits(input.u32()),
        }),
        flight_mode: (present & 8 != 0).then(|| FlightModeReport {
            name,
            number: input.u8(),
        }),
        gps: (present & 16 != 0).then(|| GpsReport {
            latitude_e7: input.u32() as i32,
            longitude_e7: input.u32() as i32,
            groundspeed_cm_s: input.u32(),
            course_cdeg: input.u16(),
            altitude_m: input.u32() as i32,
            satellites: input.u8(),
        }),
        vertical: (present & 32 != 0).then(|| VerticalReport {
            altitude_cm: input.u32() as i32,
            vario_cm_s: input.u16() as i16,
        }),
        cells: (present & 64 != 0).then(|| input.u8()),
        module_battery_mv: (present & 128 != 0).then(|| input.u16()),
        link_security: input.bool().then(|| LinkSecurityReport {
            tag_failures: input.u32(),
            alert: input.bool(),
        }),
    }
}
