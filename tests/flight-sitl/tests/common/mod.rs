//! The shared pilot script and flight helpers of the SITL tests: link sync, stick-gesture
//! arming (throttle low, yaw right, 1 s: armed at 1.507 s), take-off, hover.

// Each test file uses its own subset.
#![allow(dead_code)]
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::cast_precision_loss
)]

use flight_app::settings::Settings;
use flight_sitl::scenario::default_airframe;
use flight_sitl::{PilotInput, Scenario, Sitl, run};

/// Arming gesture from 0.5 s to 2.0 s.
pub const ARMED_BY_S: f64 = 2.0;
/// Take-off throttle from 2.5 s, hover-ish throttle from `CLIMB_END_S`.
pub const TAKEOFF_S: f64 = 2.5;
pub const CLIMB_END_S: f64 = 3.5;
pub const CLIMB_THROTTLE: f32 = 0.17;
/// Hover: 0.5 kg · g / (4 · 8 N) = 0.153 thrust; with idle 0.05, (0.153 − 0.05)/0.95 = 0.109.
pub const CRUISE_THROTTLE: f32 = 0.11;

/// The common start: gesture, take-off, cruise; `then` decides after `CLIMB_END_S`.
pub fn pilot(
    mode_switch: f32,
    then: impl Fn(f64) -> PilotInput + 'static,
) -> Box<dyn FnMut(f64) -> PilotInput> {
    Box::new(move |t| {
        let base = PilotInput {
            mode_switch,
            ..PilotInput::default()
        };
        if t < 0.5 {
            base
        } else if t < ARMED_BY_S {
            PilotInput { yaw: 1.0, ..base }
        } else if t < TAKEOFF_S {
            base
        } else if t < CLIMB_END_S {
            PilotInput {
                throttle: CLIMB_THROTTLE,
                ..base
            }
        } else {
            then(t)
        }
    })
}

pub fn cruise(mode_switch: f32) -> PilotInput {
    PilotInput {
        mode_switch,
        throttle: CRUISE_THROTTLE,
        ..PilotInput::default()
    }
}

pub fn fly(settings: Settings, seconds: f64, pilot: Box<dyn FnMut(f64) -> PilotInput>) -> Sitl {
    let (quad, _) = default_airframe();
    run(Scenario::new(settings, quad, seconds, pilot))
}

pub fn airframe_settings() -> Settings {
    default_airframe().1
}
