//! The 14-state INS/GPS extended Kalman filter (a re-derivation of the Tau Labs
//! `insgps14state.c` model, see `DERIVATION.md`): NED position and velocity, the body→NED
//! attitude quaternion, gyro bias and z accelerometer bias.
//!
//! How to fuse lives in [`Filter`] and [`fusion`] (models, Jacobians, scalar updates, gates);
//! when to fuse — timeouts, persistent-rejection resets, re-alignment — lives in [`aiding`].

pub mod aiding;
mod covariance;
pub mod equations;
pub mod fusion;
mod noise;
mod predict;
mod reset;

pub use crate::align::tilt_from_accel;
pub use aiding::{Aided, Ins};
pub use fusion::Fusion;
pub use noise::SensorNoise;

use crate::quaternion::{self, Quaternion};
use crate::{Error, GRAVITY_MPS2, check_finite};

/// Number of filter states.
pub const STATES: usize = 14;

/// Covariance matrix type (kept symmetric by construction).
pub type Covariance = [[f32; STATES]; STATES];

/// Where each quantity sits in the state vector.
pub mod index {
    /// North, east, down position (m).
    pub const POSITION: usize = 0;
    /// North, east, down velocity (m/s).
    pub const VELOCITY: usize = 3;
    /// Quaternion q0..q3.
    pub const QUATERNION: usize = 6;
    /// Gyro bias x, y, z (rad/s, body).
    pub const GYRO_BIAS: usize = 10;
    /// Accelerometer z bias (m/s², body).
    pub const ACCEL_BIAS_Z: usize = 13;
}

/// Tuning of the filter. Process noises are power spectral densities, so the tuning does not
/// depend on the predict rate (the C reference scaled its Q by dT², DERIVATION.md §7).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Gyro white noise PSD per axis ((rad/s)²·s).
    pub gyro_noise_psd: [f32; 3],
    /// Accelerometer white noise PSD ((m/s²)²·s), isotropic.
    pub accel_noise_psd: f32,
    /// Gyro bias random-walk PSD ((rad/s)²/s).
    pub gyro_bias_walk_psd: f32,
    /// z accelerometer bias random-walk PSD ((m/s²)²/s).
    pub accel_bias_walk_psd: f32,
    /// GPS horizontal position variance (m²).
    pub gps_horizontal_var_m2: f32,
    /// GPS vertical position variance (m²).
    pub gps_vertical_var_m2: f32,
    /// GPS velocity variance per axis ((m/s)²).
    pub gps_velocity_var_m2ps2: f32,
    /// Barometric altitude variance (m²).
    pub baro_var_m2: f32,
    /// Variance of each horizontal heading-frame magnetometer component (field units²).
    pub mag_var: f32,
    /// Earth magnetic field in NED (any unit, the magnetometer's).
    pub earth_field_ned: [f32; 3],
    /// Innovation gate in standard deviations; a measurement beyond it is rejected.
    pub gate_sigma: f32,
    /// Gyro bias estimates are clamped to ± this (rad/s).
    pub gyro_bias_limit_radps: f32,
    /// z accel bias estimate is clamped to ± this (m/s²).
    pub accel_bias_limit_mps2: f32,
    /// Initial standard deviations: position (m), velocity (m/s), quaternion component,
    /// gyro bias (rad/s), accel bias (m/s²).
    pub initial_std: [f32; 5],
}

impl Default for Config {
    /// Tuned on the scenario suite (tests/ins-sim): the C reference's measurement variances
    /// (its Python `CINS` set-up, except the magnetometer's, which is set to the 10-unit
    /// noise the tests inject) with rate-independent process noise, larger initial bias
    /// uncertainty and bias limits wide enough for real sensors (±20 °/s, ±2 m/s²).
    fn default() -> Self {
        Self {
            gyro_noise_psd: [1.5e-8, 1.5e-8, 1.5e-7],
            accel_noise_psd: 1.5e-5,
            gyro_bias_walk_psd: 2e-7,
            accel_bias_walk_psd: 2e-4,
            gps_horizontal_var_m2: 1e-3,
            gps_vertical_var_m2: 10.0,
            gps_velocity_var_m2ps2: 1e-2,
            baro_var_m2: 0.1,
            mag_var: 100.0,
            earth_field_ned: [400.0, 0.0, 1600.0],
            gate_sigma: 5.0,
            gyro_bias_limit_radps: 0.35,
            accel_bias_limit_mps2: 2.0,
            initial_std: [5.0, 2.236, 3.2e-3, 0.03, 0.1],
        }
    }
}

/// A snapshot of the estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct State {
    /// Position NED (m).
    pub position_ned_m: [f32; 3],
    /// Velocity NED (m/s).
    pub velocity_ned_mps: [f32; 3],
    /// Attitude, body → NED.
    pub attitude: Quaternion,
    /// Gyro bias (rad/s, body).
    pub gyro_bias_radps: [f32; 3],
    /// z accelerometer bias (m/s², body).
    pub accel_bias_z_mps2: f32,
}

/// The filter: state vector, covariance and tuning. No globals, so any number can coexist.
#[derive(Debug, Clone)]
pub struct Filter {
    x: [f32; STATES],
    p: Covariance,
    config: Config,
}

impl Filter {
    /// A filter at the origin, level, facing north, with `config`'s initial covariance.
    #[must_use]
    pub fn new(config: Config) -> Self {
        let mut x = [0.0; STATES];
        x[index::QUATERNION] = 1.0;
        let [pos, vel, quat, gyro_bias, accel_bias] = config.initial_std;
        let mut p = [[0.0; STATES]; STATES];
        for (i, row) in p.iter_mut().enumerate() {
            let std = match i {
                0..3 => pos,
                3..6 => vel,
                6..10 => quat,
                10..13 => gyro_bias,
                _ => accel_bias,
            };
            if let Some(d) = row.get_mut(i) {
                *d = std * std;
            }
        }
        Self { x, p, config }
    }

    /// The tuning in use.
    #[must_use]
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Replaces the tuning from the next step on; the state and covariance are kept (a
    /// host that sets its noise per call, as the C reference's `INSSet*Var` did).
    pub fn set_config(&mut self, config: Config) {
        self.config = config;
    }

    /// The current estimate.
    #[must_use]
    pub fn state(&self) -> State {
        let [pn, pe, pd, vn, ve, vd, q0, q1, q2, q3, bx, by, bz, ab_z] = self.x;
        State {
            position_ned_m: [pn, pe, pd],
            velocity_ned_mps: [vn, ve, vd],
            attitude: [q0, q1, q2, q3],
            gyro_bias_radps: [bx, by, bz],
            accel_bias_z_mps2: ab_z,
        }
    }

    /// The raw state vector.
    #[must_use]
    pub fn state_vector(&self) -> &[f32; STATES] {
        &self.x
    }

    /// The covariance matrix.
    #[must_use]
    pub fn covariance(&self) -> &Covariance {
        &self.p
    }

    /// Overwrites the estimate (not the covariance, as the C reference's `INSSetState`).
    /// The quaternion is normalised.
    ///
    /// # Errors
    /// [`Error::NonFinite`] if any value is not finite; nothing is changed then.
    pub fn set_state(&mut self, state: &State) -> Result<(), Error> {
        let State {
            position_ned_m: [pn, pe, pd],
            velocity_ned_mps: [vn, ve, vd],
            attitude,
            gyro_bias_radps: [bx, by, bz],
            accel_bias_z_mps2: ab_z,
        } = *state;
        let [q0, q1, q2, q3] = quaternion::normalized(attitude);
        let x = [pn, pe, pd, vn, ve, vd, q0, q1, q2, q3, bx, by, bz, ab_z];
        check_finite(&x)?;
        self.x = x;
        Ok(())
    }

    /// Gravity used by the process model (m/s²).
    #[must_use]
    pub const fn gravity_mps2() -> f32 {
        GRAVITY_MPS2
    }

    fn attitude(&self) -> Quaternion {
        let [_, _, _, _, _, _, q0, q1, q2, q3, _, _, _, _] = self.x;
        [q0, q1, q2, q3]
    }

    /// Clamps the biases to the configured limits (the C reference's `INSLimitBias`, DERIVATION.md
    /// §6–7, with wider limits).
    fn limit_biases(&mut self) {
        let g = self.config.gyro_bias_limit_radps;
        let a = self.config.accel_bias_limit_mps2;
        let [.., bx, by, bz, ab_z] = &mut self.x;
        for b in [bx, by, bz] {
            *b = symmetric_clamp(*b, g);
        }
        *ab_z = symmetric_clamp(*ab_z, a);
    }

    /// q/|q|, keeping q's sign. Not `quaternion::normalized`, which makes the scalar part
    /// non-negative: near a 180° heading (or roll) q0 crosses zero, and flipping q there
    /// while P keeps the quaternion's cross-covariances (with the biases, the velocity)
    /// made every correction across the flip pull the wrong way — the heading error that
    /// stayed after a start facing south.
    fn renormalize(&mut self) {
        let q = self.attitude();
        let n2 = q.iter().map(|c| c * c).sum::<f32>();
        if !(n2 > f32::MIN_POSITIVE && n2.is_finite()) {
            return;
        }
        let s = crate::math::inv_sqrt(n2);
        let [q0, q1, q2, q3] = q.map(|c| c * s);
        let [.., a, b, c, d, _, _, _, _] = &mut self.x;
        (*a, *b, *c, *d) = (q0, q1, q2, q3);
    }

    /// Finiteness of the state and the variances with one sum instead of 210 tests: NaN and
    /// ±∞ propagate through addition (∞ − ∞ = NaN), and a sum that overflowed would mean a
    /// diverged filter anyway. Off-diagonal terms are not scanned: a non-finite covariance
    /// term reaches the diagonal or the state at the next update and is caught then.
    fn is_finite(&self) -> bool {
        let mut sum = 0.0_f32;
        for (i, (x, row)) in self.x.iter().zip(self.p.iter()).enumerate() {
            sum += x + row.get(i).copied().unwrap_or(0.0);
        }
        sum.is_finite()
    }
}

/// Clamps to ±`limit` without `f32::clamp`, which panics on a negative or NaN limit (a bad
/// config must not be able to panic the filter; it just disables the clamp).
fn symmetric_clamp(x: f32, limit: f32) -> f32 {
    if x > limit {
        limit
    } else if x < -limit {
        -limit
    } else {
        x
    }
}
