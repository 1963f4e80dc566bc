//! The web ground station's Rust half (`telemetry-wasm`) against the flight side's own code:
//! a value the page encodes is what the flight side applies and echoes, and a change the
//! page signs after proving the phrase to the module passes the flight side's gate. Here
//! because it takes both ends: `telemetry/` depends on nothing under `flight/`.
// The helpers below are test code outside `#[test]` functions.
#![allow(clippy::unwrap_used, clippy::panic)]

use flight_app::authority::{ChangeGate, Reply};
use flight_app::report::{apply_setting, f32_value};
use flight_app::settings::{Settings, handles};
use telemetry::messages::{Decoded, Message, MessageReader, SettingChange};
use telemetry::module_record::{self, ModuleRecord};
use telemetry::settings::find;
use telemetry_wasm::settings::{Phone, Standing, from_wire, to_wire};

fn decode(bytes: &[u8]) -> Message {
    let mut reader = MessageReader::new();
    let got: Vec<_> = bytes.iter().filter_map(|&b| reader.push(b)).collect();
    match got.as_slice() {
        [Decoded::Message(m)] => *m,
        other => panic!("one message expected: {other:?}"),
    }
}

/// What the module sends the page, as the page's decoder hands it over (event JSON).
fn as_event(record: &ModuleRecord) -> String {
    serde_json::to_string(record).unwrap()
}

/// The module's side of a frame the page sent.
fn at_module(framed: &[u8]) -> ModuleRecord {
    use telemetry::framing::{Deframed, Deframer};
    let mut reader = Deframer::<256>::default();
    for &b in framed {
        if let Some(Deframed::Frame { .. }) = reader.push(b) {
            return module_record::decode(reader.payload()).unwrap();
        }
    }
    panic!("no frame");
}

#[test]
fn wire_values_are_what_the_flight_side_applies() {
    let (id, _) = find("pid.roll.kp").unwrap();
    let id = id as u16;
    let wire = to_wire(id, 0.004).unwrap();
    assert_eq!(wire, f32_value(0.004));
    let mut settings = Settings::default();
    let (result, echo) = apply_setting(&mut settings, SettingChange { id, value: wire });
    assert_eq!(result, Ok(()));
    assert_eq!(
        from_wire(id, echo.unwrap().value),
        Some(f64::from(0.004f32))
    );
    // A choice by its index: the flight side holds the mode the page picked by name.
    let (mode, _) = find("mode.switch_high").unwrap();
    let wire = to_wire(mode as u16, 3.0).unwrap();
    let (result, _) = apply_setting(
        &mut settings,
        SettingChange {
            id: mode as u16,
            value: wire,
        },
    );
    assert_eq!(result, Ok(()));
    assert_eq!(settings.get(handles::MODE_SWITCH_HIGH), 3);
}

/// The page against the module's exchange and the flight side's own gate: with the
/// module's phrase it is granted the change key and its change is applied after one
/// refusal that tells it the session; with another phrase the module refuses it and it
/// has nothing to sign with.
#[test]
fn the_page_proves_the_phrase_and_signs_changes_the_flight_side_accepts() {
    use telemetry::change_auth::ChangeKey;
    use telemetry::link::{LinkKey, PhraseSecret};
    use telemetry::module_record::ModuleExchange;
    let phrase = "amber kettle under the oak";
    let link_key = LinkKey::from_bytes([0x5A; 16]);
    let change_key = ChangeKey::from_link_key(&link_key);
    let (id, _) = find("pid.roll.kp").unwrap();
    let wire = to_wire(id as u16, 0.004).unwrap();
    for (typed, granted) in [(phrase, true), ("amber kettle under the elm", false)] {
        let module = ModuleExchange::new(&PhraseSecret::derive(phrase, [3; 8]), &[1; 32]);
        let mut phone = Phone::new(typed).unwrap();
        assert_eq!(at_module(&phone.hello().unwrap()), ModuleRecord::Hello);
        let challenge = ModuleRecord::Challenge(module.challenge());
        let response = phone.on_module_record(&as_event(&challenge), &[2; 32]);
        let ModuleRecord::Response(response) = at_module(&response) else {
            panic!("no response");
        };
        match module.respond(&response, Some(&change_key)) {
            Some((_, grant)) => {
                let next = phone.on_module_record(&as_event(&ModuleRecord::Granted(grant)), &[]);
                assert!(next.is_empty());
                assert_eq!(phone.standing(), Standing::Granted);
            }
            None => {
                assert!(!granted, "the right phrase refused");
                assert!(phone.sign_change(id as u16, wire).is_err());
                continue;
            }
        }
        let mut flight = Settings::default();
        flight.set_link_key(Some(link_key));
        let key = flight.link_key();
        let mut gate = ChangeGate::new(0x1234_5678);
        let mut frame = phone.sign_change(id as u16, wire).unwrap();
        let mut answers = Vec::new();
        while !frame.is_empty() && answers.len() < 5 {
            let reply = gate
                .on_message(&decode(&frame), &mut flight, key, false)
                .unwrap();
            answers.push(reply);
            frame = match reply {
                Reply::Refused(r) => phone.on_refused(&serde_json::to_string(&r).unwrap()),
                Reply::Applied(_) => Vec::new(),
            };
        }
        assert!(matches!(
            answers.as_slice(),
            [Reply::Refused(_), Reply::Applied(_)]
        ));
        assert_eq!(flight.get(handles::PID_ROLL_KP), 0.004);
    }
    assert!(Phone::new("").is_err());
    assert!(Phone::new("short").is_err(), "the phrase rule");
    assert!(
        Phone::new("correct horse battery staple").is_err(),
        "famous"
    );
}
