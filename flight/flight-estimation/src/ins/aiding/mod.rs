//! When to fuse: the [`Ins`] owns a [`Filter`] and decides, per measurement source, what a
//! rejection means. A single rejection is just an outcome; a run of them means the estimate
//! (not the sensor) is wrong, and that part of the state is reset from the measurement —
//! PX4 EKF2's `*_control` logic, kept apart from the fusion maths as PX4 does.

pub mod gps;

use super::{Config, Filter, Fusion, State};
use crate::{Error, GRAVITY_MPS2, check_finite};

/// Policy of the aiding logic.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AidingConfig {
    /// Consecutive GPS position rejections before the position is reset to GPS.
    pub gps_position_resets_after: u16,
    /// Consecutive GPS velocity rejections before velocity (and tilt) are reset.
    pub gps_velocity_resets_after: u16,
    /// Consecutive baro rejections before the vertical position is reset to baro.
    pub baro_resets_after: u16,
    /// Consecutive magnetometer rejections before yaw is reset from the magnetometer.
    pub mag_resets_after: u16,
    /// Attitude standard deviation given after a tilt re-alignment (rad).
    pub tilt_reset_std_rad: f32,
    /// Yaw standard deviation given after a yaw reset (rad).
    pub yaw_reset_std_rad: f32,
    /// Time constant of the accelerometer low-pass used for tilt re-alignment (s).
    pub accel_filter_tau_s: f32,
    /// Seconds after the start, an alignment or an attitude reset during which the gyro
    /// bias walks at the configured (fast) rate; afterwards it walks at
    /// `settled_gyro_bias_walk_psd`. A fast walk lets a wrong bias be learnt quickly; once
    /// learnt, a slow walk keeps the bias (and so the heading) quiet — the C reference's
    /// walk is 1.5e-9 (rad/s)²/s, slow from the start, hence its slow convergence.
    pub gyro_bias_settle_s: f32,
    /// Gyro-bias walk PSD once settled ((rad/s)²/s); `None` keeps the configured one.
    pub settled_gyro_bias_walk_psd: Option<f32>,
}

impl Default for AidingConfig {
    fn default() -> Self {
        Self {
            gps_position_resets_after: 5,
            gps_velocity_resets_after: 5,
            baro_resets_after: 20,
            mag_resets_after: 20,
            tilt_reset_std_rad: 0.1,
            yaw_reset_std_rad: 0.1,
            accel_filter_tau_s: 0.5,
            gyro_bias_settle_s: 30.0,
            settled_gyro_bias_walk_psd: None,
        }
    }
}

impl AidingConfig {
    /// Gyro-bias walk once settled when the sensors' noise is known (see
    /// [`Self::for_known_noise`]), (rad/s)²/s: the bias may drift by 0.6 °/s per hour.
    pub const KNOWN_NOISE_SETTLED_GYRO_BIAS_WALK_PSD: f32 = 1e-10;
    /// Settling time used with known noise (s).
    pub const KNOWN_NOISE_GYRO_BIAS_SETTLE_S: f32 = 10.0;

    /// The policy for a filter told the sensors' true noise figures
    /// ([`super::Config::with_sensor_noise`]). The default tuning's fast gyro-bias walk also
    /// stands in for noise it does not model; with the true figures the model is right, so
    /// the fast walk is only needed while a wrong bias is being learnt — 10 s after the
    /// start, an alignment or an attitude reset — and the bias then walks slowly, which is
    /// what keeps heading and attitude quiet in the steady state (tests/ins-sim
    /// `ins_noise.rs`, README table).
    #[must_use]
    pub fn for_known_noise(self) -> Self {
        Self {
            gyro_bias_settle_s: Self::KNOWN_NOISE_GYRO_BIAS_SETTLE_S,
            settled_gyro_bias_walk_psd: Some(Self::KNOWN_NOISE_SETTLED_GYRO_BIAS_WALK_PSD),
            ..self
        }
    }
}

/// Outcome of offering one measurement to the [`Ins`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Aided {
    /// Fused normally.
    Fused(Fusion),
    /// Rejected by the gate; `consecutive` counts this source's rejections in a row.
    Rejected {
        /// The fusion outcome.
        fusion: Fusion,
        /// Rejections in a row, this one included.
        consecutive: u16,
    },
    /// Rejected too often in a row: the matching states were reset from this measurement.
    Reset(Fusion),
}

/// Per-source run of rejections.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Streak {
    rejections: u16,
}

impl Streak {
    /// Records `fusion`; true when `limit` consecutive rejections are reached (and restarts).
    fn record(&mut self, fusion: Fusion, limit: u16) -> Aided {
        if fusion.is_fused() {
            self.rejections = 0;
            return Aided::Fused(fusion);
        }
        self.rejections = self.rejections.saturating_add(1);
        if self.rejections >= limit {
            self.rejections = 0;
            Aided::Reset(fusion)
        } else {
            Aided::Rejected {
                fusion,
                consecutive: self.rejections,
            }
        }
    }
}

/// The INS: filter plus the when-to-fuse logic.
#[derive(Debug, Clone)]
pub struct Ins {
    filter: Filter,
    aiding: AidingConfig,
    accel_lowpass_mps2: [f32; 3],
    gps_position: Streak,
    gps_velocity: Streak,
    baro: Streak,
    mag: Streak,
    /// Time since the start or the last attitude reset (s), counted until settled.
    unsettled_s: f32,
    /// The slow gyro-bias walk is in use.
    settled: bool,
    /// The configured (fast) gyro-bias walk, restored after a reset.
    fast_gyro_bias_walk_psd: f32,
}

impl Ins {
    /// A new INS at the origin, level and facing north.
    #[must_use]
    pub fn new(config: Config, aiding: AidingConfig) -> Self {
        Self {
            filter: Filter::new(config),
            aiding,
            accel_lowpass_mps2: [0.0, 0.0, -GRAVITY_MPS2],
            gps_position: Streak::default(),
            gps_velocity: Streak::default(),
            baro: Streak::default(),
            mag: Streak::default(),
            unsettled_s: 0.0,
            settled: false,
            fast_gyro_bias_walk_psd: config.gyro_bias_walk_psd,
        }
    }

    /// The filter (read-only).
    #[must_use]
    pub fn filter(&self) -> &Filter {
        &self.filter
    }

    /// The filter, for direct use (initial state, resets).
    pub fn filter_mut(&mut self) -> &mut Filter {
        &mut self.filter
    }

    /// The current estimate.
    #[must_use]
    pub fn state(&self) -> State {
        self.filter.state()
    }

    /// Propagates by one IMU sample; see [`Filter::predict`].
    ///
    /// # Errors
    /// As [`Filter::predict`].
    pub fn predict(
        &mut self,
        gyro_radps: [f32; 3],
        accel_mps2: [f32; 3],
        dt_s: f32,
    ) -> Result<(), Error> {
        self.filter.predict(gyro_radps, accel_mps2, dt_s)?;
        if !self.settled {
            self.unsettled_s += dt_s;
            if let Some(settled) = self.aiding.settled_gyro_bias_walk_psd
                && self.unsettled_s >= self.aiding.gyro_bias_settle_s
            {
                self.filter.set_gyro_bias_walk_psd(settled);
                self.settled = true;
            }
        }
        let ratio = dt_s / self.aiding.accel_filter_tau_s;
        let alpha = if ratio < 1.0 { ratio } else { 1.0 };
        for (lp, a) in self.accel_lowpass_mps2.iter_mut().zip(accel_mps2) {
            *lp += alpha * (a - *lp);
        }
        Ok(())
    }

    /// Offers a GPS position (NED m); `vertical` selects whether its height is used.
    ///
    /// # Errors
    /// As [`Filter::fuse_gps_position`].
    pub fn gps_position(
        &mut self,
        position_ned_m: [f32; 3],
        vertical: bool,
    ) -> Result<Aided, Error> {
        let cfg = self.filter.config();
        let var = [cfg.gps_horizontal_var_m2, cfg.gps_vertical_var_m2];
        self.gps_position_with_variance(position_ned_m, vertical, var)
    }

    /// As [`Ins::gps_position`] with the measurement's own `[horizontal, vertical]`
    /// variances (m²).
    ///
    /// # Errors
    /// As [`Filter::fuse_gps_position_with_variance`].
    pub fn gps_position_with_variance(
        &mut self,
        position_ned_m: [f32; 3],
        vertical: bool,
        var_m2: [f32; 2],
    ) -> Result<Aided, Error> {
        let fusion =
            self.filter
                .fuse_gps_position_with_variance(position_ned_m, vertical, var_m2)?;
        let aided = self
            .gps_position
            .record(fusion, self.aiding.gps_position_resets_after);
        if let Aided::Reset(_) = aided {
            let [n, e, d] = position_ned_m;
            let [var, _] = var_m2;
            self.filter
                .reset_position([Some(n), Some(e), vertical.then_some(d)], var);
        }
        Ok(aided)
    }

    /// Offers a GPS velocity (NED m/s). A reset also re-aligns the tilt from the low-passed
    /// accelerometer when it reads about 1 g, since a wrong tilt is what makes the
    /// velocity run away (gravity leaks into the horizontal).
    ///
    /// # Errors
    /// As [`Filter::fuse_gps_velocity`].
    pub fn gps_velocity(&mut self, velocity_ned_mps: [f32; 3]) -> Result<Aided, Error> {
        let var = self.filter.config().gps_velocity_var_m2ps2;
        self.gps_velocity_with_variance(velocity_ned_mps, var)
    }

    /// As [`Ins::gps_velocity`] with the measurement's own variance per axis ((m/s)²).
    ///
    /// # Errors
    /// As [`Filter::fuse_gps_velocity_with_variance`].
    pub fn gps_velocity_with_variance(
        &mut self,
        velocity_ned_mps: [f32; 3],
        var: f32,
    ) -> Result<Aided, Error> {
        let fusion = self
            .filter
            .fuse_gps_velocity_with_variance(velocity_ned_mps, var)?;
        let aided = self
            .gps_velocity
            .record(fusion, self.aiding.gps_velocity_resets_after);
        if let Aided::Reset(_) = aided {
            self.filter.reset_velocity(velocity_ned_mps, var);
            let f = self.accel_lowpass_mps2;
            let norm = libm::sqrtf(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
            if (norm - GRAVITY_MPS2).abs() < 0.1 * GRAVITY_MPS2 {
                let tilt = self.aiding.tilt_reset_std_rad;
                let yaw = self.aiding.yaw_reset_std_rad;
                self.filter.reset_tilt_from_accel(f, tilt * tilt, yaw * yaw);
            }
            self.reopen_gyro_bias();
        }
        Ok(aided)
    }

    /// Offers a barometric altitude (m, up, same origin as the position).
    ///
    /// # Errors
    /// As [`Filter::fuse_baro`].
    pub fn baro(&mut self, altitude_m: f32) -> Result<Aided, Error> {
        let fusion = self.filter.fuse_baro(altitude_m)?;
        let aided = self.baro.record(fusion, self.aiding.baro_resets_after);
        if let Aided::Reset(_) = aided {
            let var = self.filter.config().baro_var_m2;
            self.filter
                .reset_position([None, None, Some(-altitude_m)], var);
        }
        Ok(aided)
    }

    /// Offers a magnetometer reading (body FRD, units of the configured earth field).
    ///
    /// # Errors
    /// As [`Filter::fuse_mag`].
    pub fn mag(&mut self, mag_body: [f32; 3]) -> Result<Aided, Error> {
        let fusion = self.filter.fuse_mag(mag_body)?;
        let aided = self.mag.record(fusion, self.aiding.mag_resets_after);
        if let Aided::Reset(_) = aided {
            let std = self.aiding.yaw_reset_std_rad;
            self.filter.reset_yaw_from_mag(mag_body, std * std);
            self.reopen_gyro_bias();
        }
        Ok(aided)
    }

    /// After an attitude-related reset, let the gyro bias move again (see
    /// [`Filter::inflate_gyro_bias_variance`]) up to its initial uncertainty.
    fn reopen_gyro_bias(&mut self) {
        let [_, _, _, gyro_bias_std, _] = self.filter.config().initial_std;
        self.filter
            .inflate_gyro_bias_variance(gyro_bias_std * gyro_bias_std);
        self.unsettle();
    }

    /// Back to the fast gyro-bias walk for another settling period.
    fn unsettle(&mut self) {
        self.unsettled_s = 0.0;
        self.settled = false;
        self.filter
            .set_gyro_bias_walk_psd(self.fast_gyro_bias_walk_psd);
    }

    /// Initial alignment from one accelerometer and magnetometer sample; see
    /// [`Filter::align`].
    ///
    /// # Errors
    /// [`Error::NonFinite`] for non-finite input.
    pub fn align(
        &mut self,
        accel_mps2: [f32; 3],
        mag_body: [f32; 3],
        position_ned_m: [f32; 3],
    ) -> Result<(), Error> {
        check_finite(&accel_mps2)?;
        let tilt = self.aiding.tilt_reset_std_rad;
        let yaw = self.aiding.yaw_reset_std_rad;
        self.filter
            .align(accel_mps2, mag_body, position_ned_m, tilt, yaw)?;
        self.accel_lowpass_mps2 = accel_mps2;
        self.unsettle();
        Ok(())
    }
}
