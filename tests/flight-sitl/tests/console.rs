//! The console as a pilot types at it: overlong lines are refused whole, settings that
//! cannot run are refused with the reason, changes valid only together go on one line.

#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

use flight_app::app::FlightApp;
use flight_app::settings::{Settings, handles};
use flight_sitl::console::{LINE_BUFFER, type_into_console};

#[test]
fn an_overlong_line_is_refused_not_cut() {
    // 101 characters meaning 0.2 (padding spaces before the value); the old console kept
    // the first 96 bytes and acted on whatever they said.
    let mut line = String::from("set failsafe.descent_mps");
    while line.len() < 98 {
        line.push(' ');
    }
    line.push_str("0.2");
    assert_eq!(line.len(), 101);
    assert!(line.len() > LINE_BUFFER);
    let mut app = FlightApp::new(Settings::default(), 0).unwrap();
    let replies = type_into_console(&mut app, format!("{line}\r\n").as_bytes());
    println!("{replies:?}");
    assert_eq!(replies, ["line too long, ignored\r\n"]);
    assert_eq!(app.settings(), &Settings::default());
    // The same change on a short line is taken.
    let replies = type_into_console(&mut app, b"set failsafe.descent_mps 0.2\r\n");
    assert_eq!(replies, ["failsafe.descent_mps = 0.2\n"]);
}

#[test]
fn settings_that_cannot_run_are_refused_with_the_reason() {
    let mut app = FlightApp::new(Settings::default(), 0).unwrap();
    let replies = type_into_console(
        &mut app,
        b"set output.protocol pwm\r\nset output.rate_hz 400\r\nset link.telemetry_ratio 3\r\n",
    );
    println!("{replies:?}");
    assert_eq!(replies.len(), 3);
    for r in &replies {
        assert!(r.starts_with("refused, the settings would not run"), "{r}");
    }
    assert_eq!(app.settings(), &Settings::default());
    let replies = type_into_console(
        &mut app,
        b"set output.protocol pwm output.rate_hz 400\r\nset output.min_us 2100\r\n",
    );
    println!("{replies:?}");
    assert_eq!(replies[0], "ok\r\n");
    assert!(replies[1].contains("pulse limits"), "{}", replies[1]);
    assert_eq!(app.settings().get(handles::OUTPUT_PROTOCOL), 1);
    assert_eq!(app.settings().get(handles::OUTPUT_RATE_HZ), 400);
    assert_eq!(app.settings().get(handles::OUTPUT_MIN_US), 1_000);
}
