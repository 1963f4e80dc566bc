//! Link-failsafe guidance: the collective throttle and roll/pitch angles that fly the frame
//! while the supervisor's failsafe descent is active, and the state that takes — when the
//! failsafe began, whether the frame was in the air then, the descent's climb-rate
//! integral and whether the descent still holds the position ([`DescentHold`]).
//!
//! With a good fix, a failsafe that began in the air holds the position and the altitude
//! for [`FAILSAFE_HOLD_MS`], then descends in place at the failsafe rate, the position held
//! until the frame stops descending (the ground). Without a fix (or begun on the ground) the
//! frame is levelled and descends at once. The flight loop's hold loops ([`Hold`]) do the
//! holding; this module decides what they hold.

use super::guidance::Guidance;
use super::hold::{DescentHold, Hold, Horizontal, Nav};
use crate::supervisor::{Decision, LandingDetector, landed_climb_limit};

/// On a link failsafe with a good GPS fix the frame holds its position and altitude this
/// long (the pilot may walk back into range, the link may return), then descends in place
/// at the failsafe rate, still holding the position. Without a fix: the descent at once.
pub const FAILSAFE_HOLD_MS: u32 = 30_000;

/// The throttle stick position the hold loops take as "hold the altitude".
const CENTRED_THROTTLE: f32 = 0.5;
/// Descent PI around the hover throttle: throttle per m/s of climb-rate error, per metre of
/// accumulated error, and the integral's bound (see [`FailsafeGuidance::descent_throttle`]).
const DESCENT_KP: f32 = 0.1;
const DESCENT_KI: f32 = 0.2;
const DESCENT_I_LIMIT: f32 = 0.2;
/// Without any climb rate the descent flies this fraction of the hover throttle.
const BLIND_DESCENT_FRACTION: f32 = 0.9;

/// What the failsafe guidance reads of this loop.
#[derive(Debug, Clone, Copy)]
pub(super) struct Situation {
    /// The loop's clock, ms.
    pub now_ms: u32,
    /// The failsafe began this loop.
    pub entered: bool,
    /// The supervisor's failsafe descent rate, m/s.
    pub descent_mps: f32,
    /// Blended climb rate, m/s up.
    pub climb_rate_mps: Option<f32>,
    /// The navigation estimate.
    pub nav: Option<Nav>,
    /// The learnt hover throttle.
    pub hover_throttle: f32,
    /// Loop period, s.
    pub ts_s: f32,
}

/// The failsafe's own state across loops.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct FailsafeGuidance {
    /// When the current link failsafe began, ms.
    since_ms: Option<u32>,
    /// The touchdown detector had the frame in the air when the current failsafe began:
    /// only then does a failsafe with a fix hold the altitude first (on the ground it
    /// descends, i.e. stays, and disarms at once as without a fix).
    airborne: bool,
    /// This loop the failsafe held the altitude (with a fix): the touchdown detector is held
    /// off — a held altitude shows "not descending" by design, and the thrust against a
    /// stale hover estimate (learnt in a climb) proves nothing.
    holds_altitude: bool,
    /// Whether the descent (with a fix) still holds the position.
    descent_hold: DescentHold,
    /// Integral of the descent-rate error (throttle units).
    descent_integral: f32,
}

impl FailsafeGuidance {
    /// Follows the supervisor each loop, before any guidance: starts the failsafe's clock
    /// when the `decision` says it began (or it is found running without one), noting
    /// whether the touchdown detector had the frame in the air; stops it when there is no
    /// failsafe `descent`.
    #[inline(always)]
    pub fn track(
        &mut self,
        descent: bool,
        decision: Decision,
        now_ms: u32,
        landing: &LandingDetector,
    ) {
        self.holds_altitude = false;
        if !descent {
            self.since_ms = None;
            self.airborne = false;
            self.descent_hold = DescentHold::Idle;
        } else if decision == Decision::FailsafeEntered || self.since_ms.is_none() {
            self.since_ms = Some(now_ms);
            self.airborne = !landing.landed();
        }
    }

    /// A reset in the air at `now_ms`: in failsafe, in the air, until the link decides.
    pub fn resume(&mut self, now_ms: u32) {
        self.since_ms = Some(now_ms);
        self.airborne = true;
    }

    /// Whether this loop's guidance held the altitude (the touchdown detector waits).
    pub fn holds_altitude(&self) -> bool {
        self.holds_altitude
    }

    /// This loop's throttle and angles in the failsafe, the hold loops in `hold` flying
    /// them where a fix allows.
    #[inline(always)]
    pub fn guide(&mut self, s: &Situation, hold: &mut Hold) -> Guidance {
        let for_ms = self.since_ms.map_or(0, |t| s.now_ms.wrapping_sub(t));
        let fix_nav = s.nav.filter(|n| n.horizontal.is_some());
        let fix_nav = fix_nav.as_ref();
        let holding = self.airborne && for_ms < FAILSAFE_HOLD_MS;
        self.descent_hold = if holding {
            DescentHold::Idle
        } else {
            let descending = s
                .climb_rate_mps
                .is_some_and(|c| c < -landed_climb_limit(s.descent_mps));
            self.descent_hold.update(descending, for_ms)
        };
        let angles = match fix_nav {
            Some(nav) if self.descent_hold.holds() => {
                hold.angles(Horizontal::PositionHold, [0.0; 2], nav, s.ts_s)
            }
            _ => None,
        };
        let throttle = match fix_nav {
            Some(nav) if holding => hold.throttle(CENTRED_THROTTLE, nav, s.hover_throttle, s.ts_s),
            _ => self.descent_throttle(s),
        };
        self.holds_altitude = holding && fix_nav.is_some();
        Guidance::Failsafe {
            throttle,
            angles_deg: angles.unwrap_or([0.0; 2]),
        }
    }

    /// The descent's throttle: PI on the climb rate around the hover value. With ≈ 60 m/s²
    /// per unit throttle (a 2:1 thrust-to-weight frame) the loop has ωn ≈ 3.5 rad/s,
    /// ζ ≈ 0.9; the integral absorbs a wrong hover estimate (±0.2).
    fn descent_throttle(&mut self, s: &Situation) -> f32 {
        if s.entered {
            self.descent_integral = 0.0;
        }
        let throttle = match s.climb_rate_mps {
            Some(climb) => {
                let error = -s.descent_mps - climb;
                self.descent_integral = (self.descent_integral + DESCENT_KI * error * s.ts_s)
                    .clamp(-DESCENT_I_LIMIT, DESCENT_I_LIMIT);
                s.hover_throttle + DESCENT_KP * error + self.descent_integral
            }
            None => s.hover_throttle * BLIND_DESCENT_FRACTION,
        };
        throttle.clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::super::guidance::tests::nav;
    use super::*;

    const TS: f32 = 0.002;
    const HOVER: f32 = 0.4;

    fn situation(now_ms: u32, climb: Option<f32>, nav: Option<Nav>) -> Situation {
        Situation {
            now_ms,
            entered: now_ms == 0,
            descent_mps: 0.7,
            climb_rate_mps: climb,
            nav,
            hover_throttle: HOVER,
            ts_s: TS,
        }
    }

    /// A failsafe begun at 0 ms, in the air or not.
    fn begun(in_air: bool) -> FailsafeGuidance {
        let mut f = FailsafeGuidance::default();
        track(&mut f, true, true, 0, !in_air);
        f
    }

    /// The touchdown detector with the frame on the ground or in the air.
    fn landing(landed: bool) -> LandingDetector {
        let mut l = LandingDetector::new();
        if !landed {
            l.airborne();
        }
        l
    }

    /// Tracks one loop at `now_ms`: `descent` in failsafe, `entered` this loop.
    fn track(f: &mut FailsafeGuidance, descent: bool, entered: bool, now_ms: u32, landed: bool) {
        let decision = if entered {
            Decision::FailsafeEntered
        } else {
            Decision::Steady
        };
        f.track(descent, decision, now_ms, &landing(landed));
    }

    fn throttle_and_angles(g: Guidance) -> (f32, [f32; 2]) {
        match g {
            Guidance::Failsafe {
                throttle,
                angles_deg,
            } => (throttle, angles_deg),
            other => panic!("not the failsafe's guidance: {other:?}"),
        }
    }

    #[test]
    fn in_the_air_with_a_fix_it_holds_position_and_altitude_for_the_hold_time() {
        let mut f = begun(true);
        let mut hold = Hold::default();
        let n = nav(true);
        // The position hold's target is where the frame was; the altitude's too.
        let (t, angles) =
            throttle_and_angles(f.guide(&situation(0, Some(0.0), Some(n)), &mut hold));
        assert_eq!(hold.altitude_target(), Some(10.0));
        assert_eq!(hold.position_target(), Some([2.0, 0.0]));
        assert!((t - HOVER).abs() < 1e-6, "{t}");
        assert_eq!(angles, [0.0, 0.0]);
        assert!(f.holds_altitude());
        // Blown 1 m further north and sagged 1 m, just before the hold time ends: pitched
        // back (nose up) towards the target and climbing back.
        let drifted = Nav {
            vertical: Some((9.0, 0.0)),
            horizontal: Some(([3.0, 0.0], [0.0, 0.0])),
            ..n
        };
        track(&mut f, true, false, FAILSAFE_HOLD_MS - 1, false);
        let s = situation(FAILSAFE_HOLD_MS - 1, Some(0.0), Some(drifted));
        let (t, [roll, pitch]) = throttle_and_angles(f.guide(&s, &mut hold));
        assert!(t > HOVER + 0.09, "{t}");
        assert!(pitch > 1.0 && roll.abs() < 1e-6, "{roll} {pitch}");
        assert!(f.holds_altitude());
    }

    #[test]
    fn after_the_hold_time_it_descends_in_place_at_the_failsafe_rate() {
        let mut f = begun(true);
        let mut hold = Hold::default();
        let n = nav(true);
        let _ = f.guide(&situation(0, Some(0.0), Some(n)), &mut hold);
        // Level at the hold time's end: the descent's PI asks for −0.7 m/s, so less than
        // the hover throttle; the position still held.
        track(&mut f, true, false, FAILSAFE_HOLD_MS, false);
        let s = situation(FAILSAFE_HOLD_MS, Some(0.0), Some(n));
        let (t, _) = throttle_and_angles(f.guide(&s, &mut hold));
        assert!((t - (HOVER - 0.07)).abs() < 1e-3, "{t}");
        assert!(!f.holds_altitude());
        assert_eq!(hold.position_target(), Some([2.0, 0.0]));
        // Descending at the rate: hover throttle (the integral has barely moved).
        let s = situation(FAILSAFE_HOLD_MS + 2, Some(-0.7), Some(n));
        let (t, _) = throttle_and_angles(f.guide(&s, &mut hold));
        assert!((t - HOVER).abs() < 1e-3, "{t}");
    }

    #[test]
    fn without_a_fix_it_levels_and_descends_at_once() {
        let mut f = begun(true);
        let mut hold = Hold::default();
        let n = nav(false);
        let (t, angles) =
            throttle_and_angles(f.guide(&situation(0, Some(0.0), Some(n)), &mut hold));
        assert_eq!(angles, [0.0, 0.0]);
        assert!((t - (HOVER - 0.07)).abs() < 1e-3, "{t}");
        assert!(!f.holds_altitude());
        assert_eq!(hold.altitude_target(), None);
        // Without even a climb rate: 90 % of the hover throttle.
        let (t, _) = throttle_and_angles(f.guide(&situation(2, None, Some(n)), &mut hold));
        assert!((t - 0.9 * HOVER).abs() < 1e-6, "{t}");
    }

    #[test]
    fn begun_on_the_ground_it_descends_at_once_even_with_a_fix() {
        let mut f = begun(false);
        let mut hold = Hold::default();
        let n = nav(true);
        let (t, _) = throttle_and_angles(f.guide(&situation(0, Some(0.0), Some(n)), &mut hold));
        assert!(!f.holds_altitude());
        assert!(t < HOVER - 0.06, "{t}");
    }

    #[test]
    fn stopped_on_the_ground_it_gives_up_the_position_and_levels() {
        let mut f = begun(false);
        let mut hold = Hold::default();
        let n = nav(true);
        let _ = f.guide(&situation(0, Some(0.0), Some(n)), &mut hold);
        // Pushed 1 m off the held position and not descending (on the ground): the position
        // is still held (pitched back) until STOPPED_MS, then given up for level.
        let pushed = Nav {
            horizontal: Some(([3.0, 0.0], [0.0, 0.0])),
            ..n
        };
        for now in [1_000, 1_999] {
            track(&mut f, true, false, now, true);
            let s = situation(now, Some(0.0), Some(pushed));
            let (_, angles) = throttle_and_angles(f.guide(&s, &mut hold));
            assert!(angles[1] > 1.0, "still holding at {now} ms: {angles:?}");
        }
        track(&mut f, true, false, 2_000, true);
        let s = situation(2_000, Some(0.0), Some(pushed));
        let (_, angles) = throttle_and_angles(f.guide(&s, &mut hold));
        assert_eq!(angles, [0.0, 0.0]);
    }

    #[test]
    fn the_descent_integral_starts_afresh_when_a_failsafe_begins() {
        let mut f = begun(true);
        let mut hold = Hold::default();
        let n = nav(false);
        // 5 s falling at 2 m/s: the integral winds up to its bound.
        for i in 0..2_500 {
            let _ = f.guide(&situation(2 + 2 * i, Some(-2.0), Some(n)), &mut hold);
        }
        let (wound, _) =
            throttle_and_angles(f.guide(&situation(5_002, Some(-0.7), Some(n)), &mut hold));
        assert!((wound - (HOVER + 0.2)).abs() < 1e-3, "{wound}");
        // The link came back, then went again: the new failsafe starts from the hover value.
        track(&mut f, false, false, 6_000, false);
        track(&mut f, true, true, 7_000, false);
        let s = Situation {
            entered: true,
            ..situation(7_000, Some(-0.7), Some(n))
        };
        let (fresh, _) = throttle_and_angles(f.guide(&s, &mut hold));
        assert!((fresh - HOVER).abs() < 1e-3, "{fresh}");
    }

    #[test]
    fn tracking_stops_the_clock_and_clears_the_altitude_hold_each_loop() {
        let mut f = begun(true);
        let mut hold = Hold::default();
        let n = nav(true);
        let _ = f.guide(&situation(0, Some(0.0), Some(n)), &mut hold);
        assert!(f.holds_altitude());
        // Next loop, before any guidance: not yet held.
        track(&mut f, true, false, 2, false);
        assert!(!f.holds_altitude());
        // The failsafe ended, then a new one began on the ground: no altitude hold.
        track(&mut f, false, false, 4, false);
        track(&mut f, true, true, 6, true);
        let _ = f.guide(&situation(6, Some(0.0), Some(n)), &mut hold);
        assert!(!f.holds_altitude());
        // A resume after a reset counts as in the air: the hold again.
        f.resume(8);
        let _ = f.guide(&situation(8, Some(0.0), Some(n)), &mut hold);
        assert!(f.holds_altitude());
    }
}
