//! `magcal` from the console on synthetic rotations: a frame turned through every
//! orientation is calibrated, checked, stored and applied; a turn about one axis only is
//! refused and nothing is stored; nothing runs while armed.

use super::*;
use crate::pipeline::ImuSample;
use crate::settings::handles;
use crate::supervisor::Sticks;

/// Hard iron (raw units, µT-like) and symmetric soft iron: raw = SOFT · field + OFFSET.
const OFFSET: [f32; 3] = [21.0, -12.0, 33.0];
const SOFT: [[f32; 3]; 3] = [[1.20, 0.08, -0.03], [0.08, 0.90, 0.05], [-0.03, 0.05, 1.05]];
const FIELD: f32 = 50.0;

fn app() -> FlightApp {
    let Some(app) = FlightApp::new(Settings::default(), 0) else {
        panic!("factory settings make a setup");
    };
    app
}

fn raw(direction: [f32; 3]) -> [f32; 3] {
    let n = direction.iter().map(|v| v * v).sum::<f32>().sqrt();
    let b = direction.map(|v| FIELD * v / n);
    let mut out = OFFSET;
    for (o, row) in out.iter_mut().zip(SOFT) {
        *o += row.iter().zip(b).map(|(s, v)| s * v).sum::<f32>();
    }
    out
}

/// Feeds `n` samples 10 ms apart from `t0` with the field seen along `direction(i)`.
fn turn(app: &mut FlightApp, t0: u32, n: u32, direction: impl Fn(u32) -> [f32; 3]) -> u32 {
    app.link_input = LinkInput {
        up: true,
        sticks: Sticks::default(),
        arm_switch: None,
        mode_channel: -1.0,
    };
    for i in 0..n {
        let wiggle = (i % 13) as f32 * 1e-4;
        let sample = ImuSample {
            gyro_radps: [wiggle, -wiggle, 0.0],
            accel_mps2: [0.0, 0.0, -crate::estimation::GRAVITY_MPS2],
            mag: Some(raw(direction(i))),
        };
        let _ = app.on_imu_sample(t0 + 10 * i, &sample);
    }
    t0 + 10 * n
}

/// Every orientation: a Fibonacci sphere of field directions.
fn everywhere(i: u32) -> [f32; 3] {
    let golden = core::f32::consts::PI * (3.0 - 5.0f32.sqrt());
    let z = 1.0 - 2.0 * ((i % 1_500) as f32 + 0.5) / 1_500.0;
    let r = (1.0 - z * z).sqrt();
    let a = golden * i as f32;
    [r * a.cos(), r * a.sin(), z]
}

/// Yaw only, level: the field turns about the vertical (dip 60°).
fn yaw_only(i: u32) -> [f32; 3] {
    let a = 0.05 * i as f32;
    [0.5 * a.cos(), 0.5 * a.sin(), 0.866]
}

fn console(app: &mut FlightApp, line: &str) -> heapless::String<1024> {
    let mut out = heapless::String::new();
    let _ = app.on_console_line(line, &mut out);
    out
}

#[test]
fn a_turn_through_every_orientation_is_checked_stored_and_applied() {
    // GIVEN a disarmed frame and a calibration started from the console
    let mut app = app();
    assert!(console(&mut app, "magcal start").contains("turn the frame"));
    // WHEN the owner turns it through every orientation for 15 s
    turn(&mut app, 0, 1_500, everywhere);
    let status = console(&mut app, "magcal status");
    assert!(status.contains("checks pass"), "{status}");
    assert!(app.magcal().len() >= 100, "{}", app.magcal().len());
    let saved = console(&mut app, "magcal save");
    // THEN the checks pass, the offset and shape are stored and a save is requested
    assert!(saved.contains("stored"), "{saved}");
    let s = app.settings();
    for (handle, want) in handles::MAG_CALIBRATION.iter().zip(OFFSET) {
        let got = s.get(*handle);
        assert!((got - want).abs() < 0.2, "{handle:?} {got}");
    }
    assert!(app.take_save().is_some());
    assert!(!app.magcal().collecting());
    // AND the readings the estimator gets are calibrated: round, whatever the direction
    // (the loop takes the new calibration with its next step)
    app.on_imu_sample(600_000, &crate::app::tests::resting(7));
    let cal = *app.loop_side().unwrap().mag_calibration();
    let field = |d: [f32; 3]| {
        let c = cal.apply(raw(d));
        c.iter().map(|v| v * v).sum::<f32>().sqrt()
    };
    let (a, b) = (field([1.0, 0.0, 0.0]), field([0.0, 0.3, -1.0]));
    assert!((a - b).abs() / a < 0.01, "{a} {b}");
}

#[test]
fn a_turn_about_one_axis_is_refused_and_nothing_is_stored() {
    let mut app = app();
    let _ = console(&mut app, "magcal start");
    turn(&mut app, 0, 1_500, yaw_only);
    let saved = console(&mut app, "magcal save");
    assert!(
        saved.contains("refused") && saved.contains("single plane"),
        "{saved}"
    );
    assert_eq!(app.settings(), &Settings::default());
    assert!(app.take_save().is_none());
    // Still collecting: the owner can go on turning.
    assert!(app.magcal().collecting());
    assert!(console(&mut app, "magcal cancel").contains("nothing stored"));
    assert!(app.magcal().is_empty());
    assert!(console(&mut app, "magcal save").contains("magcal start first"));
}

#[test]
fn magcal_is_refused_while_armed_and_arming_ends_a_collection() {
    let mut app = app();
    let _ = console(&mut app, "magcal start");
    // Arm (stick gesture) and climb: the collection ends at the first armed sample.
    app.link_input = LinkInput {
        up: true,
        sticks: Sticks {
            yaw: 1.0,
            ..Sticks::default()
        },
        arm_switch: None,
        mode_channel: -1.0,
    };
    for t in 0..1_600 {
        let wiggle = (t % 13) as f32 * 1e-4;
        let sample = ImuSample {
            gyro_radps: [wiggle, -wiggle, 0.0],
            accel_mps2: [0.0, 0.0, -crate::estimation::GRAVITY_MPS2],
            mag: None,
        };
        let _ = app.on_imu_sample(t, &sample);
    }
    assert!(app.armed());
    assert!(!app.magcal().collecting());
    for line in [
        "magcal start",
        "magcal status",
        "magcal save",
        "magcal cancel",
    ] {
        assert!(
            console(&mut app, line).contains("refused: disarm first"),
            "{line}"
        );
    }
    assert!(!app.magcal().collecting());
}

/// Holds the calibration's stick gesture for 2.2 s from `t0` (link up, disarmed, 1 kHz);
/// returns the end time and the tones heard.
fn hold_gesture(app: &mut FlightApp, t0: u32, up: bool) -> (u32, std::vec::Vec<u16>) {
    app.link_input = LinkInput {
        up,
        sticks: Sticks {
            throttle: 0.0,
            roll: -1.0,
            pitch: -1.0,
            yaw: 0.0,
        },
        arm_switch: None,
        mode_channel: -1.0,
    };
    let mut tones = std::vec::Vec::new();
    for t in t0..t0 + 3_500 {
        if t == t0 + 2_200 {
            // Let the tone finish with the sticks released.
            app.link_input.sticks = Sticks::default();
        }
        let _ = app.on_imu_sample(t, &still(t));
        tones.push(app.on_alert_tick(t));
    }
    (t0 + 3_500, tones)
}

fn heard(tones: &[u16], pattern: &[crate::alerts::Tone]) -> bool {
    let pitches: std::vec::Vec<u16> = pattern
        .iter()
        .map(|t| t.frequency_hz)
        .filter(|&f| f > 0)
        .collect();
    let mut played: std::vec::Vec<u16> = tones.iter().copied().filter(|&f| f > 0).collect();
    played.dedup();
    played
        .windows(pitches.len())
        .any(|w| w == pitches.as_slice())
}

#[test]
fn the_stick_gesture_starts_and_stores_a_calibration_with_tones() {
    use crate::alerts::Alert;
    // GIVEN a disarmed frame with the link up
    let mut app = app();
    // WHEN the pilot holds the gesture for 2 s
    let (t, tones) = hold_gesture(&mut app, 0, true);
    // THEN collecting starts, confirmed by its tone
    assert!(app.magcal().collecting());
    assert!(heard(&tones, Alert::MagcalStarted.tones()), "{tones:?}");
    // WHEN the frame is turned through every orientation and the gesture held again
    let t = turn(&mut app, t, 1_500, everywhere);
    let (_, tones) = hold_gesture(&mut app, t, true);
    // THEN the calibration is stored, a save requested, and the stored tone plays
    assert!(heard(&tones, Alert::MagcalStored.tones()), "{tones:?}");
    let s = app.settings();
    for (handle, want) in handles::MAG_CALIBRATION.iter().zip(OFFSET) {
        let got = s.get(*handle);
        assert!((got - want).abs() < 0.2, "{handle:?} {got}");
    }
    assert!(app.take_save().is_some());
    assert!(!app.magcal().collecting());
}

#[test]
fn a_refused_gesture_calibration_stores_nothing_and_says_so() {
    use crate::alerts::Alert;
    let mut app = app();
    let (t, _) = hold_gesture(&mut app, 0, true);
    let t = turn(&mut app, t, 1_500, yaw_only);
    let (_, tones) = hold_gesture(&mut app, t, true);
    assert!(heard(&tones, Alert::MagcalRefused.tones()), "{tones:?}");
    assert_eq!(app.settings(), &Settings::default());
    assert!(app.take_save().is_none());
    assert!(!app.magcal().collecting(), "a refused session is dropped");
}

#[test]
fn the_gesture_does_nothing_without_the_link_or_when_not_held_long_enough() {
    let mut app = app();
    let (t, tones) = hold_gesture(&mut app, 0, false);
    assert!(!app.magcal().collecting());
    assert!(tones.iter().all(|&f| f == 0), "{tones:?}");
    // Held 1.9 s only.
    app.link_input.up = true;
    app.link_input.sticks = Sticks {
        throttle: 0.0,
        roll: -1.0,
        pitch: -1.0,
        yaw: 0.0,
    };
    for t in t..t + 1_900 {
        let _ = app.on_imu_sample(t, &still(t));
    }
    assert!(!app.magcal().collecting());
}

/// A still frame's sample with the noise a real IMU has (an exactly repeated one is a
/// frozen sensor to the fault policy).
fn still(t: u32) -> ImuSample {
    let wiggle = (t % 13) as f32 * 1e-4;
    ImuSample {
        gyro_radps: [wiggle, -wiggle, 0.0],
        accel_mps2: [0.0, 0.0, -crate::estimation::GRAVITY_MPS2],
        mag: None,
    }
}
