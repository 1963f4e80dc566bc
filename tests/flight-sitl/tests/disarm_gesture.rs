//! The stick disarm gesture after a landing (issue 13 follow-up, found by the served pilot):
//! a pilot who lands, closes the throttle and holds yaw full left must disarm the frame on
//! the ground. Before the fix the loop kept air-mode authority after touchdown, flew the
//! gesture as a full yaw demand and the frame lifted off before the 1 s hold disarmed it.

#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::cast_precision_loss
)]

mod common;

use common::*;
use flight_app::outputs::Command;
use flight_app::supervisor::Decision;
use flight_sitl::scenario::{Piloting, Sight, default_airframe};
use flight_sitl::{PilotInput, Scenario, Sitl, run};

/// Arms, climbs to ≈ 2 m, descends at ≈ 0.5 m/s by eye, and once the frame sits on the
/// ground closes the throttle and — `gesture_after_s` later — holds the disarm gesture.
struct LandAndDisarm {
    gesture_after_s: f64,
    climbed: bool,
    touchdown_s: Option<f64>,
}

impl Piloting for LandAndDisarm {
    fn input(&mut self, t: f64, sight: &Sight) -> PilotInput {
        let mut script = pilot(-1.0, |_| PilotInput::default());
        if t < CLIMB_END_S {
            return script(t);
        }
        if sight.altitude_m > 2.0 {
            self.climbed = true;
        }
        if self.climbed && self.touchdown_s.is_none() && sight.on_ground {
            self.touchdown_s = Some(t);
        }
        let input = PilotInput {
            mode_switch: -1.0,
            ..PilotInput::default()
        };
        match self.touchdown_s {
            Some(down) => PilotInput {
                throttle: 0.0,
                yaw: if t >= down + self.gesture_after_s {
                    -1.0
                } else {
                    0.0
                },
                ..input
            },
            None => {
                // Up to 2 m (the take-off boost overshoots to ≈ 4 m), then down at ≈ 0.6 m/s.
                let target = if self.climbed { -0.6 } else { 1.0 };
                let throttle = CRUISE_THROTTLE + 0.1 * (target - sight.climb_mps) as f32;
                PilotInput {
                    throttle: throttle.clamp(0.0, 0.2),
                    ..input
                }
            }
        }
    }
}

fn land_and_disarm(gesture_after_s: f64) -> Sitl {
    let (quad, settings) = default_airframe();
    run(Scenario::flown_by(
        settings,
        quad,
        20.0,
        LandAndDisarm {
            gesture_after_s,
            climbed: false,
            touchdown_s: None,
        },
    ))
}

#[test]
fn the_disarm_gesture_after_a_landing_disarms_on_the_ground() {
    // At once on touchdown, and 3 s later (as the served pilot did).
    for gesture_after_s in [0.0, 3.0] {
        let sitl = land_and_disarm(gesture_after_s);
        let s = &sitl.samples;
        let top = s.iter().map(|x| x.altitude_m).fold(0.0, f64::max);
        let touchdown = s
            .iter()
            .skip_while(|x| x.altitude_m < 1.5)
            .find(|x| x.altitude_m < 0.01)
            .unwrap();
        let after = s
            .iter()
            .filter(|x| x.t_s >= touchdown.t_s)
            .map(|x| x.altitude_m)
            .fold(0.0, f64::max);
        let disarm = s
            .iter()
            .find(|x| x.out.decision == Decision::DisarmedByPilot);
        println!(
            "gesture {gesture_after_s} s after touchdown: top {top:.2} m, touchdown {:.3} s at {:.2} m/s, \
             max altitude after touchdown {after:.3} m, disarmed by the pilot at {:?}",
            touchdown.t_s,
            touchdown.climb_mps,
            disarm.map(|d| (d.t_s, d.altitude_m))
        );
        assert!(top > 1.9, "the pilot flew: {top}");
        assert!(after < 0.3, "lifted off after the landing: {after} m");
        let disarm = disarm.expect("the gesture disarms");
        assert!(disarm.altitude_m < 0.01, "{}", disarm.altitude_m);
        // The gesture's hold (1 s) counts only once the touchdown detector saw the landing
        // (its 1 s hold; measured 2.89 s from contact to disarm with the gesture held from
        // contact, 1.06 s when it starts 3 s later), never before the gesture began.
        let from = touchdown.t_s + gesture_after_s;
        assert!(
            (from + 0.99..from + 3.5).contains(&disarm.t_s),
            "{} (gesture from {from})",
            disarm.t_s
        );
        assert!(
            s.iter()
                .filter(|x| x.t_s > disarm.t_s)
                .all(|x| x.out.motors == [Command::Stopped; 4])
        );
    }
}
