//! Closed-loop step experiments on the per-axis plant: LQG (RTKF + LQR) against the
//! autotuned PID, and the step metrics the tests and the `lqg step` command report.

use crate::axis::{AxisPlant, AxisPlantConfig};
use flight_core::control::design::{self, DesignError, KfNoise, LqrCosts};
use flight_core::control::lqr::{AxisSetpoint, LqgAxis};
use flight_core::control::pid::{AttitudePid, Pid};
use flight_core::model::AxisModel;
use flight_core::sysid::autotune::{AutotuneSettings, analytic_pid};
use serde::Serialize;

/// Which loop the step is applied to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Rate step, deg/s.
    Rate,
    /// Angle step, deg.
    Attitude,
}

/// A controller for one axis of the simulation.
pub trait AxisController {
    /// One loop from the gyro (deg/s) and the attitude estimate (deg); returns the output.
    fn update(&mut self, gyro_dps: f32, angle_deg: f32, mode: Mode, setpoint: f32) -> f32;
    /// What the mixer realised of the last output (default: ignored).
    fn realised(&mut self, _output: f32) {}
}

impl AxisController for LqgAxis {
    fn update(&mut self, gyro_dps: f32, angle_deg: f32, mode: Mode, setpoint: f32) -> f32 {
        let sp = match mode {
            Mode::Rate => AxisSetpoint::Rate { rate_dps: setpoint },
            Mode::Attitude => AxisSetpoint::Attitude {
                angle_error_deg: setpoint - angle_deg,
            },
        };
        LqgAxis::update(self, gyro_dps, sp)
    }

    fn realised(&mut self, output: f32) {
        self.set_realised_output(output);
    }
}

/// The PID baseline: rate PID, and the outer attitude loop around it.
#[derive(Debug, Clone, Copy)]
pub struct PidAxis {
    /// Rate loop.
    pub rate: Pid,
    /// Attitude loop (holds its own copy of the rate loop).
    pub attitude: AttitudePid,
}

impl AxisController for PidAxis {
    fn update(&mut self, gyro_dps: f32, angle_deg: f32, mode: Mode, setpoint: f32) -> f32 {
        match mode {
            Mode::Rate => self.rate.update(setpoint, gyro_dps),
            Mode::Attitude => self.attitude.update(setpoint - angle_deg, gyro_dps),
        }
    }
}

/// LQG for `model` with the given costs and noise, told about `output_delay` samples of
/// output latency.
pub fn lqg_axis(
    model: &AxisModel,
    ts_s: f64,
    costs: &LqrCosts,
    noise: &KfNoise,
    output_delay: u8,
) -> Result<LqgAxis, DesignError> {
    let d = design::design_axis(model, ts_s, costs, costs, noise)?;
    #[allow(clippy::cast_possible_truncation)]
    Ok(LqgAxis::new(model, ts_s as f32, &d, 0.3).with_output_delay(output_delay))
}

/// The analytic-autotune PID for `model` (TL defaults ζ 1.1, ghf 0.01), rate-setpoint limit
/// 1000 deg/s.
pub fn autotuned_pid(
    model: &AxisModel,
    ts_s: f64,
) -> Result<PidAxis, flight_core::model::ModelError> {
    let lb = model.ln_beta1;
    let tune = analytic_pid([lb, lb, lb], model.tau_s, &AutotuneSettings::default())?;
    #[allow(clippy::cast_possible_truncation)]
    let ts = ts_s as f32;
    let rate = Pid::new(tune.rate[0], ts);
    Ok(PidAxis {
        rate,
        attitude: AttitudePid::new(tune.outer_kp, 0.0, 1000.0, rate, ts),
    })
}

/// A recorded step response.
#[derive(Debug, Clone, Serialize)]
pub struct StepResponse {
    /// Loop period, s.
    pub ts_s: f64,
    /// Step size (deg/s or deg).
    pub step: f64,
    /// The true response (rate or angle) each sample.
    pub response: Vec<f64>,
    /// The controller output each sample.
    pub output: Vec<f64>,
}

/// Step metrics.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StepMetrics {
    /// 10–90 % rise time, s.
    pub rise_time_s: f64,
    /// Overshoot beyond the step, % of the step (≥ 0).
    pub overshoot_pct: f64,
    /// Time after which the response stays within ±`band_pct` of the step, s.
    pub settling_time_s: f64,
    /// Settling band used, %.
    pub band_pct: f64,
    /// Mean error over the last 20 % of the run, % of the step.
    pub final_error_pct: f64,
}

/// Runs a step of size `step` in `mode` for `duration_s`.
pub fn run_step<C: AxisController>(
    cfg: &AxisPlantConfig,
    ctrl: &mut C,
    mode: Mode,
    step: f32,
    duration_s: f64,
) -> StepResponse {
    let mut plant = AxisPlant::new(*cfg);
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let n = (duration_s / cfg.ts_s).round() as usize;
    let mut response = Vec::with_capacity(n);
    let mut output = Vec::with_capacity(n);
    let mut gyro = plant.gyro();
    for _ in 0..n {
        #[allow(clippy::cast_possible_truncation)]
        let angle = plant.truth().angle_deg as f32;
        let u = ctrl.update(gyro, angle, mode, step);
        gyro = plant.step(u);
        let t = plant.truth();
        response.push(match mode {
            Mode::Rate => t.rate_dps,
            Mode::Attitude => t.angle_deg,
        });
        output.push(f64::from(u));
    }
    StepResponse {
        ts_s: cfg.ts_s,
        step: f64::from(step),
        response,
        output,
    }
}

/// The ensemble of a step experiment over noise seeds.
#[derive(Debug, Clone)]
pub struct Ensemble {
    /// The mean response: the expected response (see [`ensemble`]).
    pub mean: StepResponse,
    /// RMS deviation of the single runs from the mean over the second half of the run: the
    /// noise-driven wander while holding the setpoint (deg/s or deg).
    pub wander_rms: f64,
}

/// Runs `pairs` antithetic seed pairs (seed s with its noise, and with the same noise
/// negated) and averages them.
///
/// Why antithetic: with independent seeds the mean of N noisy runs still wanders by
/// σ/√N around the expected response, and its peak reads as overshoot (0.03–0.1 % on a
/// 10° attitude step at 3 deg/s noise and 32 seeds) for any controller that reaches the
/// setpoint within the run. For the linear closed loop the mean of a run and its twin is
/// exactly the noise-free response, so the metrics of the mean are the controller's own;
/// the noise is measured separately as `wander_rms`.
pub fn ensemble<C: AxisController>(
    cfg: &AxisPlantConfig,
    make: impl Fn() -> C,
    mode: Mode,
    step: f32,
    duration_s: f64,
    pairs: u64,
) -> Ensemble {
    let runs: Vec<StepResponse> = (1..=pairs.max(1))
        .flat_map(|seed| [false, true].map(|antithetic| (seed, antithetic)))
        .map(|(seed, antithetic)| {
            let c = AxisPlantConfig {
                seed,
                antithetic,
                ..*cfg
            };
            run_step(&c, &mut make(), mode, step, duration_s)
        })
        .collect();
    #[allow(clippy::cast_precision_loss)]
    let count = runs.len() as f64;
    let n = runs.first().map_or(0, |r| r.response.len());
    let mean_of = |pick: fn(&StepResponse) -> &Vec<f64>| -> Vec<f64> {
        (0..n)
            .map(|i| {
                runs.iter()
                    .map(|r| pick(r).get(i).copied().unwrap_or(0.0))
                    .sum::<f64>()
                    / count
            })
            .collect()
    };
    let mean = StepResponse {
        ts_s: cfg.ts_s,
        step: f64::from(step),
        response: mean_of(|r| &r.response),
        output: mean_of(|r| &r.output),
    };
    let (mut sum, mut samples) = (0.0, 0.0);
    for r in &runs {
        for (y, m) in r.response.iter().zip(&mean.response).skip(n / 2) {
            sum += (y - m) * (y - m);
            samples += 1.0;
        }
    }
    Ensemble {
        mean,
        wander_rms: (sum / f64::max(samples, 1.0)).sqrt(),
    }
}

impl StepResponse {
    /// Rise, overshoot, settling (band in % of the step) and final error. With gyro noise,
    /// average responses over seeds first: one noisy run wanders around the setpoint.
    pub fn metrics(&self, band_pct: f64) -> StepMetrics {
        let s = self.step;
        let y = &self.response;
        let time = |i: usize| {
            #[allow(clippy::cast_precision_loss)]
            let t = (i + 1) as f64 * self.ts_s;
            t
        };
        let first = |frac: f64| {
            y.iter()
                .position(|v| v / s >= frac)
                .map_or(f64::INFINITY, time)
        };
        let peak = y.iter().fold(f64::MIN, |m, v| m.max(v / s));
        let band = band_pct / 100.0;
        let settle = y
            .iter()
            .rposition(|v| (v / s - 1.0).abs() > band)
            .map_or(0.0, time);
        let tail = y.get(y.len() * 4 / 5..).unwrap_or(&[]);
        #[allow(clippy::cast_precision_loss)]
        let final_err = tail.iter().map(|v| v / s - 1.0).sum::<f64>() / tail.len().max(1) as f64;
        StepMetrics {
            rise_time_s: first(0.9) - first(0.1),
            overshoot_pct: ((peak - 1.0) * 100.0).max(0.0),
            settling_time_s: settle,
            band_pct,
            final_error_pct: final_err * 100.0,
        }
    }
}
