//! The filter's measurement and process noise derived from the sensors' own noise figures
//! (1σ white noise per sample), as DERIVATION.md §3–4 states them: a white noise of σ per
//! IMU sample at period dt is a power spectral density σ²·dt; a measurement's variance is
//! σ². Figures left `None` keep the configuration's value.

use super::Config;

/// 1σ white-noise figures of the sensors; `None` = not known, keep the tuning.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SensorNoise {
    /// Gyro noise per sample, each axis (rad/s).
    pub gyro_radps: Option<f32>,
    /// Accelerometer noise per sample, each axis (m/s²).
    pub accel_mps2: Option<f32>,
    /// Magnetometer noise per sample, each axis (the magnetometer's unit).
    pub mag: Option<f32>,
    /// Barometric altitude noise (m).
    pub baro_m: Option<f32>,
    /// GPS horizontal position noise, each axis (m).
    pub gps_position_m: Option<f32>,
    /// GPS vertical position noise (m).
    pub gps_altitude_m: Option<f32>,
    /// GPS velocity noise, each axis (m/s).
    pub gps_velocity_mps: Option<f32>,
}

impl Config {
    /// This tuning with the noise terms the given figures determine; `imu_period_s` is the
    /// IMU sample period the gyro and accelerometer figures refer to. Bias walks, initial
    /// uncertainty, gate and limits are kept: the figures say nothing about them.
    ///
    /// The magnetometer noise is isotropic, so rotating the reading into the heading frame
    /// (fusion/mag.rs) keeps σ² per component.
    #[must_use]
    pub fn with_sensor_noise(mut self, noise: &SensorNoise, imu_period_s: f32) -> Self {
        let sq = |s: f32| s * s;
        if let Some(g) = noise.gyro_radps {
            self.gyro_noise_psd = [sq(g) * imu_period_s; 3];
        }
        if let Some(a) = noise.accel_mps2 {
            self.accel_noise_psd = sq(a) * imu_period_s;
        }
        if let Some(m) = noise.mag {
            self.mag_var = sq(m);
        }
        if let Some(b) = noise.baro_m {
            self.baro_var_m2 = sq(b);
        }
        if let Some(p) = noise.gps_position_m {
            self.gps_horizontal_var_m2 = sq(p);
        }
        if let Some(h) = noise.gps_altitude_m {
            self.gps_vertical_var_m2 = sq(h);
        }
        if let Some(v) = noise.gps_velocity_mps {
            self.gps_velocity_var_m2ps2 = sq(v);
        }
        self
    }
}
