//! The per-axis plant: θ' = ω, ω' = (β1 − β2)·ν + β2·(u − b), ν' = (u − b − ν)/τ, integrated
//! exactly (ZOH, f64) over each loop period, with output saturation at ±1, a configurable
//! whole-sample transport delay, an input disturbance b and Gaussian gyro noise.
//!
//! Timing: `step(u_k)` advances from the gyro sample k to sample k+1. With
//! `latency_samples = 0` the output computed from sample k acts during [t_k, t_k+1); every
//! extra latency sample shifts it one period later.

use flight_core::model::{AxisModel, LqrMatrices};
use sim_rng::{GOLDEN_GAMMA, SplitMix64};
use std::collections::VecDeque;

/// Plant configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisPlantConfig {
    /// The true airframe axis.
    pub model: AxisModel,
    /// Loop period, s.
    pub ts_s: f64,
    /// Whole loop periods of extra output delay.
    pub latency_samples: usize,
    /// Gyro noise σ, deg/s.
    pub gyro_noise_dps: f64,
    /// Constant input disturbance b (actuator units; e.g. an off-centre CG).
    pub input_disturbance: f64,
    /// Noise seed.
    pub seed: u64,
    /// Negate every noise sample of the seed (the antithetic twin run): for the linear
    /// closed loop the mean of a run and its twin is exactly the noise-free response.
    pub antithetic: bool,
}

impl AxisPlantConfig {
    /// One-sample latency, 3 deg/s gyro noise, no disturbance, 1 kHz.
    pub fn new(model: AxisModel) -> Self {
        Self {
            model,
            ts_s: 0.001,
            latency_samples: 1,
            gyro_noise_dps: 3.0,
            input_disturbance: 0.0,
            seed: 1,
            antithetic: false,
        }
    }
}

/// True state of the axis.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AxisTruth {
    /// Angle, deg.
    pub angle_deg: f64,
    /// Rate, deg/s.
    pub rate_dps: f64,
    /// Normalised torque ν.
    pub torque: f64,
    /// The (saturated, delayed) output that acted during the last period.
    pub applied_output: f64,
}

/// The per-axis plant.
#[derive(Debug, Clone)]
pub struct AxisPlant {
    cfg: AxisPlantConfig,
    m: LqrMatrices<f64>,
    truth: AxisTruth,
    queue: VecDeque<f64>,
    rng: SplitMix64,
}

impl AxisPlant {
    /// A plant at rest.
    pub fn new(cfg: AxisPlantConfig) -> Self {
        let queue = std::iter::repeat_n(0.0, cfg.latency_samples).collect();
        Self {
            m: LqrMatrices::new(&cfg.model, cfg.ts_s),
            truth: AxisTruth::default(),
            queue,
            rng: SplitMix64::new(cfg.seed ^ GOLDEN_GAMMA),
            cfg,
        }
    }

    /// The true state.
    pub fn truth(&self) -> AxisTruth {
        self.truth
    }

    /// A gyro sample of the current state.
    pub fn gyro(&mut self) -> f32 {
        let sign = if self.cfg.antithetic { -1.0 } else { 1.0 };
        let noise = sign * self.cfg.gyro_noise_dps * self.rng.gaussian();
        #[allow(clippy::cast_possible_truncation)]
        let g = (self.truth.rate_dps + noise) as f32;
        g
    }

    /// Applies output `u` (clamped to ±1) and advances one loop period; returns the next
    /// gyro sample.
    pub fn step(&mut self, u: f32) -> f32 {
        self.queue.push_back(f64::from(u).clamp(-1.0, 1.0));
        let applied = self.queue.pop_front().unwrap_or(0.0);
        let drive = applied - self.cfg.input_disturbance;
        let AxisTruth {
            angle_deg,
            rate_dps,
            torque,
            ..
        } = self.truth;
        let m = &self.m;
        let [b0, b1, b2] = m.b;
        self.truth = AxisTruth {
            angle_deg: angle_deg + m.ts * rate_dps + m.a_angle_torque * torque + b0 * drive,
            rate_dps: rate_dps + m.a_rate_torque * torque + b1 * drive,
            torque: m.e * torque + b2 * drive,
            applied_output: applied,
        };
        self.gyro()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latency_and_authority() {
        let model = AxisModel::new(10.0, 0.03).unwrap();
        let mut p = AxisPlant::new(AxisPlantConfig {
            gyro_noise_dps: 0.0,
            ..AxisPlantConfig::new(model)
        });
        p.step(0.5);
        assert_eq!(p.truth().rate_dps, 0.0); // one sample of latency
        for _ in 0..1000 {
            p.step(0.5);
        }
        // After 1 s of 0.5 (ν settled), ω ≈ β·0.5·(t − τ − latency).
        let expect = 22_026.47 * 0.5 * (1.0 - 0.03 - 0.001);
        assert!(
            (p.truth().rate_dps - expect).abs() < 0.01 * expect,
            "{:?}",
            p.truth()
        );
        // Saturation.
        let mut q = AxisPlant::new(AxisPlantConfig {
            latency_samples: 0,
            ..AxisPlantConfig::new(model)
        });
        q.step(5.0);
        assert_eq!(q.truth().applied_output, 1.0);
    }
}
