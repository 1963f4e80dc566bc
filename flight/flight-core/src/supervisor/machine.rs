//! The arming / failsafe state machine.
//!
//! ```text
//!            arm gesture + all preconditions             link lost
//! Disarmed ─────────────────────────────────▶ Armed ─────────────────▶ Failsafe
//!    ▲  ▲      disarm gesture / idle on ground  │   link back + sticks    │
//!    │  └───────────────────────────────────────┘◀──────── centred ───────┤
//!    └──────────────── touchdown detected (or the last resort) ──────────┘
//! ```
//! Motors turn only in `Armed` and `Failsafe`; in `Failsafe` the controller levels and
//! descends at a fixed rate, ignoring the (stale) sticks. Both automatic disarms — the idle
//! disarm and the end of a failsafe — wait for the touchdown detector
//! ([`LandingDetector`](super::LandingDetector)), so neither stops the motors in the air. The
//! only timed cut is the failsafe's last resort ([`last_resort_ms`]), for a frame whose
//! landing cannot be detected (no baro): long enough to descend from
//! [`LAST_RESORT_ALTITUDE_M`] at the set rate.

use super::{Gesture, GestureDetector, Sticks};

/// Tunables, with safe defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Settings {
    /// How long a stick gesture must be held.
    pub gesture_hold_ms: u32,
    /// Disarm after the throttle has been low this long while armed and landed.
    pub idle_disarm_ms: u32,
    /// Descent rate during failsafe, m/s.
    pub failsafe_descent_mps: f32,
    /// How close to centre roll/pitch/yaw must be to take control back after a failsafe.
    pub centre_deadband: f32,
    /// Arm even when the battery is at its critical level (the pilot's explicit choice).
    pub arm_on_critical_battery: bool,
}

/// The altitude a failsafe descent is assumed to start from at most, m, for the last-resort
/// time limit. 200 m is the 120 m (400 ft) ceiling of EU and FAA rules with two thirds
/// margin; a frame higher than that has usually run its battery flat before it could land.
pub const LAST_RESORT_ALTITUDE_M: f32 = 200.0;

/// How long a failsafe lasts before the motors are cut even though no touchdown was detected,
/// ms: the time to descend [`LAST_RESORT_ALTITUDE_M`] at `descent_mps` (286 s at the factory
/// 0.7 m/s). A documented last resort for frames whose landing cannot be detected (no
/// vertical estimate); with one, the touchdown detector ends the failsafe long before.
pub fn last_resort_ms(descent_mps: f32) -> u32 {
    let rate = if descent_mps.is_finite() {
        descent_mps.max(0.1)
    } else {
        0.1
    };
    // At most 2000 s: far below u32::MAX ms, and the cast saturates anyway.
    (LAST_RESORT_ALTITUDE_M / rate * 1000.0).min(2_000_000.0) as u32
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            gesture_hold_ms: 1_000,
            idle_disarm_ms: 10_000,
            failsafe_descent_mps: 0.7,
            centre_deadband: 0.1,
            arm_on_critical_battery: false,
        }
    }
}

/// What the supervisor looks at each loop.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Inputs {
    /// Milliseconds since boot (wrapping).
    pub now_ms: u32,
    /// The link delivers fresh channels (not in failsafe).
    pub link_up: bool,
    /// The sticks from the link (meaningless while the link is down).
    pub sticks: Sticks,
    /// The arm switch, if one is configured.
    pub arm_switch: Option<bool>,
    /// IMU (and whatever the mode needs) reading and plausible.
    pub sensors_healthy: bool,
    /// Controller gains are solved (the LQG Riccati solution runs before take-off).
    pub gains_ready: bool,
    /// The touchdown detector says the frame stands on the ground. The idle disarm and the
    /// stick disarm gesture only count while it does, and a failsafe ends (disarms) only
    /// once it does.
    pub landed: bool,
    /// A vertical estimate exists, so `landed` can become true again after a take-off.
    /// Without one the stick disarm cannot wait for a touchdown and counts whenever the
    /// throttle is low (the loop does not fly the yaw stick then, so the gesture cannot
    /// lift the frame).
    pub landing_detectable: bool,
    /// The battery is at its critical level.
    pub battery_critical: bool,
    /// The settings loaded at boot had a problem (corrupt, invalid, refused values): the
    /// frame flies nothing until the pilot saves a set.
    pub settings_problem: bool,
    /// A USB host has the console (the board enumerated): arming is refused. The frame is on
    /// the bench, tethered by a cable; settings may change under the pilot's hands; and a
    /// board powered from the port browns out when motors start. Disconnecting or connecting
    /// while armed changes nothing (a cable caught in flight must not disarm).
    pub usb_connected: bool,
}

/// The supervisor's state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum State {
    /// Motors stopped.
    Disarmed,
    /// The pilot flies.
    Armed,
    /// Link lost while armed: level and descend, since `since_ms`.
    Failsafe {
        /// When the failsafe began.
        since_ms: u32,
    },
}

/// Why an arm gesture was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ArmBlocker {
    /// No link.
    LinkDown,
    /// Throttle not at the bottom.
    ThrottleNotLow,
    /// Sensors not healthy.
    SensorsUnhealthy,
    /// Gains not solved yet.
    GainsNotReady,
    /// The battery is at its critical level (setting `arm.critical_battery` overrides).
    BatteryCritical,
    /// The stored settings had a problem at boot; fixed by a successful save.
    SettingsProblem,
    /// A USB host has the console (unplug to fly).
    UsbConnected,
}

/// What happened this loop (for alerts and telemetry), besides the state itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Decision {
    /// Nothing new.
    Steady,
    /// Just armed.
    Armed,
    /// An arm gesture was refused.
    ArmRefused(ArmBlocker),
    /// Disarmed by gesture.
    DisarmedByPilot,
    /// Disarmed after idling on the ground.
    DisarmedIdle,
    /// Disarmed at the end of a failsafe: touchdown detected.
    DisarmedFailsafe,
    /// Disarmed by the failsafe's last-resort time limit, no touchdown detected.
    DisarmedLastResort,
    /// Link lost while armed.
    FailsafeEntered,
    /// Link back and sticks centred: the pilot has control again.
    ControlRecovered,
    /// Disarmed because the attitude sensor stopped delivering usable data (the frame can
    /// no longer sense its attitude). Only a fresh arm restarts the motors.
    DisarmedSensorFault,
    /// Back in the air after a reset: the link shows the arm switch still on (or no arm switch
    /// is set) — armed in the mode the frame had ([`Supervisor::resume`]).
    Resumed,
}

/// The state machine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Supervisor {
    settings: Settings,
    state: State,
    gestures: GestureDetector,
    throttle_low_since: Option<u32>,
    /// In failsafe since a reset in the air, waiting for the link's word ([`Self::resume`]).
    resumed: bool,
}

impl Supervisor {
    /// Starts disarmed: motors are stopped from power-on.
    pub fn new(settings: Settings) -> Self {
        Self {
            settings,
            state: State::Disarmed,
            gestures: GestureDetector::new(settings.gesture_hold_ms),
            throttle_low_since: None,
            resumed: false,
        }
    }

    /// The board reset in the air while armed (`app::resume`): the motors run again at once,
    /// in failsafe — levelling, descending or holding as a link loss would — until the link
    /// delivers: then the arm switch decides, on (or no arm switch set) is
    /// [`Decision::Resumed`] and armed, off disarms. A link that never comes back is the
    /// failsafe as usual, landing and disarming on touchdown.
    pub fn resume(&mut self, now_ms: u32) {
        self.state = State::Failsafe { since_ms: now_ms };
        self.throttle_low_since = None;
        self.resumed = true;
    }

    /// Current state.
    pub fn state(&self) -> State {
        self.state
    }

    /// Whether the motors may turn.
    pub fn motors_enabled(&self) -> bool {
        !matches!(self.state, State::Disarmed)
    }

    /// Failsafe descent rate when in failsafe, else `None`.
    pub fn failsafe_descent_mps(&self) -> Option<f32> {
        matches!(self.state, State::Failsafe { .. }).then_some(self.settings.failsafe_descent_mps)
    }

    fn blocker(&self, inputs: &Inputs) -> Option<ArmBlocker> {
        if !inputs.link_up || !inputs.sticks.is_finite() {
            Some(ArmBlocker::LinkDown)
        } else if !inputs.sticks.throttle_low() {
            Some(ArmBlocker::ThrottleNotLow)
        } else if !inputs.sensors_healthy {
            Some(ArmBlocker::SensorsUnhealthy)
        } else if !inputs.gains_ready {
            Some(ArmBlocker::GainsNotReady)
        } else if inputs.battery_critical && !self.settings.arm_on_critical_battery {
            Some(ArmBlocker::BatteryCritical)
        } else if inputs.settings_problem {
            Some(ArmBlocker::SettingsProblem)
        } else if inputs.usb_connected {
            Some(ArmBlocker::UsbConnected)
        } else {
            None
        }
    }

    /// The attitude sensor failed for longer than the loop can ride through: disarm (a
    /// no-op while disarmed). Motors restart only after a new arm gesture.
    pub fn sensor_fault(&mut self) -> Decision {
        if !self.motors_enabled() {
            return Decision::Steady;
        }
        self.state = State::Disarmed;
        self.throttle_low_since = None;
        self.resumed = false;
        Decision::DisarmedSensorFault
    }

    /// One loop.
    pub fn update(&mut self, inputs: &Inputs) -> Decision {
        let now = inputs.now_ms;
        let link_ok = inputs.link_up && inputs.sticks.is_finite();
        // The stick disarm only on the ground: in the air the same stick position is a pilot
        // yawing with the throttle closed, and disarming there drops the frame.
        let stick_disarm = inputs.landed || !inputs.landing_detectable;
        // Gestures only count while the link delivers real sticks.
        let gesture = if link_ok {
            self.gestures
                .update(now, &inputs.sticks, inputs.arm_switch, stick_disarm)
        } else {
            None
        };
        match self.state {
            State::Disarmed => match gesture {
                Some(Gesture::Arm) => match self.blocker(inputs) {
                    None => {
                        self.state = State::Armed;
                        self.throttle_low_since = Some(now);
                        Decision::Armed
                    }
                    Some(b) => Decision::ArmRefused(b),
                },
                _ => Decision::Steady,
            },
            State::Armed => {
                if !link_ok {
                    self.state = State::Failsafe { since_ms: now };
                    return Decision::FailsafeEntered;
                }
                if gesture == Some(Gesture::Disarm) {
                    self.state = State::Disarmed;
                    return Decision::DisarmedByPilot;
                }
                if inputs.sticks.throttle_low() && inputs.landed {
                    let since = *self.throttle_low_since.get_or_insert(now);
                    if now.wrapping_sub(since) >= self.settings.idle_disarm_ms {
                        self.state = State::Disarmed;
                        return Decision::DisarmedIdle;
                    }
                } else {
                    self.throttle_low_since = None;
                }
                Decision::Steady
            }
            State::Failsafe { .. } if self.resumed && link_ok => {
                self.resumed = false;
                if inputs.arm_switch == Some(false) {
                    self.state = State::Disarmed;
                    return Decision::DisarmedByPilot;
                }
                self.state = State::Armed;
                Decision::Resumed
            }
            State::Failsafe { since_ms } => {
                if inputs.landed {
                    self.state = State::Disarmed;
                    return Decision::DisarmedFailsafe;
                }
                if now.wrapping_sub(since_ms) >= last_resort_ms(self.settings.failsafe_descent_mps)
                {
                    self.state = State::Disarmed;
                    return Decision::DisarmedLastResort;
                }
                if link_ok && gesture == Some(Gesture::Disarm) {
                    self.state = State::Disarmed;
                    return Decision::DisarmedByPilot;
                }
                if link_ok && inputs.sticks.centred(self.settings.centre_deadband) {
                    self.state = State::Armed;
                    self.throttle_low_since = None;
                    return Decision::ControlRecovered;
                }
                Decision::Steady
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inputs(now_ms: u32, link_up: bool, throttle: f32, yaw: f32) -> Inputs {
        Inputs {
            now_ms,
            link_up,
            sticks: Sticks {
                throttle,
                yaw,
                ..Sticks::default()
            },
            arm_switch: None,
            sensors_healthy: true,
            gains_ready: true,
            landed: true,
            landing_detectable: true,
            battery_critical: false,
            settings_problem: false,
            usb_connected: false,
        }
    }

    fn armed(s: &Settings) -> Supervisor {
        let mut sup = Supervisor::new(*s);
        sup.update(&inputs(0, true, 0.0, 1.0));
        assert_eq!(
            sup.update(&inputs(s.gesture_hold_ms, true, 0.0, 1.0)),
            Decision::Armed
        );
        sup
    }

    #[test]
    fn starts_disarmed_and_arms_only_with_every_precondition() {
        let s = Settings::default();
        let mut sup = Supervisor::new(s);
        assert!(!sup.motors_enabled());
        let mut no_gains = inputs(0, true, 0.0, 1.0);
        no_gains.gains_ready = false;
        sup.update(&no_gains);
        no_gains.now_ms = 1000;
        assert_eq!(
            sup.update(&no_gains),
            Decision::ArmRefused(ArmBlocker::GainsNotReady)
        );
        assert_eq!(sup.state(), State::Disarmed);
        // Without a link the gesture is not even seen.
        let mut sup = Supervisor::new(s);
        for t in (0..3000).step_by(10) {
            assert_eq!(sup.update(&inputs(t, false, 0.0, 1.0)), Decision::Steady);
        }
        let sup = armed(&s);
        assert!(sup.motors_enabled());
    }

    #[test]
    fn disarms_after_idle_on_the_ground() {
        let s = Settings::default();
        let mut sup = armed(&s);
        // Throttle up at 2 s resets the idle timer; low again from 3 s.
        assert_eq!(sup.update(&inputs(2_000, true, 0.5, 0.0)), Decision::Steady);
        assert_eq!(sup.update(&inputs(3_000, true, 0.0, 0.0)), Decision::Steady);
        assert_eq!(
            sup.update(&inputs(12_999, true, 0.0, 0.0)),
            Decision::Steady
        );
        assert_eq!(
            sup.update(&inputs(13_000, true, 0.0, 0.0)),
            Decision::DisarmedIdle
        );
    }

    #[test]
    fn a_closed_throttle_in_the_air_never_idle_disarms() {
        let s = Settings::default();
        let mut sup = armed(&s);
        for t in (2_000..60_000).step_by(10) {
            let mut falling = inputs(t, true, 0.0, 0.0);
            falling.landed = false;
            assert_eq!(sup.update(&falling), Decision::Steady);
        }
        // Touch-down: the idle timer starts only now.
        assert_eq!(
            sup.update(&inputs(60_000, true, 0.0, 0.0)),
            Decision::Steady
        );
        assert_eq!(
            sup.update(&inputs(69_999, true, 0.0, 0.0)),
            Decision::Steady
        );
        assert_eq!(
            sup.update(&inputs(70_000, true, 0.0, 0.0)),
            Decision::DisarmedIdle
        );
    }

    #[test]
    fn the_stick_disarm_counts_only_on_the_ground() {
        let s = Settings::default();
        let mut sup = armed(&s);
        // Yaw full left at a closed throttle in the air, for 5 s: no disarm.
        for t in (2_000..7_000).step_by(10) {
            let mut air = inputs(t, true, 0.0, -1.0);
            air.landed = false;
            assert_eq!(sup.update(&air), Decision::Steady, "{t}");
        }
        // Touchdown seen at 7 s, the stick still held: disarmed a full hold later.
        assert_eq!(
            sup.update(&inputs(7_000, true, 0.0, -1.0)),
            Decision::Steady
        );
        assert_eq!(
            sup.update(&inputs(7_999, true, 0.0, -1.0)),
            Decision::Steady
        );
        assert_eq!(
            sup.update(&inputs(8_000, true, 0.0, -1.0)),
            Decision::DisarmedByPilot
        );
        // Without a vertical estimate the touchdown cannot be seen: the gesture counts.
        let mut sup = armed(&s);
        let blind = |t| Inputs {
            landed: false,
            landing_detectable: false,
            ..inputs(t, true, 0.0, -1.0)
        };
        assert_eq!(sup.update(&blind(2_000)), Decision::Steady);
        assert_eq!(sup.update(&blind(3_000)), Decision::DisarmedByPilot);
        // An arm switch disarms anywhere.
        let mut sup = Supervisor::new(s);
        let switch = |t, on| Inputs {
            arm_switch: Some(on),
            landed: false,
            ..inputs(t, true, 0.0, 0.0)
        };
        sup.update(&switch(0, false));
        assert_eq!(sup.update(&switch(10, true)), Decision::Armed);
        assert_eq!(sup.update(&switch(20, false)), Decision::DisarmedByPilot);
    }

    #[test]
    fn link_cut_descends_and_disarms_only_on_touchdown() {
        let s = Settings::default();
        let mut sup = armed(&s);
        assert_eq!(sup.update(&inputs(5_000, true, 0.6, 0.0)), Decision::Steady);
        let mut air = inputs(5_010, false, 0.6, 0.0);
        air.landed = false;
        assert_eq!(sup.update(&air), Decision::FailsafeEntered);
        assert_eq!(sup.failsafe_descent_mps(), Some(0.7));
        assert!(sup.motors_enabled(), "failsafe keeps flying to land level");
        // 0.7 m/s from 60 m takes 86 s: still descending, never disarmed (the old code cut
        // at 15 s).
        for t in (5_010..91_010).step_by(10) {
            air.now_ms = t;
            assert_eq!(sup.update(&air), Decision::Steady, "{t}");
        }
        assert!(sup.motors_enabled());
        // Touchdown detected.
        assert_eq!(
            sup.update(&inputs(91_020, false, 0.6, 0.0)),
            Decision::DisarmedFailsafe
        );
        assert!(!sup.motors_enabled());
        // The link coming back after that does not re-arm.
        assert_eq!(
            sup.update(&inputs(92_000, true, 0.0, 0.0)),
            Decision::Steady
        );
        assert_eq!(sup.state(), State::Disarmed);
    }

    #[test]
    fn the_last_resort_cuts_only_after_descending_from_200_m() {
        let s = Settings::default();
        assert_eq!(last_resort_ms(0.7), 285_714);
        let mut sup = armed(&s);
        let mut air = inputs(5_000, false, 0.6, 0.0);
        air.landed = false;
        assert_eq!(sup.update(&air), Decision::FailsafeEntered);
        air.now_ms = 5_000 + 285_713;
        assert_eq!(sup.update(&air), Decision::Steady);
        air.now_ms += 1;
        assert_eq!(sup.update(&air), Decision::DisarmedLastResort);
    }

    #[test]
    fn a_critical_battery_refuses_arming_unless_overridden() {
        for (override_on, expected) in [
            (false, Decision::ArmRefused(ArmBlocker::BatteryCritical)),
            (true, Decision::Armed),
        ] {
            let s = Settings {
                arm_on_critical_battery: override_on,
                ..Settings::default()
            };
            let mut sup = Supervisor::new(s);
            let mut low = inputs(0, true, 0.0, 1.0);
            low.battery_critical = true;
            sup.update(&low);
            low.now_ms = s.gesture_hold_ms;
            assert_eq!(sup.update(&low), expected);
        }
    }

    #[test]
    fn a_usb_host_refuses_arming_but_never_disarms() {
        let s = Settings::default();
        let mut sup = Supervisor::new(s);
        let mut usb = inputs(0, true, 0.0, 1.0);
        usb.usb_connected = true;
        sup.update(&usb);
        usb.now_ms = s.gesture_hold_ms;
        assert_eq!(
            sup.update(&usb),
            Decision::ArmRefused(ArmBlocker::UsbConnected)
        );
        // Unplugged: arms; plugged in while armed (flying): nothing happens.
        let mut sup = armed(&s);
        let mut flying = inputs(5_000, true, 0.5, 0.0);
        flying.landed = false;
        flying.usb_connected = true;
        assert_eq!(sup.update(&flying), Decision::Steady);
        assert!(sup.motors_enabled());
    }

    #[test]
    fn control_returns_only_with_centred_sticks() {
        let s = Settings::default();
        let mut sup = armed(&s);
        let flying = |t, up, yaw| Inputs {
            landed: false,
            ..inputs(t, up, 0.6, yaw)
        };
        sup.update(&flying(5_000, false, 0.0));
        // Link back but yaw held over: still failsafe.
        assert_eq!(sup.update(&flying(6_000, true, 0.5)), Decision::Steady);
        assert!(matches!(sup.state(), State::Failsafe { .. }));
        assert_eq!(
            sup.update(&flying(6_100, true, 0.05)),
            Decision::ControlRecovered
        );
        assert_eq!(sup.state(), State::Armed);
        assert_eq!(sup.failsafe_descent_mps(), None);
    }

    #[test]
    fn a_resumed_board_flies_in_failsafe_until_the_link_decides() {
        let s = Settings::default();
        let air = |t, up, switch| Inputs {
            landed: false,
            arm_switch: switch,
            ..inputs(t, up, 0.6, 0.3)
        };
        // The link back, the arm switch on: armed, the sticks wherever they are.
        let mut sup = Supervisor::new(s);
        sup.resume(0);
        assert!(sup.motors_enabled(), "motors at once, before any link");
        assert_eq!(sup.failsafe_descent_mps(), Some(0.7));
        assert_eq!(sup.update(&air(5, false, None)), Decision::Steady);
        assert_eq!(sup.update(&air(400, true, Some(true))), Decision::Resumed);
        assert_eq!(sup.state(), State::Armed);
        // No arm switch set (stick arming): the link alone is the pilot's word.
        let mut sup = Supervisor::new(s);
        sup.resume(0);
        assert_eq!(sup.update(&air(400, true, None)), Decision::Resumed);
        // The arm switch off: disarmed.
        let mut sup = Supervisor::new(s);
        sup.resume(0);
        assert_eq!(
            sup.update(&air(400, true, Some(false))),
            Decision::DisarmedByPilot
        );
        assert!(!sup.motors_enabled());
        // No link: the failsafe as usual, down to the touchdown.
        let mut sup = Supervisor::new(s);
        sup.resume(0);
        for t in (0..60_000).step_by(10) {
            assert_eq!(sup.update(&air(t, false, Some(true))), Decision::Steady);
        }
        assert_eq!(
            sup.update(&inputs(60_000, false, 0.6, 0.0)),
            Decision::DisarmedFailsafe
        );
        // The resume is spent once decided: a later link loss is a normal failsafe, whose
        // recovery wants centred sticks.
        let mut sup = Supervisor::new(s);
        sup.resume(0);
        assert_eq!(sup.update(&air(100, true, Some(true))), Decision::Resumed);
        assert_eq!(
            sup.update(&air(200, false, Some(true))),
            Decision::FailsafeEntered
        );
        assert_eq!(sup.update(&air(300, true, Some(true))), Decision::Steady);
        let centred = Inputs {
            sticks: Sticks::default(),
            ..air(400, true, Some(true))
        };
        assert_eq!(sup.update(&centred), Decision::ControlRecovered);
    }

    #[test]
    fn non_finite_sticks_count_as_a_lost_link() {
        let s = Settings::default();
        let mut sup = armed(&s);
        let mut bad = inputs(5_000, true, f32::NAN, 0.0);
        bad.landed = false;
        assert_eq!(sup.update(&bad), Decision::FailsafeEntered);
        bad.now_ms = 6_000;
        assert_eq!(sup.update(&bad), Decision::Steady, "no recovery on garbage");
    }
}
