//! Altitude hold, position hold and loiter: what the INS's navigation estimate
//! ([`super::Estimator::vertical`], [`super::Estimator::horizontal`]) turns into a
//! collective throttle and roll/pitch angle setpoints for the attitude controller.
//!
//! - **Altitude** (altitude hold, position hold, loiter): the throttle stick centred
//!   (0.5 ± [`STICK_DEADBAND`]) holds the altitude it was centred at; a deflection asks for a
//!   climb rate up to ±[`MAX_CLIMB_MPS`] at full stick. Cascade: altitude error → climb-rate
//!   setpoint → PI on the climb rate around the learnt hover throttle (the failsafe
//!   descent's gains). Without the INS vertical (complementary filter, no baro) the loop's
//!   blended climb rate is held at the stick's setpoint without an altitude term; without
//!   even that, the hover throttle.
//! - **Position hold**: roll and pitch sticks centred hold the position they were centred
//!   at; deflected, the sticks fly attitude mode and the held position follows the frame.
//! - **Loiter**: the sticks move the held position at up to [`LOITER_SPEED_MPS`] (body
//!   forward/right, turned by the yaw estimate), so the frame flies at that speed and stops
//!   where the sticks are released.
//!
//! Horizontal cascade: position error → velocity setpoint (≤ [`MAX_SPEED_MPS`]) → PI on the
//! velocity (the integral learns the wind's drag) → NED acceleration → roll/pitch angles
//! (small-angle thrust tilt, ≤ [`MAX_TILT_DEG`]). Without a good fix position hold and
//! loiter fly attitude mode on the sticks (altitude still held).
//!
//! **Failsafe descent with a fix** ([`DescentHold`]): the position is held while the frame
//! descends, and given up (level) once it has stopped descending for [`STOPPED_MS`] — the
//! ground: pressed against it, the position loop's tilt demands rock the frame, the gyro
//! never goes quiet and the touchdown detector could never end the failsafe.

use crate::estimation::math::{max, min};

/// Throttle stick deadband around centre, and roll/pitch stick deadband.
pub const STICK_DEADBAND: f32 = 0.1;
/// Climb rate at full throttle deflection, m/s.
pub const MAX_CLIMB_MPS: f32 = 1.5;
/// Loiter speed at full roll/pitch deflection, m/s.
pub const LOITER_SPEED_MPS: f32 = 3.0;
/// Largest horizontal speed the position loop asks for, m/s.
pub const MAX_SPEED_MPS: f32 = 3.0;
/// Largest tilt the position loop asks for, deg.
pub const MAX_TILT_DEG: f32 = 25.0;

/// Failsafe descent: not seen descending this long, the frame is levelled for good, ms
/// (the descent builds up within ≈ 1 s; on the ground the detector then needs its 1 s).
pub const STOPPED_MS: u32 = 2_000;

/// Altitude error → climb rate, (m/s)/m.
const ALTITUDE_KP: f32 = 1.0;
/// Climb-rate PI around the hover throttle (as the failsafe descent: ωn ≈ 3.5 rad/s).
const CLIMB_KP: f32 = 0.1;
const CLIMB_KI: f32 = 0.2;
const CLIMB_I_LIMIT: f32 = 0.2;
/// Position error → velocity, (m/s)/m.
const POSITION_KP: f32 = 1.0;
/// Velocity error → acceleration, (m/s²)/(m/s), and its integral (m/s²)/m.
const VELOCITY_KP: f32 = 2.0;
const VELOCITY_KI: f32 = 0.5;
/// The velocity integral's bound, m/s² (≈ 12° of tilt: a 10 m/s wind on a small frame).
const VELOCITY_I_LIMIT: f32 = 2.0;
const GRAVITY: f32 = crate::estimation::GRAVITY_MPS2;
const DEG_PER_RAD: f32 = 180.0 / core::f32::consts::PI;

/// What the horizontal loop does with the roll/pitch sticks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Horizontal {
    /// Sticks centred hold the position; deflected, the pilot flies attitude.
    PositionHold,
    /// Sticks move the held position.
    Loiter,
}

/// The navigation estimate the hold loops read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nav {
    /// INS altitude (m, up) and climb rate (m/s, up).
    pub vertical: Option<(f32, f32)>,
    /// The loop's blended climb rate when the INS vertical is missing, m/s up.
    pub climb_mps: Option<f32>,
    /// INS north/east position (m) and velocity (m/s) on a good fix.
    pub horizontal: Option<([f32; 2], [f32; 2])>,
    /// Heading, rad (cosine and sine).
    pub yaw_cos_sin: [f32; 2],
}

/// The hold loops' state.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Hold {
    altitude_target_m: Option<f32>,
    climb_integral: f32,
    position_target_m: Option<[f32; 2]>,
    velocity_integral: [f32; 2],
}

fn clamp(x: f32, limit: f32) -> f32 {
    max(-limit, min(limit, x))
}

/// A stick beyond the deadband, rescaled to −1…1 (0 inside it).
fn beyond_deadband(x: f32) -> f32 {
    let a = x.abs() - STICK_DEADBAND;
    if a <= 0.0 {
        0.0
    } else {
        min(1.0, a / (1.0 - STICK_DEADBAND)).copysign(x)
    }
}

impl Hold {
    /// Forgets targets and integrals (a mode change, arming).
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// The altitude being held, if any.
    pub fn altitude_target(&self) -> Option<f32> {
        self.altitude_target_m
    }

    /// The position being held, if any.
    pub fn position_target(&self) -> Option<[f32; 2]> {
        self.position_target_m
    }

    /// Collective throttle (0…1) for the throttle stick (0…1, centre 0.5 holds).
    pub fn throttle(&mut self, stick: f32, nav: &Nav, hover: f32, dt_s: f32) -> f32 {
        // Centre 0.5 → −1…1 around it, deadband applied.
        let demand = beyond_deadband((stick - 0.5) * 2.0);
        let (climb_sp, climb) = match nav.vertical {
            Some((altitude, climb)) => {
                let sp = if demand == 0.0 {
                    let target = *self.altitude_target_m.get_or_insert(altitude);
                    clamp(ALTITUDE_KP * (target - altitude), MAX_CLIMB_MPS)
                } else {
                    self.altitude_target_m = None;
                    demand * MAX_CLIMB_MPS
                };
                (sp, Some(climb))
            }
            None => {
                self.altitude_target_m = None;
                (demand * MAX_CLIMB_MPS, nav.climb_mps)
            }
        };
        let Some(climb) = climb.filter(|c| c.is_finite()) else {
            return max(0.0, min(1.0, hover));
        };
        let error = climb_sp - climb;
        self.climb_integral = clamp(self.climb_integral + CLIMB_KI * error * dt_s, CLIMB_I_LIMIT);
        max(
            0.0,
            min(1.0, hover + CLIMB_KP * error + self.climb_integral),
        )
    }

    /// Roll and pitch setpoints (deg) for `kind` with the roll/pitch sticks (−1…1);
    /// `None` when the pilot's sticks fly attitude mode instead (no fix, or deflected in
    /// position hold).
    pub fn angles(
        &mut self,
        kind: Horizontal,
        [roll_stick, pitch_stick]: [f32; 2],
        nav: &Nav,
        dt_s: f32,
    ) -> Option<[f32; 2]> {
        let Some(([n, e], [vn, ve])) = nav.horizontal else {
            self.position_target_m = None;
            self.velocity_integral = [0.0; 2];
            return None;
        };
        let [c, s] = nav.yaw_cos_sin;
        let (right, back) = (beyond_deadband(roll_stick), beyond_deadband(pitch_stick));
        let moving = right != 0.0 || back != 0.0;
        // Feed-forward velocity (NED) the loiter sticks ask for.
        let mut feed_forward = [0.0_f32; 2];
        match kind {
            Horizontal::PositionHold if moving => {
                self.position_target_m = None;
                self.velocity_integral = [0.0; 2];
                return None;
            }
            Horizontal::PositionHold => {}
            Horizontal::Loiter => {
                // Pitch stick positive is nose up (backwards), as in attitude mode.
                let (fwd, rgt) = (-back * LOITER_SPEED_MPS, right * LOITER_SPEED_MPS);
                feed_forward = [c * fwd - s * rgt, s * fwd + c * rgt];
                if let Some([tn, te]) = self.position_target_m.as_mut() {
                    *tn += feed_forward[0] * dt_s;
                    *te += feed_forward[1] * dt_s;
                    // The target never runs away from the frame (a wind it cannot beat).
                    *tn = n + clamp(*tn - n, MAX_SPEED_MPS / POSITION_KP);
                    *te = e + clamp(*te - e, MAX_SPEED_MPS / POSITION_KP);
                }
            }
        }
        let [tn, te] = *self.position_target_m.get_or_insert([n, e]);
        let speed_limit = max(MAX_SPEED_MPS, LOITER_SPEED_MPS);
        let v_sp = [
            clamp(feed_forward[0] + POSITION_KP * (tn - n), speed_limit),
            clamp(feed_forward[1] + POSITION_KP * (te - e), speed_limit),
        ];
        let error = [v_sp[0] - vn, v_sp[1] - ve];
        let mut accel = [0.0_f32; 2];
        for ((a, i), err) in accel
            .iter_mut()
            .zip(self.velocity_integral.iter_mut())
            .zip(error)
        {
            *i = clamp(*i + VELOCITY_KI * err * dt_s, VELOCITY_I_LIMIT);
            *a = VELOCITY_KP * err + *i;
        }
        // NED acceleration → body forward/right → tilt: accelerating forward takes the
        // nose down (negative pitch), right takes a right roll.
        let [an, ae] = accel;
        let (a_fwd, a_right) = (c * an + s * ae, -s * an + c * ae);
        let limit = MAX_TILT_DEG;
        Some([
            clamp(a_right / GRAVITY * DEG_PER_RAD, limit),
            clamp(-a_fwd / GRAVITY * DEG_PER_RAD, limit),
        ])
    }
}

/// Whether the failsafe descent (with a fix) still holds the position: see the module
/// documentation. Starts as "not yet descending" at the descent's start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DescentHold {
    /// Not in the descent (before it, or no failsafe).
    #[default]
    Idle,
    /// Descending: the position is held.
    Descending,
    /// Not descending since this time (ms, the caller's clock); still holding.
    Stopped(u32),
    /// Stopped descending for `STOPPED_MS`: level until the descent ends.
    Level,
}

impl DescentHold {
    /// The next state at `now_ms` in the descent, the frame seen `descending` or not.
    pub fn update(self, descending: bool, now_ms: u32) -> Self {
        match (self, descending) {
            (Self::Level, _) => Self::Level,
            (_, true) => Self::Descending,
            (Self::Idle | Self::Descending, false) => Self::Stopped(now_ms),
            (Self::Stopped(since), false) if now_ms.wrapping_sub(since) >= STOPPED_MS => {
                Self::Level
            }
            (stopped, false) => stopped,
        }
    }

    /// Whether the position is still held.
    pub fn holds(self) -> bool {
        self != Self::Level
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn nav(altitude: f32, climb: f32) -> Nav {
        Nav {
            vertical: Some((altitude, climb)),
            climb_mps: Some(climb),
            horizontal: None,
            yaw_cos_sin: [1.0, 0.0],
        }
    }

    #[test]
    fn a_centred_throttle_holds_the_altitude_it_was_centred_at() {
        let mut h = Hold::default();
        // Centred at 10 m: hover throttle, target 10 m.
        let t = h.throttle(0.52, &nav(10.0, 0.0), 0.4, 0.001);
        assert!((t - 0.4).abs() < 1e-3, "{t}");
        assert_eq!(h.altitude_target(), Some(10.0));
        // Sagged to 9 m: climb demanded, more throttle.
        assert!(h.throttle(0.5, &nav(9.0, 0.0), 0.4, 0.001) > 0.45);
        // Full up: 1.5 m/s climb, target released.
        let t = h.throttle(1.0, &nav(9.0, 0.0), 0.4, 0.001);
        assert!((t - (0.4 + 0.15)).abs() < 0.01, "{t}");
        assert_eq!(h.altitude_target(), None);
        // Without any vertical estimate: the hover throttle.
        let none = Nav {
            vertical: None,
            climb_mps: None,
            ..nav(0.0, 0.0)
        };
        assert_eq!(h.throttle(1.0, &none, 0.4, 0.001), 0.4);
    }

    #[test]
    fn position_hold_leans_back_towards_the_target_and_hands_the_sticks_over() {
        let mut h = Hold::default();
        let mut n = Nav {
            horizontal: Some(([0.0, 0.0], [0.0, 0.0])),
            ..nav(5.0, 0.0)
        };
        assert_eq!(
            h.angles(Horizontal::PositionHold, [0.0; 2], &n, 0.001),
            Some([0.0, 0.0])
        );
        // Blown 2 m north while facing north: pitch nose up (back towards the target).
        n.horizontal = Some(([2.0, 0.0], [0.0, 0.0]));
        let [roll, pitch] = h
            .angles(Horizontal::PositionHold, [0.0; 2], &n, 0.001)
            .unwrap();
        assert!(pitch > 5.0 && roll.abs() < 1e-3, "{roll} {pitch}");
        // Facing east, south is to the right: the same error is a right roll.
        n.yaw_cos_sin = [0.0, 1.0];
        let [roll, pitch] = h
            .angles(Horizontal::PositionHold, [0.0; 2], &n, 0.001)
            .unwrap();
        assert!(roll > 5.0 && pitch.abs() < 1e-3, "{roll} {pitch}");
        // Sticks deflected: the pilot flies, the target is dropped.
        assert_eq!(
            h.angles(Horizontal::PositionHold, [0.5, 0.0], &n, 0.001),
            None
        );
        assert_eq!(h.position_target(), None);
        // No fix: the pilot flies.
        n.horizontal = None;
        assert_eq!(
            h.angles(Horizontal::PositionHold, [0.0; 2], &n, 0.001),
            None
        );
    }

    #[test]
    fn loiter_sticks_move_the_target_at_the_loiter_speed() {
        let mut h = Hold::default();
        let n = Nav {
            horizontal: Some(([0.0, 0.0], [0.0, 0.0])),
            ..nav(5.0, 0.0)
        };
        // Full forward stick (pitch −1) facing north for 1 s while the frame stays put.
        for _ in 0..1000 {
            let _ = h.angles(Horizontal::Loiter, [0.0, -1.0], &n, 0.001);
        }
        let [tn, te] = h.position_target().unwrap();
        // Moved north, bounded by the leash (3 m ahead of the frame at most).
        assert!(tn > 2.9 && tn <= 3.0 + 1e-4 && te.abs() < 1e-4, "{tn} {te}");
        let [_, pitch] = h
            .angles(Horizontal::Loiter, [0.0, -1.0], &n, 0.001)
            .unwrap();
        assert!(pitch < -10.0, "nose down to go forward: {pitch}");
    }

    #[test]
    fn the_failsafe_descent_gives_up_the_position_once_stopped_for_two_seconds() {
        let mut d = DescentHold::Idle;
        // The descent builds up: not yet descending, still holding.
        d = d.update(false, 1_000);
        assert_eq!(d, DescentHold::Stopped(1_000));
        d = d.update(false, 2_500);
        assert!(d.holds());
        d = d.update(true, 2_600);
        assert_eq!(d, DescentHold::Descending);
        // A gust: a moment without descent keeps the hold.
        d = d
            .update(false, 10_000)
            .update(false, 11_900)
            .update(true, 11_950);
        assert!(d.holds());
        // Touchdown: level after 2 s, and for good.
        d = d.update(false, 20_000).update(false, 21_999);
        assert!(d.holds());
        d = d.update(false, 22_000);
        assert_eq!(d, DescentHold::Level);
        assert!(!d.update(true, 23_000).holds());
        // Never descending at all (a failsafe on the ground): level after 2 s too.
        assert!(
            !DescentHold::Idle
                .update(false, 0)
                .update(false, 2_000)
                .holds()
        );
    }
}
