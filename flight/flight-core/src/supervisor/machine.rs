//! The arming / failsafe state machine.
//!
//! ```text
//!            arm gesture + all preconditions             link lost
//! Disarmed ─────────────────────────────────▶ Armed ─────────────────▶ Failsafe
//!    ▲  ▲      disarm gesture / idle on ground  │   link back + sticks    │
//!    │  └───────────────────────────────────────┘◀──────── centred ───────┤
//!    └──────────────────── failsafe time out (landed by then) ───────────┘
//! ```
//! Motors turn only in `Armed` and `Failsafe`; in `Failsafe` the controller levels and
//! descends at a fixed rate, ignoring the (stale) sticks.

use super::{Gesture, GestureDetector, Sticks};

/// Tunables, with safe defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Settings {
    /// How long a stick gesture must be held.
    pub gesture_hold_ms: u32,
    /// Disarm after the throttle has been low this long while armed and landed.
    pub idle_disarm_ms: u32,
    /// Disarm this long after the link failsafe began; the descent must have landed by then.
    pub failsafe_disarm_ms: u32,
    /// Descent rate during failsafe, m/s.
    pub failsafe_descent_mps: f32,
    /// How close to centre roll/pitch/yaw must be to take control back after a failsafe.
    pub centre_deadband: f32,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            gesture_hold_ms: 1_000,
            idle_disarm_ms: 10_000,
            failsafe_disarm_ms: 15_000,
            failsafe_descent_mps: 0.7,
            centre_deadband: 0.1,
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
    /// The frame rests on the ground (still, feeling 1 g). The idle disarm only counts
    /// while it does, so a closed throttle in the air never disarms.
    pub landed: bool,
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
    /// Disarmed at the end of a failsafe.
    DisarmedFailsafe,
    /// Link lost while armed.
    FailsafeEntered,
    /// Link back and sticks centred: the pilot has control again.
    ControlRecovered,
    /// Disarmed because the attitude sensor stopped delivering usable data (the frame can
    /// no longer sense its attitude). Only a fresh arm restarts the motors.
    DisarmedSensorFault,
}

/// The state machine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Supervisor {
    settings: Settings,
    state: State,
    gestures: GestureDetector,
    throttle_low_since: Option<u32>,
}

impl Supervisor {
    /// Starts disarmed: motors are stopped from power-on.
    pub fn new(settings: Settings) -> Self {
        Self {
            settings,
            state: State::Disarmed,
            gestures: GestureDetector::new(settings.gesture_hold_ms),
            throttle_low_since: None,
        }
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

    fn blocker(inputs: &Inputs) -> Option<ArmBlocker> {
        if !inputs.link_up || !inputs.sticks.is_finite() {
            Some(ArmBlocker::LinkDown)
        } else if !inputs.sticks.throttle_low() {
            Some(ArmBlocker::ThrottleNotLow)
        } else if !inputs.sensors_healthy {
            Some(ArmBlocker::SensorsUnhealthy)
        } else if !inputs.gains_ready {
            Some(ArmBlocker::GainsNotReady)
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
        Decision::DisarmedSensorFault
    }

    /// One loop.
    pub fn update(&mut self, inputs: &Inputs) -> Decision {
        let now = inputs.now_ms;
        let link_ok = inputs.link_up && inputs.sticks.is_finite();
        // Gestures only count while the link delivers real sticks.
        let gesture = if link_ok {
            self.gestures.update(now, &inputs.sticks, inputs.arm_switch)
        } else {
            None
        };
        match self.state {
            State::Disarmed => match gesture {
                Some(Gesture::Arm) => match Self::blocker(inputs) {
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
            State::Failsafe { since_ms } => {
                if now.wrapping_sub(since_ms) >= self.settings.failsafe_disarm_ms {
                    self.state = State::Disarmed;
                    return Decision::DisarmedFailsafe;
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
    fn link_cut_descends_then_disarms() {
        let s = Settings::default();
        let mut sup = armed(&s);
        assert_eq!(sup.update(&inputs(5_000, true, 0.6, 0.0)), Decision::Steady);
        assert_eq!(
            sup.update(&inputs(5_010, false, 0.6, 0.0)),
            Decision::FailsafeEntered
        );
        assert_eq!(sup.failsafe_descent_mps(), Some(0.7));
        assert!(sup.motors_enabled(), "failsafe keeps flying to land level");
        assert_eq!(
            sup.update(&inputs(20_009, false, 0.6, 0.0)),
            Decision::Steady
        );
        assert_eq!(
            sup.update(&inputs(20_010, false, 0.6, 0.0)),
            Decision::DisarmedFailsafe
        );
        assert!(!sup.motors_enabled());
        // The link coming back after that does not re-arm.
        assert_eq!(
            sup.update(&inputs(21_000, true, 0.0, 0.0)),
            Decision::Steady
        );
        assert_eq!(sup.state(), State::Disarmed);
    }

    #[test]
    fn control_returns_only_with_centred_sticks() {
        let s = Settings::default();
        let mut sup = armed(&s);
        sup.update(&inputs(5_000, false, 0.6, 0.0));
        // Link back but yaw held over: still failsafe.
        assert_eq!(sup.update(&inputs(6_000, true, 0.6, 0.5)), Decision::Steady);
        assert!(matches!(sup.state(), State::Failsafe { .. }));
        assert_eq!(
            sup.update(&inputs(6_100, true, 0.6, 0.05)),
            Decision::ControlRecovered
        );
        assert_eq!(sup.state(), State::Armed);
        assert_eq!(sup.failsafe_descent_mps(), None);
    }

    #[test]
    fn non_finite_sticks_count_as_a_lost_link() {
        let s = Settings::default();
        let mut sup = armed(&s);
        let mut bad = inputs(5_000, true, f32::NAN, 0.0);
        assert_eq!(sup.update(&bad), Decision::FailsafeEntered);
        bad.now_ms = 6_000;
        assert_eq!(sup.update(&bad), Decision::Steady, "no recovery on garbage");
    }
}
