//! Identification experiment: three per-axis plants (roll, pitch, yaw; one shared τ) flown by
//! the autotuned PID (attitude on roll/pitch, rate on yaw, as Tau Labs' SYSTEMIDENT mode)
//! with the shake added to the outputs, and the flight-core identification EKF listening.

use crate::axis::{AxisPlant, AxisPlantConfig};
use crate::closed_loop::PidAxis;
use flight_core::control::pid::{AttitudePid, Pid};
use flight_core::model::{AxisModel, ModelError};
use flight_core::sysid::autotune::{AutotuneSettings, analytic_pid};
use flight_core::sysid::shake::Shake;
use flight_core::sysid::{Identification, SysidConfig, SystemIdentifier};
use serde::Serialize;

/// The simulated frame and the experiment.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SysidExperiment {
    /// True ln β (roll, pitch, yaw).
    pub ln_beta: [f32; 3],
    /// True τ, s.
    pub tau_s: f32,
    /// Loop period, s.
    pub ts_s: f64,
    /// Extra output delay of the plant (and what the EKF is told), samples.
    pub latency_samples: u8,
    /// Gyro noise σ, deg/s.
    pub gyro_noise_dps: f64,
    /// Shake duration, s.
    pub seconds: f64,
    /// Noise seed.
    pub seed: u64,
}

impl SysidExperiment {
    /// Roll/pitch ln β, yaw 2.5 lower, 1 kHz, one-sample latency, 5 deg/s noise, 60 s.
    pub fn new(ln_beta: f32, tau_s: f32) -> Self {
        Self {
            ln_beta: [ln_beta, ln_beta, ln_beta - 2.5],
            tau_s,
            ts_s: 0.001,
            latency_samples: 1,
            gyro_noise_dps: 5.0,
            seconds: 60.0,
            seed: 3,
        }
    }

    /// Runs the shake and returns the EKF's result; the EKF is told the true output delay.
    pub fn run(&self) -> Result<Identification, ModelError> {
        self.run_with_ekf_delay(self.latency_samples)
    }

    /// Runs the shake with the EKF told `ekf_delay_samples` of output delay (to show what a
    /// wrong pairing does).
    pub fn run_with_ekf_delay(&self, ekf_delay_samples: u8) -> Result<Identification, ModelError> {
        self.run_with_progress(ekf_delay_samples, |_| {})
    }

    /// [`Self::run_with_ekf_delay`], calling `progress` with the simulated seconds done after
    /// each one (for a host tool's progress bar).
    pub fn run_with_progress(
        &self,
        ekf_delay_samples: u8,
        mut progress: impl FnMut(u64),
    ) -> Result<Identification, ModelError> {
        #[allow(clippy::cast_possible_truncation)]
        let ts = self.ts_s as f32;
        // The frame's existing tune (here: the analytic PID of the true frame).
        let tune = analytic_pid(self.ln_beta, self.tau_s, &AutotuneSettings::default())?;
        let mut axes = Vec::with_capacity(3);
        for (i, (lb, gains)) in self.ln_beta.iter().zip(tune.rate).enumerate() {
            let model = AxisModel::new(*lb, self.tau_s)?;
            let plant = AxisPlant::new(AxisPlantConfig {
                model,
                ts_s: self.ts_s,
                latency_samples: usize::from(self.latency_samples),
                gyro_noise_dps: self.gyro_noise_dps,
                input_disturbance: 0.02,
                seed: self.seed.wrapping_mul(3).wrapping_add(i as u64),
                antithetic: false,
            });
            let rate = Pid::new(gains, ts);
            let pid = PidAxis {
                rate,
                attitude: AttitudePid::new(tune.outer_kp, 0.0, 1000.0, rate, ts),
            };
            // Roll and pitch fly attitude, yaw flies rate (Tau Labs' SYSTEMIDENT mode).
            axes.push((plant, pid, i == 2));
        }
        let mut cfg = SysidConfig::new(ts);
        cfg.output_delay_samples = ekf_delay_samples;
        // R = 10× the true gyro variance (SysidConfig::gyro_variance explains why).
        #[allow(clippy::cast_possible_truncation)]
        let variance = (10.0 * self.gyro_noise_dps * self.gyro_noise_dps).max(1.0) as f32;
        cfg.gyro_variance = variance;
        let mut ekf = SystemIdentifier::new(cfg);
        let mut shake = Shake::new(ts, 0.075);
        let mut gyro = [0.0f32; 3];
        for ((plant, _, _), g) in axes.iter_mut().zip(gyro.iter_mut()) {
            *g = plant.gyro();
        }
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let n = (self.seconds / self.ts_s).round() as usize;
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let per_second = ((1.0 / self.ts_s).round() as usize).max(1);
        for k in 0..n {
            if k > 0 && k % per_second == 0 {
                progress((k / per_second) as u64);
            }
            ekf.update(gyro);
            let offsets = shake.next(ekf.ln_beta());
            let mut out = [0.0f32; 3];
            for (((plant, pid, yaw), g), (o, offset)) in
                axes.iter_mut().zip(gyro).zip(out.iter_mut().zip(offsets))
            {
                #[allow(clippy::cast_possible_truncation)]
                let angle = plant.truth().angle_deg as f32;
                let u = if *yaw {
                    pid.rate.update(0.0, g)
                } else {
                    pid.attitude.update(-angle, g)
                };
                *o = (u + offset).clamp(-1.0, 1.0);
            }
            ekf.record_output(out);
            for ((plant, _, _), (g, o)) in axes.iter_mut().zip(gyro.iter_mut().zip(out)) {
                *g = plant.step(o);
            }
        }
        Ok(ekf.result())
    }
}
