//! Complementary attitude filter (Mahony style) for flight without GPS: the gyro is
//! integrated, the accelerometer pulls the estimated "down" towards measured gravity and the
//! magnetometer pulls the heading only; an integral term learns the gyro bias.
//!
//! It starts from the first still sample ([`Complementary::align`], `estimation::align`),
//! not level and north, and re-aligns its heading from the magnetometer when the two keep
//! disagreeing by more than 30° ([`REALIGN_COS`]) for [`REALIGN_AFTER_S`] (after a new
//! magnetometer calibration, or a start facing the heading where the proportional pull
//! vanishes: sin 180° = 0).

use crate::align;
use crate::math::inv_sqrt;
use crate::quaternion::{self, Quaternion, ned_to_body};
use crate::{Error, check_finite};

/// The cosine of the heading disagreement (30°) beyond which the filter counts towards a
/// re-alignment.
pub const REALIGN_COS: f32 = 0.866_025_4;
/// How long the disagreement must last (s): longer than a magnetic disturbance passing.
pub const REALIGN_AFTER_S: f32 = 1.0;

/// Gains of the complementary filter.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Proportional gain on the accelerometer error (rad/s per rad).
    pub accel_kp: f32,
    /// Integral gain on the accelerometer error (learns x/y gyro bias).
    pub accel_ki: f32,
    /// Proportional gain on the magnetometer heading error.
    pub mag_kp: f32,
    /// Integral gain on the heading error (learns z gyro bias).
    pub mag_ki: f32,
    /// The accelerometer is ignored when |f| differs from g by more than this fraction.
    pub accel_trust_band: f32,
    /// Earth field direction in NED (any scale); only its horizontal part is used.
    pub earth_field_ned: [f32; 3],
}

impl Default for Config {
    fn default() -> Self {
        Self {
            accel_kp: 1.0,
            accel_ki: 0.1,
            mag_kp: 1.0,
            mag_ki: 0.1,
            accel_trust_band: 0.2,
            earth_field_ned: [1.0, 0.0, 0.0],
        }
    }
}

/// Attitude and gyro-bias estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Complementary {
    config: Config,
    attitude: Quaternion,
    gyro_bias_radps: [f32; 3],
    /// How long the magnetometer has disagreed by more than 30° (s).
    heading_off_s: f32,
}

impl Complementary {
    /// A filter starting level and facing north.
    #[must_use]
    pub fn new(config: Config) -> Self {
        Self {
            config,
            attitude: quaternion::IDENTITY,
            gyro_bias_radps: [0.0; 3],
            heading_off_s: 0.0,
        }
    }

    /// Starts from a still frame's accelerometer and (if any) magnetometer sample, whatever
    /// way it points ([`align::attitude`]); the gyro bias is kept.
    ///
    /// # Errors
    /// [`Error::NonFinite`]; the estimate is unchanged then.
    pub fn align(&mut self, accel_mps2: [f32; 3], mag: Option<[f32; 3]>) -> Result<(), Error> {
        check_finite(&accel_mps2)?;
        if let Some(m) = mag {
            check_finite(&m)?;
        }
        self.attitude = align::attitude(accel_mps2, mag, self.config.earth_field_ned);
        self.heading_off_s = 0.0;
        Ok(())
    }

    /// Body → NED attitude.
    #[must_use]
    pub fn attitude(&self) -> Quaternion {
        self.attitude
    }

    /// Estimated gyro bias (rad/s).
    #[must_use]
    pub fn gyro_bias_radps(&self) -> [f32; 3] {
        self.gyro_bias_radps
    }

    /// Takes over an estimate (attitude normalised, gyro bias) from another estimator, so a
    /// hand-over to this filter continues from where the other one was instead of jumping.
    ///
    /// # Errors
    /// [`Error::NonFinite`]; the estimate is unchanged then.
    pub fn reset(&mut self, attitude: Quaternion, gyro_bias_radps: [f32; 3]) -> Result<(), Error> {
        check_finite(&attitude)?;
        check_finite(&gyro_bias_radps)?;
        self.attitude = quaternion::normalized(attitude);
        self.gyro_bias_radps = gyro_bias_radps;
        Ok(())
    }

    /// One step: gyro (rad/s), specific force (m/s², level reads [0,0,−g]), optional
    /// magnetometer (any unit), `dt_s` in seconds.
    ///
    /// # Errors
    /// [`Error::NonFinite`] or [`Error::InvalidTimeStep`]; the estimate is unchanged then.
    pub fn update(
        &mut self,
        gyro_radps: [f32; 3],
        accel_mps2: [f32; 3],
        mag: Option<[f32; 3]>,
        dt_s: f32,
    ) -> Result<(), Error> {
        self.update_with(gyro_radps, accel_mps2, true, mag, dt_s)
    }

    /// [`Self::update`] where the accelerometer corrects only if `accel_corrects` (armed,
    /// one sample in `armed_accel_divider`); it is checked for finiteness either way, so a
    /// broken accelerometer is refused on every sample.
    ///
    /// # Errors
    /// [`Error::NonFinite`] or [`Error::InvalidTimeStep`]; the estimate is unchanged then.
    pub fn update_with(
        &mut self,
        gyro_radps: [f32; 3],
        accel_mps2: [f32; 3],
        accel_corrects: bool,
        mag: Option<[f32; 3]>,
        dt_s: f32,
    ) -> Result<(), Error> {
        check_finite(&gyro_radps)?;
        check_finite(&accel_mps2)?;
        if let Some(m) = mag {
            check_finite(&m)?;
        }
        if !(dt_s > 0.0 && dt_s <= 0.1) {
            return Err(Error::InvalidTimeStep);
        }
        let cfg = self.config;
        // The rotation matrix only when a vector corrects: armed, the accelerometer is
        // skipped on most samples and there is seldom a magnetometer sample.
        let r = || ned_to_body(self.attitude);
        let mut correction = [0.0_f32; 3];
        let mut integral = [0.0_f32; 3];
        let mut corrected = false;
        // Accelerometer: measured "up" (−f/|f|) against the estimated up (−third column of
        // R_be); their cross product is the rotation error in body axes.
        let [ax, ay, az] = accel_mps2;
        let f2 = ax * ax + ay * ay + az * az;
        let g = crate::GRAVITY_MPS2;
        if accel_corrects && f2 > 1e-6 {
            let inv = inv_sqrt(f2);
            let norm = f2 * inv;
            if (norm - g).abs() < cfg.accel_trust_band * g {
                let meas = [-ax * inv, -ay * inv, -az * inv];
                let r = r();
                let est = [-r[0][2], -r[1][2], -r[2][2]];
                let e = cross(est, meas);
                corrected = true;
                for ((c, i), e) in correction.iter_mut().zip(integral.iter_mut()).zip(e) {
                    *c += cfg.accel_kp * e;
                    *i += cfg.accel_ki * e;
                }
            }
        }
        if let Some(m) = mag {
            // Heading only: compare horizontal directions in NED, apply about NED down.
            let [mn, me, _] = quaternion::body_to_ned_vector(self.attitude, m);
            let [bn, be, _] = cfg.earth_field_ned;
            let (m2, b2) = (mn * mn + me * me, bn * bn + be * be);
            if m2 > 1e-12 && b2 > 1e-12 {
                let s = inv_sqrt(m2) * inv_sqrt(b2);
                // sin of the angle from measured to reference, about down.
                let yaw_error = (mn * be - me * bn) * s;
                // cos of it: far off for long, the heading is re-aligned instead.
                let cos_error = (mn * bn + me * be) * s;
                if keeps_disagreeing(&mut self.heading_off_s, cos_error, dt_s) {
                    self.realign_heading(m);
                    return Ok(());
                }
                let r = r();
                let down_body = [r[0][2], r[1][2], r[2][2]];
                corrected = true;
                for ((c, i), d) in correction
                    .iter_mut()
                    .zip(integral.iter_mut())
                    .zip(down_body)
                {
                    *c += cfg.mag_kp * yaw_error * d;
                    *i += cfg.mag_ki * yaw_error * d;
                }
            }
        }
        // No vector corrected this sample (armed, most samples): the bias stays as it is.
        if corrected {
            for (b, i) in self.gyro_bias_radps.iter_mut().zip(integral) {
                *b -= i * dt_s;
            }
        }
        let omega: [f32; 3] = core::array::from_fn(|k| {
            gyro_radps.get(k).copied().unwrap_or(0.0)
                - self.gyro_bias_radps.get(k).copied().unwrap_or(0.0)
                + correction.get(k).copied().unwrap_or(0.0)
        });
        self.attitude = renormalized(quaternion::rotate_by_body_vector(
            self.attitude,
            omega.map(|w| w * dt_s),
        ));
        Ok(())
    }
}

/// Counts in `off_s` how long the heading has been off by more than 30° (`cos_error`
/// below [`REALIGN_COS`]); true once it has been for [`REALIGN_AFTER_S`].
fn keeps_disagreeing(off_s: &mut f32, cos_error: f32, dt_s: f32) -> bool {
    if cos_error < REALIGN_COS {
        *off_s += dt_s;
    } else {
        *off_s = 0.0;
    }
    *off_s >= REALIGN_AFTER_S
}

impl Complementary {
    /// Keeps roll and pitch, sets the heading from the magnetometer (cold path).
    fn realign_heading(&mut self, mag: [f32; 3]) {
        let [roll, pitch, _] = quaternion::to_euler(self.attitude);
        if let Some(yaw) = align::heading_from_mag(roll, pitch, mag, self.config.earth_field_ned) {
            self.attitude = quaternion::from_euler(roll, pitch, yaw);
        }
        self.heading_off_s = 0.0;
    }
}

/// `quaternion::normalized` for a quaternion one filter step away from unit length:
/// |q|² = 1 + ε with |ε| ≈ 1e-7 (rounding, the rotation series' error), and
/// 1/√(1 + ε) = 1 − ε/2 + 3ε²/8 − …, so s = (3 − |q|²)/2 is exact to f32 rounding while
/// |ε| < 2⁻¹² (the neglected 3ε²/8 < 3·2⁻²⁷, below half an ulp of 1) — no inverse square
/// root. Anything further off (a reset, NaN) takes the full normalisation.
fn renormalized(q: Quaternion) -> Quaternion {
    let [q0, q1, q2, q3] = q;
    let n2 = q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3;
    if (n2 - 1.0).abs() < 1.0 / 4096.0 {
        let s = 1.5 - 0.5 * n2;
        // The scalar part is kept non-negative, as `normalized` does.
        let s = if q0 < 0.0 { -s } else { s };
        q.map(|c| c * s)
    } else {
        quaternion::normalized(q)
    }
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn simulate(truth: Quaternion, gyro_bias: [f32; 3], seconds: f32) -> Complementary {
        let field = [0.4, 0.05, 0.9];
        let mut cf = Complementary::new(Config {
            earth_field_ned: field,
            ..Config::default()
        });
        let accel = quaternion::ned_to_body_vector(truth, [0.0, 0.0, -crate::GRAVITY_MPS2]);
        let mag = quaternion::ned_to_body_vector(truth, field);
        let dt = 0.002;
        for _ in 0..(seconds / dt) as usize {
            cf.update(gyro_bias, accel, Some(mag), dt).unwrap();
        }
        cf
    }

    #[test]
    fn converges_in_tilt_without_mag() {
        let truth = quaternion::from_euler(0.35, -0.17, 0.0);
        let mut cf = Complementary::new(Config::default());
        let accel = quaternion::ned_to_body_vector(truth, [0.0, 0.0, -crate::GRAVITY_MPS2]);
        for _ in 0..30000 {
            cf.update([0.0; 3], accel, None, 0.002).unwrap();
        }
        let [r, p, _] = quaternion::to_euler(cf.attitude());
        assert!(
            (r - 0.35).abs() < 1e-3 && (p + 0.17).abs() < 1e-3,
            "{r} {p}"
        );
    }

    #[test]
    fn converges_to_tilted_heading_and_learns_bias() {
        // GIVEN a static craft rolled 20°, pitched −10°, yawed 120° with a gyro offset
        let truth = quaternion::from_euler(0.35, -0.17, 2.1);
        // WHEN the filter runs 60 s from level/north
        let cf = simulate(truth, [0.02, -0.03, 0.01], 60.0);
        // THEN attitude is within 0.5° and the bias within 10 %
        let err = quaternion::angle_between(cf.attitude(), truth).to_degrees();
        assert!(err < 0.5, "attitude error {err}°");
        let b = cf.gyro_bias_radps();
        assert!(
            (b[0] - 0.02).abs() < 0.002
                && (b[1] + 0.03).abs() < 0.003
                && (b[2] - 0.01).abs() < 0.001,
            "{b:?}"
        );
    }

    #[test]
    fn renormalising_near_unit_length_matches_the_full_normalisation() {
        // One step's worth of error either way, and a quaternion far off (full path).
        for (k, scale) in [1.0_f32, 1.0 + 1e-7, 1.0 - 2e-7, 1.0 + 1e-4, 1.0 - 1e-4, 3.0]
            .into_iter()
            .enumerate()
        {
            let q = quaternion::from_euler(0.3 * k as f32, -0.2, 2.0 - k as f32).map(|c| c * scale);
            let (fast, full) = (renormalized(q), quaternion::normalized(q));
            for (a, b) in fast.iter().zip(full) {
                assert!((a - b).abs() < 2.5e-7, "{scale}: {fast:?} vs {full:?}");
            }
        }
        // Negative scalar part flipped, NaN to the identity, as the full one does.
        assert!(renormalized([-1.0, 0.0, 0.0, 0.0])[0] > 0.0);
        assert_eq!(renormalized([f32::NAN; 4]), quaternion::IDENTITY);
    }

    #[test]
    fn a_skipped_accelerometer_is_still_checked_but_does_not_correct() {
        let mut cf = Complementary::new(Config::default());
        let tilted = [0.0, -3.0, -9.3];
        for _ in 0..100 {
            cf.update_with([0.0; 3], tilted, false, None, 0.002)
                .unwrap();
        }
        assert_eq!(cf.attitude(), quaternion::IDENTITY);
        assert_eq!(
            cf.update_with([0.0; 3], [f32::NAN, 0.0, -9.8], false, None, 0.002),
            Err(Error::NonFinite)
        );
        cf.update_with([0.0; 3], tilted, true, None, 0.002).unwrap();
        assert_ne!(cf.attitude(), quaternion::IDENTITY);
    }

    #[test]
    fn a_start_facing_away_from_the_field_is_realigned() {
        // GIVEN a frame facing south and a filter that starts north (not aligned): the
        // proportional heading pull is sin 180° = 0
        let field = [0.4, 0.05, 0.9];
        let truth = quaternion::from_euler(0.0, 0.0, core::f32::consts::PI);
        let mut cf = Complementary::new(Config {
            earth_field_ned: field,
            ..Config::default()
        });
        let accel = quaternion::ned_to_body_vector(truth, [0.0, 0.0, -crate::GRAVITY_MPS2]);
        let mag = quaternion::ned_to_body_vector(truth, field);
        // WHEN it runs 1.2 s with the magnetometer
        for _ in 0..600 {
            cf.update([0.0; 3], accel, Some(mag), 0.002).unwrap();
        }
        // THEN after the 1 s of disagreement the heading was re-aligned
        let err = quaternion::angle_between(cf.attitude(), truth).to_degrees();
        assert!(err < 1.0, "{err}°");
    }

    #[test]
    fn align_starts_from_one_sample_whatever_the_heading() {
        let field = [0.4, 0.05, 0.9];
        let truth = quaternion::from_euler(0.2, 0.3, -2.5);
        let mut cf = Complementary::new(Config {
            earth_field_ned: field,
            ..Config::default()
        });
        let accel = quaternion::ned_to_body_vector(truth, [0.0, 0.0, -crate::GRAVITY_MPS2]);
        cf.align(accel, Some(quaternion::ned_to_body_vector(truth, field)))
            .unwrap();
        assert!(quaternion::angle_between(cf.attitude(), truth).to_degrees() < 0.01);
        assert_eq!(cf.align([f32::NAN; 3], None), Err(Error::NonFinite));
    }

    #[test]
    fn refuses_non_finite_input() {
        let mut cf = Complementary::new(Config::default());
        assert_eq!(
            cf.update([f32::NAN, 0.0, 0.0], [0.0, 0.0, -9.8], None, 0.002),
            Err(Error::NonFinite)
        );
        assert_eq!(
            cf.update([0.0; 3], [0.0, 0.0, -9.8], None, 0.0),
            Err(Error::InvalidTimeStep)
        );
        assert_eq!(cf.attitude(), quaternion::IDENTITY);
    }
}
