//! The served world's pilot: the one scripted thing in it. A person at the transmitter who
//! flies the same minute again and again — on the ground until [`ARM_AT_S`], the arming
//! gesture, take-off, a hover at [`HOVER_M`] holding the height by eye (the quad-sim truth the
//! world shows, [`Sight`]), roll and pitch steps, the mode switch to rate for
//! [`RATE_FROM_S`]…[`RATE_TO_S`] (levelling the frame by eye meanwhile), a yaw turn, a slow
//! descent, throttle closed once down (the flight side's idle timeout disarms), then on the
//! ground until the minute is over.
//! Everything the flight side does with these sticks is `FlightApp`'s.

use crate::runner::pilot::{HOLD_AUTHORITY, KD_PER_MPS, KP_PER_M};
use crate::scenario::{PilotInput, Piloting, Sight};

/// Length of one flight, s (scenario time; the world's warm-up comes before the first).
pub const CYCLE_S: f64 = 60.0;
/// Arming gesture (throttle low, yaw right, held 1.5 s), s into the cycle.
pub const ARM_AT_S: f64 = 4.5;
const ARM_END_S: f64 = 6.0;
/// Take-off: from here the pilot flies towards the hover height by eye (no boost: the
/// eye-and-hand loop is slow, ωn ≈ 0.5 rad/s, and would carry a fast climb metres past it), s.
const TAKEOFF_S: f64 = 6.5;
/// The hover height, m.
pub const HOVER_M: f64 = 5.0;
/// Stick steps in attitude mode: (from, to, roll, pitch, yaw), s and stick units (a third of
/// `attitude.max_deg` = 15° at the factory 45°; yaw a 72° turn at a tenth of `rate.max_dps`).
const STEPS: [(f64, f64, f32, f32, f32); 4] = [
    (10.0, 12.0, 0.33, 0.0, 0.0),
    (12.5, 14.5, 0.0, -0.33, 0.0),
    (26.0, 27.0, 0.0, 0.0, 0.1),
    (28.0, 30.0, -0.33, 0.33, 0.0),
];
/// The mode switch in its middle position (factory `mode.switch_mid`: rate PID), s.
pub const RATE_FROM_S: f64 = 16.0;
/// … back to low (attitude), s.
pub const RATE_TO_S: f64 = 24.0;
/// In rate mode the pilot levels the frame by eye: stick per degree of tilt, and its limit.
const LEVEL_PER_DEG: f64 = 0.005;
const LEVEL_MAX: f64 = 0.2;
/// The descent starts here, at this rate, s and m/s.
const DESCEND_S: f64 = 30.0;
const DESCENT_MPS: f64 = 0.5;
// Once down the pilot closes the throttle and leaves the sticks alone: the flight side
// disarms on its idle timeout (`arm.idle_disarm_ms`, 10 s). (The disarm gesture once lifted
// the frame here — full yaw at a closed throttle flown in air mode after the landing; since
// the fix it disarms on the ground, `tests/disarm_gesture.rs`; this pilot still idles.)

/// The pilot of the served world.
#[derive(Debug, Clone)]
pub struct ServedPilot {
    trim: f32,
    /// The pilot saw the frame come down in this cycle.
    landed: bool,
}

impl ServedPilot {
    /// A pilot whose hover trim is `trim` (the frame's hover throttle through the output
    /// idle, as `runner::pilot::PilotPlan::climb` works it out).
    pub fn new(trim: f32) -> Self {
        Self {
            trim,
            landed: false,
        }
    }

    /// Throttle holding `target_m`: the runner pilot's eye-and-hand loop, watched all the time.
    fn hold(&self, target_m: f64, sight: &Sight) -> f32 {
        let correction = (KP_PER_M * (target_m - sight.altitude_m) - KD_PER_MPS * sight.climb_mps)
            .clamp(-HOLD_AUTHORITY, HOLD_AUTHORITY);
        (f64::from(self.trim) + correction).clamp(0.0, 1.0) as f32
    }
}

impl Piloting for ServedPilot {
    fn input(&mut self, t_s: f64, sight: &Sight) -> PilotInput {
        let base = PilotInput::default();
        let c = t_s.rem_euclid(CYCLE_S);
        if c < ARM_AT_S {
            self.landed = false;
            return base;
        }
        if c < ARM_END_S {
            return PilotInput { yaw: 1.0, ..base };
        }
        if c < TAKEOFF_S {
            return base;
        }
        let descending = c >= DESCEND_S;
        self.landed |= descending && sight.on_ground;
        if self.landed {
            // Down: throttle closed, hands off.
            return base;
        }
        let target_m = if descending {
            HOVER_M - DESCENT_MPS * (c - DESCEND_S)
        } else {
            HOVER_M
        };
        let mut input = PilotInput {
            throttle: self.hold(target_m, sight),
            ..base
        };
        if (RATE_FROM_S..RATE_TO_S).contains(&c) {
            input.mode_switch = 0.0;
            let level = |deg: f64| (-LEVEL_PER_DEG * deg).clamp(-LEVEL_MAX, LEVEL_MAX) as f32;
            input.roll = level(sight.attitude_deg[0]);
            input.pitch = level(sight.attitude_deg[1]);
        } else if let Some(&(_, _, roll, pitch, yaw)) = STEPS
            .iter()
            .find(|(from, to, ..)| (*from..*to).contains(&c))
        {
            input.roll = roll;
            input.pitch = pitch;
            input.yaw = yaw;
        }
        input
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(pilot: &mut ServedPilot, t: f64, sight: Sight) -> PilotInput {
        pilot.input(t, &sight)
    }

    #[test]
    fn one_minute_of_flying_again_and_again() {
        let mut p = ServedPilot::new(0.11);
        let ground = Sight {
            on_ground: true,
            ..Sight::default()
        };
        let hovering = Sight {
            altitude_m: HOVER_M,
            ..Sight::default()
        };
        assert_eq!(at(&mut p, 1.0, ground), PilotInput::default());
        assert_eq!(at(&mut p, 5.0, ground).yaw, 1.0);
        assert_eq!(at(&mut p, 5.0, ground).throttle, 0.0);
        assert!(at(&mut p, 7.0, ground).throttle > 0.11);
        // At the height, still: the trim; 1 m low: more.
        assert_eq!(at(&mut p, 9.0, hovering).throttle, 0.11);
        let low = Sight {
            altitude_m: HOVER_M - 1.0,
            ..hovering
        };
        assert!(at(&mut p, 9.0, low).throttle > 0.11);
        assert_eq!(at(&mut p, 11.0, hovering).roll, 0.33);
        // Rate mode: the mode switch mid, the frame levelled by eye.
        let banked = Sight {
            attitude_deg: [10.0, -4.0, 0.0],
            ..hovering
        };
        let rate = at(&mut p, 20.0, banked);
        assert_eq!(rate.mode_switch, 0.0);
        assert!(rate.roll < 0.0 && rate.pitch > 0.0, "{rate:?}");
        assert_eq!(at(&mut p, 25.0, hovering).mode_switch, -1.0);
        // Descending: the target falls 0.5 m/s, so at the hover height it asks for less.
        assert!(at(&mut p, 36.0, hovering).throttle < 0.11);
        // Still in the air: flown down.
        let above = at(&mut p, 43.0, hovering);
        assert_eq!(above.yaw, 0.0);
        assert!(above.throttle < 0.11);
        // Down at 44 s: throttle closed, hands off (whatever it bounces to).
        assert_eq!(at(&mut p, 44.0, ground), PilotInput::default());
        assert_eq!(at(&mut p, 45.0, hovering), PilotInput::default());
        assert_eq!(at(&mut p, 50.0, ground), PilotInput::default());
        // The next minute is the same.
        assert_eq!(at(&mut p, CYCLE_S + 5.0, ground).yaw, 1.0);
    }
}
