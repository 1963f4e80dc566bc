//! The scripted pilot of the runner's scenarios: arm (stick gesture, or the arm switch when
//! `arm.channel` is set), take off, climb, and hold the wanted altitude with a P loop (plus a
//! damping term on the climb rate) on the *true* altitude, as a pilot does by eye. This is
//! the person at the transmitter, not firmware: nothing here decides anything the flight
//! controller decides.
//!
//! The world shows the pilot the frame as it is (`crate::Sight`: the quad-sim truth after each
//! physics step). The pilot looks at it in *glances*, every [`GLANCE_S`], as a person does,
//! and holds the throttle in between; the runner's pilot (`super::PlanPilot`) records each
//! glance into the plan as it takes it.
//!
//! In the hold scenarios the pilot, once settled at the altitude, flicks the mode switch high
//! ([`PilotPlan::engage_s`]) and centres the throttle stick: from then on the flight
//! controller holds, and the pilot only moves the pitch stick when the plan says
//! ([`PilotPlan::push`]).

use crate::scenario::PilotInput;
use quad_sim::quad::QuadParams;

/// Stick gesture (throttle low, yaw right) from this time after the pilot starts, s.
pub const GESTURE_FROM_S: f64 = 0.5;
/// … until this time (the supervisor wants it held 1 s), s.
pub const GESTURE_TO_S: f64 = 2.0;
/// Take-off throttle from this time, s.
pub const TAKEOFF_S: f64 = 2.5;
/// Take-off boost until this time, then the cruise throttle, s.
pub const BOOST_END_S: f64 = 3.5;
/// Take-off boost throttle (climbs ≈ 3.5 m/s after 1 s on the 250-class quad).
pub const BOOST_THROTTLE: f32 = 0.17;
/// Cruise throttle of the climb (a touch above hover: keeps climbing, slowly bleeding speed).
pub const CRUISE_THROTTLE: f32 = 0.12;
/// Time between the pilot's glances at the frame while holding the altitude, s.
pub const GLANCE_S: f64 = 0.5;
/// Throttle per metre of altitude error (a 5 m error asks 0.02 more throttle).
pub const KP_PER_M: f64 = 0.004;
/// Throttle per m/s of climb (damping: with ≈ 61 m/s² per unit throttle on the 250-class
/// quad, ≈ 1.4 s to spend a climb).
pub const KD_PER_MPS: f64 = 0.012;
/// The pilot's throttle authority around the trim while holding.
pub const HOLD_AUTHORITY: f64 = 0.06;

/// The pilot starts holding this far below the wanted altitude (from the ≈ 3.3 m/s cruise
/// climb, the damping term spends the climb in ≈ 2 m), m.
pub const HOLD_LEAD_M: f64 = 2.0;

/// What the pilot saw at one glance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Glance {
    /// When, s.
    pub t_s: f64,
    /// True altitude above ground, m.
    pub altitude_m: f64,
    /// True climb rate, m/s.
    pub climb_mps: f64,
}

/// How the pilot flies one scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct PilotPlan {
    /// When the pilot starts (arming gesture `GESTURE_FROM_S` after it), s.
    pub start_s: f64,
    /// Whether the pilot takes off after arming (false: stays on the ground at zero throttle).
    pub take_off: bool,
    /// Arm with the switch on this channel instead of the stick gesture (`arm.channel`).
    pub arm_switch: bool,
    /// Hold `target_m` from this time (None: climb on), s.
    pub hold_from_s: Option<f64>,
    /// The altitude to hold, m.
    pub target_m: f64,
    /// What the pilot saw while holding, in time order (the first at `hold_from_s`).
    pub glances: Vec<Glance>,
    /// Throttle that holds the height (the frame's hover throttle through the output idle).
    pub trim: f32,
    /// From this time the pilot closes the throttle and leaves the sticks alone (landing or
    /// having lost the aircraft), s.
    pub hands_off_s: Option<f64>,
    /// From this time the pilot starts over (arms again and takes off), s.
    pub rearm_s: Option<f64>,
    /// From this time the mode switch is high and the throttle stick centred (a hold mode
    /// flies), s.
    pub engage_s: Option<f64>,
    /// The pitch stick held at `pitch` over [from, to) s while engaged (loiter).
    pub push: Option<Push>,
}

/// The pilot holding the pitch stick for a while.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Push {
    /// From, s.
    pub from_s: f64,
    /// To, s.
    pub to_s: f64,
    /// Stick, −1…1 (negative: forward, nose down).
    pub pitch: f32,
}

impl PilotPlan {
    /// A pilot that arms at the start, takes off and climbs on; trim and braking for `quad`
    /// through the flight settings' output idle `idle` (0…0.3).
    pub fn climb(quad: &QuadParams, idle: f32) -> Self {
        let idle = f64::from(idle);
        let hover = quad.hover_throttle();
        let trim = ((hover - idle) / (1.0 - idle)).clamp(0.0, 1.0);
        Self {
            start_s: 0.0,
            take_off: true,
            arm_switch: false,
            hold_from_s: None,
            target_m: 0.0,
            glances: Vec::new(),
            trim: trim as f32,
            hands_off_s: None,
            rearm_s: None,
            engage_s: None,
            push: None,
        }
    }

    /// Holds `target_m` from `t_s` (glances still to be taken).
    pub fn hold(mut self, t_s: f64, target_m: f64) -> Self {
        self.hold_from_s = Some(t_s);
        self.target_m = target_m;
        self.glances.clear();
        self
    }

    /// When the next glance is due (None: not holding).
    pub fn next_glance_s(&self) -> Option<f64> {
        let from = self.hold_from_s?;
        #[allow(clippy::cast_precision_loss)]
        Some(from + self.glances.len() as f64 * GLANCE_S)
    }

    /// The holding throttle after the glances up to `t_s`.
    fn holding(&self, t_s: f64) -> f32 {
        let seen = self.glances.iter().rev().find(|g| g.t_s <= t_s);
        // Before the first glance, and once the pilot has stopped looking (a glance
        // interval after the last), the trim: a correction is only held while watched.
        let Some(g) = seen.filter(|g| t_s < g.t_s + GLANCE_S) else {
            return self.trim;
        };
        let correction = (KP_PER_M * (self.target_m - g.altitude_m) - KD_PER_MPS * g.climb_mps)
            .clamp(-HOLD_AUTHORITY, HOLD_AUTHORITY);
        (f64::from(self.trim) + correction).clamp(0.0, 1.0) as f32
    }

    /// The sticks and switches at `t_s` (everything else at the defaults).
    pub fn input(&self, t_s: f64) -> PilotInput {
        if let Some(r) = self.rearm_s
            && t_s >= r
        {
            let again = Self {
                start_s: r,
                take_off: true,
                rearm_s: None,
                ..self.clone()
            };
            return again.input(t_s);
        }
        let base = PilotInput::default();
        let t = t_s - self.start_s;
        if t < 0.0 || self.hands_off_s.is_some_and(|h| t_s >= h) {
            return base;
        }
        let arming = if self.arm_switch {
            PilotInput {
                arm_switch: if t >= GESTURE_FROM_S { 1.0 } else { -1.0 },
                ..base
            }
        } else if (GESTURE_FROM_S..GESTURE_TO_S).contains(&t) {
            PilotInput { yaw: 1.0, ..base }
        } else {
            base
        };
        if !self.take_off || t < TAKEOFF_S {
            return arming;
        }
        if let Some(e) = self.engage_s
            && t_s >= e
        {
            let pitch = self
                .push
                .filter(|p| (p.from_s..p.to_s).contains(&t_s))
                .map_or(0.0, |p| p.pitch);
            return PilotInput {
                throttle: 0.5,
                mode_switch: 1.0,
                pitch,
                yaw: 0.0,
                ..arming
            };
        }
        let throttle = if t < BOOST_END_S {
            BOOST_THROTTLE
        } else {
            match self.hold_from_s {
                Some(h) if t_s >= h => self.holding(t_s),
                _ => CRUISE_THROTTLE,
            }
        };
        PilotInput {
            throttle,
            yaw: 0.0,
            ..arming
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flight_app::control::mixer::QUAD_X;

    #[test]
    fn arms_takes_off_climbs_and_holds_on_what_it_saw() {
        let quad = QuadParams::quad_x(10.0, 6.5, 0.03, &QUAD_X);
        let mut plan = PilotPlan::climb(&quad, 0.05).hold(10.0, 5.0);
        // Hover 0.153 of full thrust through a 0.05 idle.
        assert!((plan.trim - 0.1087).abs() < 1e-3, "{}", plan.trim);
        assert_eq!(plan.input(1.0).yaw, 1.0);
        assert_eq!(plan.input(1.0).throttle, 0.0);
        assert_eq!(plan.input(2.2).yaw, 0.0);
        assert_eq!(plan.input(3.0).throttle, BOOST_THROTTLE);
        assert_eq!(plan.input(5.0).throttle, CRUISE_THROTTLE);
        // Holding before the first glance: the trim.
        assert_eq!(plan.next_glance_s(), Some(10.0));
        assert_eq!(plan.input(10.2).throttle, plan.trim);
        // 1 m too high and climbing 2 m/s: 0.004 + 0.024 less, held until the next glance.
        plan.glances.push(Glance {
            t_s: 10.0,
            altitude_m: 6.0,
            climb_mps: 2.0,
        });
        assert_eq!(plan.next_glance_s(), Some(10.5));
        let expected = plan.trim - 0.028;
        assert!((plan.input(10.2).throttle - expected).abs() < 1e-6);
        assert!((plan.input(10.49).throttle - expected).abs() < 1e-6);
        // Not watched any more: back to the trim.
        assert_eq!(plan.input(10.7).throttle, plan.trim);
        // Far too low: the correction is bounded.
        plan.glances.push(Glance {
            t_s: 10.5,
            altitude_m: -100.0,
            climb_mps: 0.0,
        });
        assert!((plan.input(10.6).throttle - (plan.trim + 0.06)).abs() < 1e-6);
        assert_eq!(plan.next_glance_s(), Some(11.0));
        let hands_off = PilotPlan {
            hands_off_s: Some(12.0),
            ..plan
        };
        assert_eq!(hands_off.input(12.5), PilotInput::default());
    }

    #[test]
    fn an_engaged_pilot_centres_the_throttle_flicks_the_switch_and_pushes_when_told() {
        let quad = QuadParams::quad_x(10.0, 6.5, 0.03, &QUAD_X);
        let plan = PilotPlan {
            engage_s: Some(10.0),
            push: Some(Push {
                from_s: 12.0,
                to_s: 13.0,
                pitch: -0.5,
            }),
            ..PilotPlan::climb(&quad, 0.05).hold(8.0, 5.0)
        };
        let before = plan.input(9.9);
        assert_eq!((before.mode_switch, before.pitch), (-1.0, 0.0));
        let on = plan.input(10.0);
        assert_eq!((on.throttle, on.mode_switch, on.pitch), (0.5, 1.0, 0.0));
        assert_eq!(plan.input(12.5).pitch, -0.5);
        assert_eq!(plan.input(13.0).pitch, 0.0);
        assert_eq!(plan.input(13.0).mode_switch, 1.0);
    }

    #[test]
    fn a_switch_pilot_flicks_the_switch_with_the_throttle_low() {
        let quad = QuadParams::quad_x(10.0, 6.5, 0.03, &QUAD_X);
        let plan = PilotPlan {
            arm_switch: true,
            start_s: 5.0,
            ..PilotPlan::climb(&quad, 0.05)
        };
        assert_eq!(plan.input(5.2).arm_switch, -1.0);
        let on = plan.input(6.0);
        assert_eq!((on.arm_switch, on.yaw, on.throttle), (1.0, 0.0, 0.0));
        assert_eq!(plan.input(8.0).throttle, BOOST_THROTTLE);
    }
}
