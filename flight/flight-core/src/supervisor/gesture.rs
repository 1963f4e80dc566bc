//! Arm and disarm gestures: an arm switch (acted on only at its off→on edge, so a switch
//! left on at power-up never arms) or the classic stick hold (throttle low, yaw full right
//! to arm, full left to disarm, held for a second). The stick disarm counts only while the
//! supervisor allows it (on the ground): in the air the same stick position is a pilot
//! yawing with the throttle closed.

use super::Sticks;

/// A completed gesture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Gesture {
    /// The pilot asks to arm.
    Arm,
    /// The pilot asks to disarm.
    Disarm,
}

/// Turns switch positions and stick holds into gestures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GestureDetector {
    hold_ms: u32,
    last_switch: Option<bool>,
    hold: Option<(Gesture, u32)>,
    fired: bool,
}

impl GestureDetector {
    /// A detector needing stick gestures held for `hold_ms`.
    pub const fn new(hold_ms: u32) -> Self {
        Self {
            hold_ms,
            last_switch: None,
            hold: None,
            fired: false,
        }
    }

    /// Feeds one sample. `arm_switch` is `None` when no switch is configured.
    /// `stick_disarm`: the disarm stick hold may count now. While it may not, holding the
    /// disarm position starts no hold, so the hold time counts from when it may (a pilot
    /// who holds the gesture from touchdown disarms a second after the landing is seen).
    /// A switch disarms at its edge regardless: flicking it is a deliberate act.
    pub fn update(
        &mut self,
        now_ms: u32,
        sticks: &Sticks,
        arm_switch: Option<bool>,
        stick_disarm: bool,
    ) -> Option<Gesture> {
        if let Some(on) = arm_switch {
            // The first sample only learns the position: no edge at power-up.
            let previous = self.last_switch.replace(on);
            return match (previous, on) {
                (Some(false), true) => Some(Gesture::Arm),
                (Some(true), false) => Some(Gesture::Disarm),
                _ => None,
            };
        }
        let wanted = if sticks.throttle_low() && sticks.yaw > 0.9 {
            Some(Gesture::Arm)
        } else if stick_disarm && sticks.throttle_low() && sticks.yaw < -0.9 {
            Some(Gesture::Disarm)
        } else {
            None
        };
        match (wanted, self.hold) {
            (None, _) => {
                self.hold = None;
                self.fired = false;
                None
            }
            (Some(g), Some((held, since))) if g == held => {
                if !self.fired && now_ms.wrapping_sub(since) >= self.hold_ms {
                    // One gesture per hold: the stick must come back before the next.
                    self.fired = true;
                    Some(g)
                } else {
                    None
                }
            }
            (Some(g), _) => {
                self.hold = Some((g, now_ms));
                self.fired = false;
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sticks(throttle: f32, yaw: f32) -> Sticks {
        Sticks {
            throttle,
            yaw,
            ..Sticks::default()
        }
    }

    #[test]
    fn stick_hold_fires_once_after_the_hold_time() {
        let mut g = GestureDetector::new(1000);
        let arm = sticks(0.0, 1.0);
        assert_eq!(g.update(0, &arm, None, true), None);
        assert_eq!(g.update(999, &arm, None, true), None);
        assert_eq!(g.update(1000, &arm, None, true), Some(Gesture::Arm));
        assert_eq!(g.update(1500, &arm, None, true), None, "only once per hold");
        assert_eq!(g.update(1600, &sticks(0.0, 0.0), None, true), None);
        assert_eq!(g.update(1700, &sticks(0.0, -1.0), None, true), None);
        assert_eq!(
            g.update(2700, &sticks(0.0, -1.0), None, true),
            Some(Gesture::Disarm)
        );
    }

    #[test]
    fn a_stick_disarm_held_while_not_allowed_counts_from_when_it_is() {
        let mut g = GestureDetector::new(1000);
        let disarm = sticks(0.0, -1.0);
        // Held for 3 s in the air: nothing, and no hold time banked.
        for t in (0..3000).step_by(10) {
            assert_eq!(g.update(t, &disarm, None, false), None, "{t}");
        }
        // Landed from 3 s: a full second more.
        assert_eq!(g.update(3000, &disarm, None, true), None);
        assert_eq!(g.update(3999, &disarm, None, true), None);
        assert_eq!(g.update(4000, &disarm, None, true), Some(Gesture::Disarm));
        // The switch is not gated.
        let mut g = GestureDetector::new(1000);
        let s = Sticks::default();
        assert_eq!(g.update(0, &s, Some(true), false), None);
        assert_eq!(g.update(10, &s, Some(false), false), Some(Gesture::Disarm));
    }

    #[test]
    fn yaw_with_throttle_up_is_not_a_gesture() {
        let mut g = GestureDetector::new(1000);
        for t in (0..5000).step_by(20) {
            assert_eq!(g.update(t, &sticks(0.5, 1.0), None, true), None);
        }
    }

    #[test]
    fn switch_acts_on_edges_only() {
        let mut g = GestureDetector::new(1000);
        let s = Sticks::default();
        assert_eq!(
            g.update(0, &s, Some(true), true),
            None,
            "on at power-up: no arm"
        );
        assert_eq!(g.update(10, &s, Some(false), true), Some(Gesture::Disarm));
        assert_eq!(g.update(20, &s, Some(true), true), Some(Gesture::Arm));
        assert_eq!(g.update(30, &s, Some(true), true), None);
    }
}
