//! The magnetometer calibration from the sticks (issue 32): disarmed, throttle low, yaw
//! centred and the roll/pitch stick in its forward-left corner for 2 s starts collecting;
//! the same gesture again fits, checks and stores it; tones confirm each step
//! (`flight_app::app`'s magcal module). The world has no magnetometer, so here the second
//! gesture finds no readings and is refused with its tone, nothing stored; the stored path
//! is `flight-core`'s `app::magcal_tests` (a synthetic rotation). Armed, the gesture does
//! nothing.

#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

mod common;

use common::*;
use flight_app::alerts::Alert;
use flight_sitl::{PilotInput, Sitl};

/// The gesture's stick position.
fn gesture(mode_switch: f32) -> PilotInput {
    PilotInput {
        throttle: 0.0,
        roll: -1.0,
        pitch: -1.0,
        yaw: 0.0,
        mode_switch,
        ..PilotInput::default()
    }
}

/// The pitches of `alert`'s pattern, in order.
fn pitches(alert: Alert) -> Vec<u16> {
    alert
        .tones()
        .iter()
        .map(|t| t.frequency_hz)
        .filter(|&f| f > 0)
        .collect()
}

/// When `alert`'s pattern started playing (its pitches in a row), if it did.
fn played(sitl: &Sitl, alert: Alert) -> Option<f64> {
    let want = pitches(alert);
    let mut heard: Vec<(f64, u16)> = Vec::new();
    for s in sitl.samples.iter().filter(|s| s.tone_hz > 0) {
        if heard.last().is_none_or(|&(_, f)| f != s.tone_hz) {
            heard.push((s.t_s, s.tone_hz));
        }
    }
    heard
        .windows(want.len())
        .find(|w| w.iter().map(|&(_, f)| f).eq(want.iter().copied()))
        .map(|w| w[0].0)
}

#[test]
fn the_gesture_starts_a_calibration_and_a_second_one_ends_it_with_tones() {
    // GIVEN a disarmed frame on the ground with the link up
    // WHEN the pilot holds the gesture from 1.0 to 3.6 s, lets go, and holds it again from
    // 5.0 to 7.6 s
    let sitl = fly(
        airframe_settings(),
        10.0,
        Box::new(|t| {
            if (1.0..3.6).contains(&t) || (5.0..7.6).contains(&t) {
                gesture(-1.0)
            } else {
                PilotInput {
                    mode_switch: -1.0,
                    ..PilotInput::default()
                }
            }
        }),
    );
    // THEN the start tone plays 2 s into the first hold, the refusal tone 2 s into the
    // second (no readings: the world has no magnetometer), the frame never arms, and the
    // magnetometer calibration in the settings is the factory one
    let started = played(&sitl, Alert::MagcalStarted).expect("the start tone");
    let refused = played(&sitl, Alert::MagcalRefused).expect("the refusal tone");
    println!("magcal started {started:.3} s, refused {refused:.3} s");
    assert!((3.0..3.7).contains(&started), "{started}");
    assert!((7.0..7.7).contains(&refused), "{refused}");
    assert!(played(&sitl, Alert::MagcalStored).is_none());
    assert!(sitl.samples.iter().all(|s| !s.out.armed));
    let factory = airframe_settings();
    for h in flight_app::settings::handles::MAG_CALIBRATION {
        assert_eq!(sitl.settings.get(h), factory.get(h), "{h:?}");
    }
}

#[test]
fn armed_the_gesture_does_nothing() {
    // GIVEN a frame armed on the ground (stick gesture, 0.5–2.0 s)
    // WHEN the pilot holds the calibration gesture from 2.5 to 6 s, throttle low
    let sitl = fly(
        airframe_settings(),
        8.0,
        pilot(-1.0, |_| PilotInput::default()),
    );
    let with_gesture = fly(
        airframe_settings(),
        8.0,
        Box::new({
            let mut base = pilot(-1.0, |_| PilotInput::default());
            move |t| {
                if (2.5..6.0).contains(&t) {
                    gesture(-1.0)
                } else {
                    base(t)
                }
            }
        }),
    );
    // THEN no calibration tone plays and the frame is armed throughout the hold
    assert!(sitl.samples.iter().any(|s| s.out.armed));
    assert!(played(&with_gesture, Alert::MagcalStarted).is_none());
    assert!(
        with_gesture
            .samples
            .iter()
            .filter(|s| (2.5..6.0).contains(&s.t_s))
            .all(|s| s.out.armed)
    );
}
