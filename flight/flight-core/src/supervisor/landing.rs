//! Touchdown detection: whether the frame stands on the ground while armed. The supervisor's
//! failsafe disarm and idle disarm both wait for it, so neither can stop the motors in the air.
//!
//! The physics: with the thrust command clearly below what holds a hover, a flying frame
//! accelerates downwards. If the vertical estimate nevertheless shows no descent, something
//! holds it up — the ground. The gyro being quiet and the accelerometer reading ≈ 1 g are
//! checked too, but they are not enough on their own: a steady hover or a steady descent
//! shows them as well. All four conditions must hold for [`LANDED_HOLD_MS`] in a row.
//!
//! Without a vertical estimate (no baro) landing cannot be detected: the detector then never
//! declares a landing after a take-off (the pilot disarms by gesture; a failsafe ends only
//! by the supervisor's last-resort time limit).
//!
//! It starts landed (motors are off at power-up and arming needs a closed throttle) and
//! leaves that state on any sign of a take-off: thrust above [`TAKEOFF_THRUST`] (the pilot
//! raised the throttle out of the idle band — the hover estimate may still be far off before
//! the first flight, so thrust against it proves nothing), or vertical movement. A false
//! "airborne" only delays a disarm; a false "landed" would stop motors in the air.

/// Climb rate magnitude below which the frame counts as not moving vertically, m/s. Well
/// below the slowest failsafe descent setting (0.2 m/s is the floor of `failsafe.descent_mps`
/// — see [`landed_climb_limit`]) and above the baro-rate noise on the ground (≈ 0.05 m/s).
pub const LANDED_CLIMB_MPS: f32 = 0.3;
/// The thrust must be this far (throttle units, 0…1) below the hover estimate: with
/// ≈ 60 m/s² per unit throttle that is a ≈ 6 m/s² downward demand no air can hide.
pub const THRUST_MARGIN: f32 = 0.1;
/// Gyro quiet: every axis below this, deg/s.
pub const QUIET_GYRO_DPS: f32 = 20.0;
/// Accelerometer within this fraction of 1 g.
pub const ONE_G_TOLERANCE: f32 = 0.1;
/// How long every condition must hold, ms.
pub const LANDED_HOLD_MS: u32 = 1_000;
/// Vertical speed that proves the frame left the ground, m/s (the blended rate's noise on
/// the ground is ≈ 0.05 m/s).
pub const TAKEOFF_CLIMB_MPS: f32 = 0.5;
/// Thrust command above which a landed frame counts as taking off (throttle units): the
/// flight loop's own "throttle raised" threshold.
pub const TAKEOFF_THRUST: f32 = 0.1;

/// The climb-rate band counted as "not descending" for a commanded descent rate: never more
/// than half the commanded rate, so a steady descent can never look landed.
pub fn landed_climb_limit(descent_mps: f32) -> f32 {
    crate::estimation::math::min(LANDED_CLIMB_MPS, 0.5 * descent_mps.abs())
}

/// What the detector looks at each loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LandingInputs {
    /// Milliseconds since boot (wrapping).
    pub now_ms: u32,
    /// Angular rate, deg/s.
    pub gyro_dps: [f32; 3],
    /// Specific force, m/s².
    pub accel_mps2: [f32; 3],
    /// Vertical velocity estimate, m/s up (`None` without a baro/INS).
    pub climb_mps: Option<f32>,
    /// Collective thrust command 0…1 (before idle and mixing).
    pub thrust: f32,
    /// Thrust that holds a hover, 0…1 (the loop's estimate).
    pub hover_thrust: f32,
    /// The commanded descent rate in failsafe, m/s (positive down), else `None`.
    pub failsafe_descent_mps: Option<f32>,
}

/// The touchdown detector.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LandingDetector {
    landed: bool,
    candidate_since: Option<u32>,
}

impl Default for LandingDetector {
    fn default() -> Self {
        Self::new()
    }
}

impl LandingDetector {
    /// Starts landed.
    pub const fn new() -> Self {
        Self {
            landed: true,
            candidate_since: None,
        }
    }

    /// Back to landed (the motors are stopped: the frame is on the ground or falling, and
    /// nothing flies until a new arm).
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// In the air (a flight resumed after a reset): no touchdown until one is detected.
    pub fn airborne(&mut self) {
        self.landed = false;
        self.candidate_since = None;
    }

    /// A loop holds the altitude (the failsafe's hold with a GPS fix): "not descending" is
    /// then by design and proves nothing, so no touchdown is concluded — the candidate is
    /// dropped and the state kept.
    pub fn hold_off(&mut self) {
        self.candidate_since = None;
    }

    /// Whether the frame stands on the ground.
    pub fn landed(&self) -> bool {
        self.landed
    }

    /// One loop; returns [`LandingDetector::landed`].
    pub fn update(&mut self, i: &LandingInputs) -> bool {
        let thrust_low = i.thrust.is_finite() && i.thrust <= i.hover_thrust - THRUST_MARGIN;
        let climb_limit = i
            .failsafe_descent_mps
            .map_or(LANDED_CLIMB_MPS, landed_climb_limit);
        if self.landed {
            let moved = i
                .climb_mps
                .is_some_and(|c| !c.is_finite() || c.abs() > TAKEOFF_CLIMB_MPS);
            let thrust_up = !i.thrust.is_finite() || i.thrust > TAKEOFF_THRUST;
            if !thrust_low || thrust_up || moved {
                self.landed = false;
                self.candidate_since = None;
            }
            return self.landed;
        }
        // Evaluated lazily, cheapest and most often false first: in flight the thrust is
        // rarely low, so the usual step ends at the first test.
        let still = |c: Option<f32>| c.is_some_and(|c| c.is_finite() && c.abs() < climb_limit);
        // `abs() < limit` is false for NaN and ±∞: no separate finiteness test.
        let quiet = |gyro: &[f32; 3]| gyro.iter().all(|g| g.abs() < QUIET_GYRO_DPS);
        let one_g = |[x, y, z]: [f32; 3]| {
            let g = crate::estimation::GRAVITY_MPS2;
            let (lo, hi) = ((1.0 - ONE_G_TOLERANCE) * g, (1.0 + ONE_G_TOLERANCE) * g);
            (lo * lo..hi * hi).contains(&(x * x + y * y + z * z))
        };
        if thrust_low && still(i.climb_mps) && quiet(&i.gyro_dps) && one_g(i.accel_mps2) {
            let since = *self.candidate_since.get_or_insert(i.now_ms);
            if i.now_ms.wrapping_sub(since) >= LANDED_HOLD_MS {
                self.landed = true;
                self.candidate_since = None;
            }
        } else {
            self.candidate_since = None;
        }
        self.landed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: f32 = crate::estimation::GRAVITY_MPS2;

    /// A frame in the air descending steadily at `descent` m/s under failsafe: thrust just
    /// under hover (drag balances the rest), gyro quiet, the accelerometer reading 1 g.
    fn descending(now_ms: u32, descent: f32) -> LandingInputs {
        LandingInputs {
            now_ms,
            gyro_dps: [1.0, -1.0, 0.5],
            accel_mps2: [0.0, 0.0, -G],
            climb_mps: Some(-descent),
            thrust: 0.48,
            hover_thrust: 0.5,
            failsafe_descent_mps: Some(0.7),
        }
    }

    fn airborne() -> LandingDetector {
        let mut d = LandingDetector::new();
        let mut climb = descending(0, 0.0);
        climb.thrust = 0.6;
        climb.climb_mps = Some(2.0);
        assert!(!d.update(&climb));
        d
    }

    #[test]
    fn steady_descent_from_60_m_never_lands() {
        // 0.7 m/s from 60 m: 86 s at 1 kHz, even with the hover estimate 0.2 too high (the
        // descent PI's integral then holds the thrust 0.2 below it).
        for hover in [0.5, 0.7] {
            let mut d = airborne();
            for k in 0..86_000 {
                let mut s = descending(k, 0.7);
                s.hover_thrust = hover;
                s.thrust = 0.48;
                assert!(!d.update(&s), "landed in the air at {k} ms (hover {hover})");
            }
        }
    }

    #[test]
    fn hover_with_quiet_gyro_and_one_g_is_not_landed() {
        let mut d = airborne();
        for k in 0..60_000 {
            let mut s = descending(k, 0.0);
            s.thrust = 0.5;
            s.failsafe_descent_mps = None;
            assert!(!d.update(&s));
        }
    }

    #[test]
    fn touchdown_is_detected_within_two_seconds() {
        let mut d = airborne();
        for k in 0..10_000 {
            d.update(&descending(k, 0.7));
        }
        // Touchdown at 10 s: the climb rate goes to 0; the descent PI winds the thrust down
        // (0.1 per m/s at once, then 0.14 per second).
        let mut landed_at = None;
        for k in 10_000..14_000u32 {
            let t = (k - 10_000) as f32 / 1000.0;
            let mut s = descending(k, 0.0);
            s.thrust = 0.5 - 0.07 - (0.14 * t).min(0.2);
            if d.update(&s) && landed_at.is_none() {
                landed_at = Some(k);
            }
        }
        let landed_at = landed_at.unwrap();
        assert!((11_000..12_000).contains(&landed_at), "{landed_at}");
    }

    #[test]
    fn a_shaking_or_weightless_frame_is_not_landed() {
        for bad in [
            |s: &mut LandingInputs| s.gyro_dps[0] = 40.0,
            |s: &mut LandingInputs| s.accel_mps2[2] = -0.5 * G,
            |s: &mut LandingInputs| s.climb_mps = None,
            |s: &mut LandingInputs| s.thrust = 0.45,
        ] {
            let mut d = airborne();
            for k in 0..5_000 {
                let mut s = descending(k, 0.0);
                s.thrust = 0.3;
                bad(&mut s);
                assert!(!d.update(&s));
            }
        }
    }

    #[test]
    fn starts_landed_and_takes_off_on_thrust_or_movement() {
        let mut d = LandingDetector::new();
        let mut ground = descending(0, 0.0);
        ground.thrust = 0.0;
        for k in 0..5_000 {
            ground.now_ms = k;
            // Baro noise on the ground does not count as a take-off.
            ground.climb_mps = Some(if k % 2 == 0 { 0.2 } else { -0.2 });
            assert!(d.update(&ground));
        }
        // A gentle take-off at the real hover thrust (0.11) while the hover estimate still
        // holds its 0.5 start value, climbing at only 0.2 m/s: airborne at once.
        let mut up = ground;
        up.thrust = 0.11;
        up.climb_mps = Some(0.2);
        assert!(!d.update(&up));
        d.reset();
        let mut knocked = ground;
        knocked.climb_mps = Some(-1.5);
        assert!(!d.update(&knocked));
    }

    #[test]
    fn a_held_altitude_never_lands_and_the_count_starts_over_after_it() {
        // GIVEN a frame in the air whose loop holds the altitude on a hover estimate 0.15
        // too high (thrust "low", not descending, quiet, 1 g: every touchdown condition)
        let mut d = airborne();
        let held = |k| {
            let mut s = descending(k, 0.0);
            s.hover_thrust = 0.65;
            s
        };
        // WHEN the hold holds the detector off for a minute, with a step now and then
        for k in 0..60_000 {
            if k % 700 == 0 {
                assert!(!d.update(&held(k)));
            } else {
                d.hold_off();
            }
        }
        // THEN it never lands, and after the hold the full second is needed again
        assert!(!d.landed());
        assert!(!d.update(&held(60_000)));
        assert!(!d.update(&held(60_999)));
        assert!(d.update(&held(61_000)));
    }
}
