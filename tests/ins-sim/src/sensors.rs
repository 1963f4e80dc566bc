//! Sensor models: truth plus bias (optionally stepping at a given time), scale error and
//! white noise, each at its own rate. Everything is deterministic given the seed.

use crate::trajectory::{Truth, rotate_to_body};
use crate::zip3;
use sim_rng::SplitMix64;

/// A bias that may change once, at `step_time_s`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Bias {
    /// Bias from the start.
    pub initial: [f64; 3],
    /// Bias from `step_time_s` on (replaces `initial`).
    pub after_step: [f64; 3],
    /// When the bias steps; `None` keeps `initial` for ever.
    pub step_time_s: Option<f64>,
}

impl Bias {
    /// A constant bias.
    #[must_use]
    pub fn constant(b: [f64; 3]) -> Self {
        Self {
            initial: b,
            after_step: b,
            step_time_s: None,
        }
    }

    /// No bias before `t`, `b` afterwards.
    #[must_use]
    pub fn step(t: f64, b: [f64; 3]) -> Self {
        Self {
            initial: [0.0; 3],
            after_step: b,
            step_time_s: Some(t),
        }
    }

    /// The bias at time `t`.
    #[must_use]
    pub fn at(&self, t: f64) -> [f64; 3] {
        match self.step_time_s {
            Some(s) if t >= s => self.after_step,
            _ => self.initial,
        }
    }
}

/// IMU model (gyro and accelerometer).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuModel {
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Gyro bias (rad/s).
    pub gyro_bias: Bias,
    /// Accelerometer bias (m/s²).
    pub accel_bias: Bias,
    /// Gyro scale factor error (1.0 = perfect).
    pub gyro_scale: f64,
    /// Accelerometer scale factor error.
    pub accel_scale: f64,
    /// Gyro white noise per sample (rad/s, 1σ).
    pub gyro_noise: f64,
    /// Accelerometer white noise per sample (m/s², 1σ).
    pub accel_noise: f64,
}

/// Magnetometer model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MagModel {
    /// Sample rate (Hz); 0 disables it.
    pub rate_hz: f64,
    /// Earth field NED.
    pub earth_field_ned: [f64; 3],
    /// `Some(v)`: the sensor reads this constant body vector (the static tests' fixed mag).
    pub fixed_body: Option<[f64; 3]>,
    /// Scale per axis.
    pub scale: [f64; 3],
    /// White noise (1σ).
    pub noise: f64,
}

/// Barometer model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaroModel {
    /// Sample rate (Hz); 0 disables it.
    pub rate_hz: f64,
    /// Altitude offset (m).
    pub offset_m: f64,
    /// White noise (m, 1σ).
    pub noise_m: f64,
}

/// GPS model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpsModel {
    /// Fix rate (Hz); 0 disables it.
    pub rate_hz: f64,
    /// Position noise per axis (m, 1σ).
    pub position_noise_m: f64,
    /// Velocity noise per axis (m/s, 1σ).
    pub velocity_noise_mps: f64,
}

/// One IMU sample and whatever slower sensors produced at the same instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Readings {
    /// Gyro (rad/s).
    pub gyro_radps: [f32; 3],
    /// Accelerometer (m/s²).
    pub accel_mps2: [f32; 3],
    /// Magnetometer, when due.
    pub mag: Option<[f32; 3]>,
    /// Baro altitude (m), when due.
    pub baro_m: Option<f32>,
    /// GPS position and velocity (NED), when due.
    pub gps: Option<([f32; 3], [f32; 3])>,
}

fn to_f32(v: [f64; 3]) -> [f32; 3] {
    v.map(|c| c as f32)
}

/// Three independent normals scaled by `std`.
fn normal3(rng: &mut SplitMix64, std: f64) -> [f64; 3] {
    [
        rng.gaussian() * std,
        rng.gaussian() * std,
        rng.gaussian() * std,
    ]
}

impl ImuModel {
    /// Reading for `truth`.
    pub fn read(&self, truth: &Truth, rng: &mut SplitMix64) -> ([f32; 3], [f32; 3]) {
        let gb = self.gyro_bias.at(truth.time_s);
        let ab = self.accel_bias.at(truth.time_s);
        let ng = normal3(rng, self.gyro_noise);
        let na = normal3(rng, self.accel_noise);
        let gyro = zip3(
            zip3(truth.gyro_radps, gb, |t, b| t * self.gyro_scale + b),
            ng,
            |a, n| a + n,
        );
        let accel = zip3(
            zip3(truth.accel_mps2, ab, |t, b| t * self.accel_scale + b),
            na,
            |a, n| a + n,
        );
        (to_f32(gyro), to_f32(accel))
    }
}

impl MagModel {
    /// Reading for `truth`.
    pub fn read(&self, truth: &Truth, rng: &mut SplitMix64) -> [f32; 3] {
        let body = self
            .fixed_body
            .unwrap_or_else(|| rotate_to_body(truth.attitude, self.earth_field_ned));
        let n = normal3(rng, self.noise);
        to_f32(zip3(zip3(body, self.scale, |b, s| b * s), n, |a, n| a + n))
    }
}

impl BaroModel {
    /// Reading for `truth`.
    pub fn read(&self, truth: &Truth, rng: &mut SplitMix64) -> f32 {
        (-truth.position_ned_m[2] + self.offset_m + rng.gaussian() * self.noise_m) as f32
    }
}

impl GpsModel {
    /// Reading for `truth`.
    pub fn read(&self, truth: &Truth, rng: &mut SplitMix64) -> ([f32; 3], [f32; 3]) {
        let np = normal3(rng, self.position_noise_m);
        let nv = normal3(rng, self.velocity_noise_mps);
        (
            to_f32(zip3(truth.position_ned_m, np, |a, n| a + n)),
            to_f32(zip3(truth.velocity_ned_mps, nv, |a, n| a + n)),
        )
    }
}
