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
    /// The rate and attitude laws with the look-ahead folded in ([`FoldedLaw`]).
    laws: [FoldedLaw; 2],
    /// Recent outputs, newest first: the RTKF predicts with the one that acted on the frame.
    outputs: [f32; 4],
    output_delay_samples: usize,
    ts_s: f32,
}

#[allow(clippy::cast_possible_truncation)] // f64 design → f32 flight gains, intended
fn to_f32<const N: usize>(v: [f64; N]) -> [f32; N] {
    v.map(|x| x as f32)
}

/// One LQR law with the certainty-equivalent look-ahead past the pending outputs folded in
/// at design time. The look-ahead (predict the estimate once per output still in flight,
/// sum the rotation they cause) and the law are linear in the estimate (ω̂, ν̂, b̂) and the
/// pending outputs, so per loop the law is one dot product:
/// u = k·s + c_ω·ω̂ + c_ν·ν̂ + c_b·b̂ + Σ c_i·u_i, with s the rate setpoint or the angle
/// error and u_i the pending outputs (newest first, 0 beyond the delay).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct FoldedLaw {
    setpoint: f32,
    rate: f32,
    torque: f32,
    bias: f32,
    pending: [f32; 3],
}

impl FoldedLaw {
    /// The rate law (`attitude` false: u = k_ω·(ω_sp − ω̂ₐ) − k_ν·ν̂ₐ + b̂) or the attitude law
    /// (u = k_θ·(θ_err − Σ Ts·ω̂ⱼ) − k_ω·ω̂ₐ − k_ν·ν̂ₐ + b̂), ω̂ₐ and ν̂ₐ predicted `delay` periods
    /// ahead under the pending outputs. Folded in f64 from the flight (f32) values.
    #[allow(clippy::cast_possible_truncation)] // f64 folding → f32 flight coefficients
    #[inline] // run-once: compiled where the controllers are built (see `LqgAxis::new`)
    fn new(gains: &[f32], m: &EstimatorMatrices<f32>, ts_s: f32, delay: usize) -> Self {
        let f = f64::from;
        let (a, e, b_rate, b_torque) = (f(m.a_rate_torque), f(m.e), f(m.b_rate), f(m.b_torque));
        // Coefficient vectors over (ω̂, ν̂, d₀, d₁, d₂), dᵢ = uᵢ − b̂ the pending drives.
        let mut rate = [1.0, 0.0, 0.0, 0.0, 0.0];
        let mut torque = [0.0, 1.0, 0.0, 0.0, 0.0];
        let mut angle = [0.0_f64; 5];
        // Oldest pending output first, as the loop predicts.
        for i in (0..delay.min(3)).rev() {
            for (g, r) in angle.iter_mut().zip(rate) {
                *g += f(ts_s) * r;
            }
            let mut next_rate = [0.0; 5];
            let mut next_torque = [0.0; 5];
            for (((nr, nt), r), t) in next_rate
                .iter_mut()
                .zip(next_torque.iter_mut())
                .zip(rate)
                .zip(torque)
            {
                *nr = r + a * t;
                *nt = e * t;
            }
            if let (Some(nr), Some(nt)) = (next_rate.get_mut(2 + i), next_torque.get_mut(2 + i)) {
                *nr += b_rate;
                *nt += b_torque;
            }
            rate = next_rate;
            torque = next_torque;
        }
        // u = k·s − k_θ·angle − k_ω·ω̂ₐ − k_ν·ν̂ₐ + b̂ (k_θ·angle absent in the rate law).
        let (k, k_angle, k_rate, k_torque) = match *gains {
            [kw, kn] => (f(kw), 0.0, f(kw), f(kn)),
            [ka, kw, kn] => (f(ka), f(ka), f(kw), f(kn)),
            _ => (0.0, 0.0, 0.0, 0.0),
        };
        let mut c = [0.0_f64; 5];
        for (((c, g), r), t) in c.iter_mut().zip(angle).zip(rate).zip(torque) {
            *c = -(k_angle * g + k_rate * r + k_torque * t);
        }
        let [c_rate, c_torque, d0, d1, d2] = c;
        // Σ cᵢ·(uᵢ − b̂) + b̂ = Σ cᵢ·uᵢ + (1 − Σ cᵢ)·b̂.
        Self {
            setpoint: k as f32,
            rate: c_rate as f32,
            torque: c_torque as f32,
            bias: (1.0 - d0 - d1 - d2) as f32,
            pending: [d0 as f32, d1 as f32, d2 as f32],
        }
    }

    /// u for setpoint (or angle error) `s`, estimate `x` and the outputs newest first.
    #[inline(always)]
    fn apply(&self, s: f32, x: RateTorqueEstimate, outputs: [f32; 4]) -> f32 {
        let [p0, p1, p2] = self.pending;
        let [o0, o1, o2, _] = outputs;
        self.setpoint * s
            + self.rate * x.rate_dps
            + self.torque * x.torque
            + self.bias * x.bias
            + p0 * o0
            + p1 * o1
            + p2 * o2
    }
}

impl LqgAxis {
    /// Builds the controller from an f64 design for `model` at loop period `ts_s`.
    ///
    /// Run once per design, never in the loop: `#[inline]` (like the folding and
    /// [`Self::with_output_delay`]) so it is compiled in the crate that builds the
    /// controllers, built for size (`flight-app`), not in this one, built for speed.
    #[inline]
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
        let mut axis = Self {
            kf,
            gains,
            laws: [FoldedLaw::default(); 2],
            outputs: [0.0; 4],
            output_delay_samples: 0,
            ts_s,
        };
        axis.fold_laws();
        axis
    }

    /// Folds the gains and the look-ahead for the current delay into the per-loop laws.
    #[inline]
    fn fold_laws(&mut self) {
        let m = self.kf.model();
        let d = self.output_delay_samples;
        self.laws = [
            FoldedLaw::new(&self.gains.rate, m, self.ts_s, d),
            FoldedLaw::new(&self.gains.attitude, m, self.ts_s, d),
        ];
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
    #[inline]
    pub fn with_output_delay(mut self, samples: u8) -> Self {
        self.output_delay_samples = usize::from(samples.min(3));
        self.fold_laws();
        self
    }

    /// Replaces the output the last [`Self::update`] returned with what the mixer realised
    /// of it (`Mixer::mix_with_applied`), so the RTKF predicts with the torque really
    /// commanded. Without it, whenever the mixer scales the attitude demand down (gyro
    /// noise through a yaw axis with little authority, plus a roll step) the filter
    /// over-predicts the response: on the 6-DoF quad at 3 deg/s noise that cost 0.3–0.5 %
    /// attitude overshoot and a 35 ms instead of 24 ms rate rise.
    pub fn set_realised_output(&mut self, realised: f32) {
        // `realised.clamp(-1.0, 1.0)` unless NaN (ignored); within ±1 (always, unless the
        // caller passes something else than the mixer's result) in one compare.
        let clamped = if realised.abs() <= 1.0 {
            realised
        } else if realised > 1.0 {
            1.0
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
    /// the LQR law (the look-ahead past pending outputs folded in, `FoldedLaw`); returns
    /// the output clamped to ±1.
    pub fn update(&mut self, gyro_dps: f32, setpoint: AxisSetpoint) -> f32 {
        let applied = self
            .outputs
            .get(self.output_delay_samples)
            .copied()
            .unwrap_or(0.0);
        let x = self.kf.update(applied, gyro_dps);
        let [rate_law, attitude_law] = &self.laws;
        let outputs = self.outputs;
        let u = match setpoint {
            AxisSetpoint::Rate { rate_dps } => rate_law.apply(rate_dps, x, outputs),
            AxisSetpoint::Attitude { angle_error_deg } => {
                attitude_law.apply(angle_error_deg, x, outputs)
            }
            AxisSetpoint::Blend {
                rate_dps,
                angle_error_deg,
                attitude_weight,
            } => {
                let w = attitude_weight.clamp(0.0, 1.0);
                w * attitude_law.apply(angle_error_deg, x, outputs)
                    + (1.0 - w) * rate_law.apply(rate_dps, x, outputs)
            }
        };
        // NaN (never expected) clamps to NaN: fall back to 0 so the motors stay defined.
        // Unsaturated (the usual case) in one compare.
        let out = if u.abs() <= 1.0 {
            u
        } else if u > 1.0 {
            1.0
        } else if u < -1.0 {
            -1.0
        } else {
            0.0 // NaN fails every compare
        };
        // Shifted by hand: `rotate_right` is a `memmove` call for four floats.
        let [o0, o1, o2, _] = self.outputs;
        self.outputs = [out, o0, o1, o2];
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::design::{FrameInvariantCosts, KfNoise, design_axis};

    /// The law as it was before the folding: predict past each pending output (oldest
    /// first), sum the rotation, then the LQR law on the predicted state.
    fn unfolded(axis: &LqgAxis, x: RateTorqueEstimate, setpoint: AxisSetpoint) -> f32 {
        let mut x = x;
        let mut angle_ahead = 0.0;
        for u in axis.outputs.iter().take(axis.output_delay_samples).rev() {
            angle_ahead += axis.ts_s * x.rate_dps;
            x = axis.kf.predict_ahead(x, *u);
        }
        let [kw_r, kn_r] = axis.gains.rate;
        let [ka, kw_a, kn_a] = axis.gains.attitude;
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
        u.clamp(-1.0, 1.0)
    }

    #[test]
    fn the_folded_look_ahead_is_the_step_by_step_one() {
        let model = AxisModel::new(10.0, 0.03).unwrap();
        let c = FrameInvariantCosts::default().for_beta(model.beta1());
        let d = design_axis(&model, 0.001, &c, &c, &KfNoise::default()).unwrap();
        let setpoints = [
            AxisSetpoint::Rate { rate_dps: 40.0 },
            AxisSetpoint::Attitude {
                angle_error_deg: -3.0,
            },
            AxisSetpoint::Blend {
                rate_dps: -25.0,
                angle_error_deg: 2.0,
                attitude_weight: 0.4,
            },
        ];
        for delay in 0..=3 {
            let mut axis = LqgAxis::new(&model, 0.001, &d, 0.3).with_output_delay(delay);
            for k in 0..200 {
                let setpoint = setpoints[k % 3];
                let gyro = 30.0 * (k as f32 * 0.05).sin();
                // The filter update is the same code either way: compare the laws on the
                // estimate it returns.
                let mut reference = axis;
                let applied = reference.outputs[reference.output_delay_samples];
                let x = reference.kf.update(applied, gyro);
                let want = unfolded(&reference, x, setpoint);
                let got = axis.update(gyro, setpoint);
                assert!(
                    (got - want).abs() < 1e-5,
                    "delay {delay}, step {k}: {got} vs {want}"
                );
            }
        }
    }
}
