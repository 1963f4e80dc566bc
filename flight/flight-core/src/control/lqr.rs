//! The LQG controller of one axis: RTKF estimate + LQR feedback with setpoint offsets
//! (`control/LQG.md` §3, the blog's "Setpoints" section).
//!
//! Rate mode: u = k_ω·(ω_sp − ω̂) − k_ν·ν̂ + b̂. Attitude mode: u = k_θ·θ_err − k_ω·ω̂ − k_ν·ν̂ + b̂
//! (θ_err = θ_sp − θ from the attitude estimator, yaw already wrapped to ±180°). The ν
//! setpoint is 0 and there is no feed-forward. A horizon-style blend mixes the two outputs.
//! The clamped output is what the RTKF is fed next loop, so saturation cannot wind it up.

use super::design::AxisDesign;
use super::rtkf::{RateTorqueEstimate, Rtkf};
use crate::model::{AxisModel, EstimatorMatrices};

/// What the pilot/outer loop asks this axis for.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AxisSetpoint {
    /// Hold a rotation rate, deg/s.
    Rate {
        /// Desired rate, deg/s.
        rate_dps: f32,
    },
    /// Hold an angle: the current error θ_sp − θ in degrees.
    Attitude {
        /// Angle error, deg.
        angle_error_deg: f32,
    },
    /// Horizon-style: `attitude_weight`·attitude + (1 − weight)·rate, weight in [0, 1].
    Blend {
        /// Desired rate, deg/s (from the sticks).
        rate_dps: f32,
        /// Angle error, deg.
        angle_error_deg: f32,
        /// 1 = pure attitude, 0 = pure rate.
        attitude_weight: f32,
    },
}

/// Gains of one axis in flight precision.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LqrGains {
    /// Rate mode (k_ω, k_ν).
    pub rate: [f32; 2],
    /// Attitude mode (k_θ, k_ω, k_ν).
    pub attitude: [f32; 3],
}

/// One axis of the LQG controller.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LqgAxis {
    kf: Rtkf,
    gains: LqrGains,
    /// Recent outputs, newest first: the RTKF predicts with the one that acted on the frame.
    outputs: [f32; 4],
    output_delay_samples: usize,
    ts_s: f32,
}

#[allow(clippy::cast_possible_truncation)] // f64 design → f32 flight gains, intended
fn to_f32<const N: usize>(v: [f64; N]) -> [f32; N] {
    v.map(|x| x as f32)
}

impl LqgAxis {
    /// Builds the controller from an f64 design for `model` at loop period `ts_s`.
    pub fn new(model: &AxisModel, ts_s: f32, design: &AxisDesign, bias_limit: f32) -> Self {
        let kf = Rtkf::new(
            EstimatorMatrices::new(model, ts_s),
            to_f32(design.kalman),
            bias_limit,
        );
        let gains = LqrGains {
            rate: to_f32(design.rate),
            attitude: to_f32(design.attitude),
        };
        Self {
            kf,
            gains,
            outputs: [0.0; 4],
            output_delay_samples: 0,
            ts_s,
        }
    }

    /// Whole loop periods between computing an output and it acting on the airframe beyond
    /// the normal one-period hold (0–3; the ESC protocol and motor-update timing). The
    /// RTKF then predicts with the output that really drove the frame, so the latency does
    /// not leak into the bias estimate, and the LQR acts on the state predicted past the
    /// outputs still in flight (certainty-equivalent delay compensation): without it a
    /// one-sample delay leaves a lightly damped ≈ 60 Hz mode that gyro noise keeps ringing.
    ///
    /// [`Self::new`] starts at 0, the timing of a loop that writes the motors right after
    /// the gyro read, and does not guess: the delay is a property of the output path (ESC
    /// protocol, when the timer latches), so the caller states it (the flight pipeline's
    /// `ControlParams::output_delay_samples`). Matched, the expected step response is the
    /// latency-free one (tests/quad-sim, 1 kHz, 3 deg/s noise: no overshoot, same rise).
    /// Measured cost of a one-sample mismatch, 100 deg/s rate step, four frames across
    /// ln β 8–11 and τ 15–50 ms: told 0 with 1 present, 0.12–1.6 % overshoot (told 1 with 2
    /// present, up to 1.65 %); told 1 with 0 present, 0.003–0.36 % overshoot and a 2–4 ms
    /// slower rise. Attitude steps change by ≤ 0.002 %. So when the path's delay is
    /// uncertain, round it up.
    pub fn with_output_delay(mut self, samples: u8) -> Self {
        self.output_delay_samples = usize::from(samples.min(3));
        self
    }

    /// Replaces the output the last [`Self::update`] returned with what the mixer realised
    /// of it (`Mixer::mix_with_applied`), so the RTKF predicts with the torque really
    /// commanded. Without it, whenever the mixer scales the attitude demand down (gyro
    /// noise through a yaw axis with little authority, plus a roll step) the filter
    /// over-predicts the response: on the 6-DoF quad at 3 deg/s noise that cost 0.3–0.5 %
    /// attitude overshoot and a 35 ms instead of 24 ms rate rise.
    pub fn set_realised_output(&mut self, realised: f32) {
        // `realised.clamp(-1.0, 1.0)` unless NaN (ignored), in two compares.
        let clamped = if realised >= -1.0 {
            if realised > 1.0 { 1.0 } else { realised }
        } else if realised < -1.0 {
            -1.0
        } else {
            return;
        };
        let [_, o1, o2, o3] = self.outputs;
        self.outputs = [clamped, o1, o2, o3];
    }

    /// Restarts the estimator from a gyro sample (mode entry, arming).
    pub fn reset(&mut self, gyro_dps: f32) {
        self.kf.reset(gyro_dps);
        self.outputs = [0.0; 4];
    }

    /// The current estimate.
    pub fn estimate(&self) -> RateTorqueEstimate {
        self.kf.estimate()
    }

    /// One control loop: update the RTKF with the previous output and this gyro sample, then
    /// the LQR law; returns the output clamped to ±1.
    pub fn update(&mut self, gyro_dps: f32, setpoint: AxisSetpoint) -> f32 {
        let applied = self
            .outputs
            .get(self.output_delay_samples)
            .copied()
            .unwrap_or(0.0);
        let now = self.kf.update(applied, gyro_dps);
        // Look past the outputs computed but not yet acting, oldest first; the angle error
        // shrinks by the rotation they will still cause.
        let mut x = now;
        let mut angle_ahead = 0.0;
        if self.output_delay_samples == 1 {
            // The factory delay, straight-line: the same sums as the loop below.
            let [pending, ..] = self.outputs;
            angle_ahead += self.ts_s * x.rate_dps;
            x = self.kf.predict_ahead(x, pending);
        } else {
            // The delay is at most 3 of the 4 outputs kept; `take` needs no fallback.
            for u in self.outputs.iter().take(self.output_delay_samples).rev() {
                angle_ahead += self.ts_s * x.rate_dps;
                x = self.kf.predict_ahead(x, *u);
            }
        }
        let [kw_r, kn_r] = self.gains.rate;
        let [ka, kw_a, kn_a] = self.gains.attitude;
        let rate_law = |rate_dps: f32| kw_r * (rate_dps - x.rate_dps) - kn_r * x.torque;
        let attitude_law =
            |err: f32| ka * (err - angle_ahead) - kw_a * x.rate_dps - kn_a * x.torque;
        let u = match setpoint {
            AxisSetpoint::Rate { rate_dps } => rate_law(rate_dps),
            AxisSetpoint::Attitude { angle_error_deg } => attitude_law(angle_error_deg),
            AxisSetpoint::Blend {
                rate_dps,
                angle_error_deg,
                attitude_weight,
            } => {
                let w = attitude_weight.clamp(0.0, 1.0);
                w * attitude_law(angle_error_deg) + (1.0 - w) * rate_law(rate_dps)
            }
        } + x.bias;
        // NaN (never expected) clamps to NaN: fall back to 0 so the motors stay defined.
        let out = if u >= -1.0 {
            if u > 1.0 { 1.0 } else { u }
        } else if u < -1.0 {
            -1.0
        } else {
            0.0 // NaN fails both compares
        };
        // Shifted by hand: `rotate_right` is a `memmove` call for four floats.
        let [o0, o1, o2, _] = self.outputs;
        self.outputs = [out, o0, o1, o2];
        out
    }
}
