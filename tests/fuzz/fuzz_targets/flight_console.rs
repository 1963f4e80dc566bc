//! The flight controller's USB console (`flight_app::settings::console`): fuzzed text,
//! line by line, parsed and applied to the settings as the console task does.
//!
//! Invariants: parsing never fails on anything but the command word or the word count; a
//! `set` that is accepted leaves a value inside the parameter's range, and what `get` then
//! prints is accepted by `set` again and gives the same value bits (console round trip);
//! a refused `set` changes nothing; the set left always passes the whole-set check; a
//! `bind PHRASE` carries the rest of the line, trimmed, which the phrase rule takes or
//! refuses without panicking (the console's bind window starts from it).
#![no_main]

use flight_app::settings::{Command, Settings, parse_line, write_list, write_setting};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let mut settings = Settings::default();
    for line in text.split(['\n', '\r']) {
        let Ok(command) = parse_line(line) else {
            continue;
        };
        match command {
            Command::Set { name, value } => {
                let before = settings.clone();
                match settings.set_text(name, value) {
                    Ok(()) => round_trip(&settings, name),
                    Err(_) => assert_eq!(settings, before, "a refused set changed something"),
                }
            }
            Command::SetAll(pairs) => {
                let before = settings.clone();
                if settings.set_text_pairs(pairs).is_err() {
                    assert_eq!(settings, before, "a refused multi-set changed something");
                }
            }
            Command::Get(name) => {
                let mut out = String::new();
                write_setting(&mut out, &settings, name).expect("String never fails");
            }
            Command::List(prefix) => {
                let mut out = String::new();
                write_list(&mut out, &settings, prefix).expect("String never fails");
            }
            Command::Defaults => settings = Settings::default(),
            Command::Bind(text) => {
                assert_eq!(
                    text,
                    text.trim(),
                    "the phrase is the trimmed rest of the line"
                );
                let _ = telemetry::link::check_phrase(text);
            }
            Command::Help
            | Command::Save
            | Command::Status
            | Command::Magcal(_)
            | Command::Nothing => {}
        }
    }
    for (param, value) in settings.iter() {
        assert_eq!(param.check(value), Ok(value), "{} out of range", param.name);
    }
    // The console only ever leaves a set that runs (every cross-setting rule holds).
    assert!(
        settings.check().is_ok(),
        "the console accepted settings that cannot run"
    );
});

/// `get NAME` prints `NAME = VALUE`; `set NAME VALUE` with that text must restore the value.
fn round_trip(settings: &Settings, name: &str) {
    let mut shown = String::new();
    write_setting(&mut shown, settings, name).expect("String never fails");
    let value_text = shown
        .trim_end()
        .split_once(" = ")
        .map(|(_, v)| v)
        .expect("an accepted setting prints NAME = VALUE");
    let mut again = Settings::default();
    again
        .set_text(name, value_text)
        .unwrap_or_else(|e| panic!("`set {name} {value_text}` refused: {e:?}"));
    let bits = |s: &Settings| s.by_name(name).map(|v| v.to_bits());
    assert_eq!(bits(&again), bits(settings), "{shown}");
}
