//! The rate/torque/bias Kalman filter ("RTKF", `control/LQG.md` §2), steady-state gain, f32.
//!
//! Per loop: predict with the output applied during the last period, x⁻ = A·x̂ + B·u_{k−1},
//! then correct with the new gyro sample, x̂ = x⁻ + L·(y_k − ω⁻) (the "current estimator",
//! dRonin's structure). The input-bias state b is the controller's integral action: the
//! plant is driven by (u − b), so adding b̂ to the output cancels a constant disturbance.

use crate::estimation::math::clamp_abs;
use crate::model::EstimatorMatrices;

/// One axis' estimate.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RateTorqueEstimate {
    /// Filtered rotation rate ω̂, deg/s.
    pub rate_dps: f32,
    /// Normalised torque ν̂ (actuator units).
    pub torque: f32,
    /// Input bias b̂ (actuator units).
    pub bias: f32,
}

/// Steady-state RTKF for one axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rtkf {
    model: EstimatorMatrices<f32>,
    gain: [f32; 3],
    bias_limit: f32,
    x: RateTorqueEstimate,
}

impl Rtkf {
    /// A filter with discretised `model`, filter gain L = (rate, torque, bias) from
    /// [`super::design::kalman_gain`] and a bias clamp (dRonin's BiasLimit, 0.3).
    pub fn new(model: EstimatorMatrices<f32>, gain: [f32; 3], bias_limit: f32) -> Self {
        Self {
            model,
            gain,
            bias_limit,
            x: RateTorqueEstimate::default(),
        }
    }

    /// Restarts at x̂ = (gyro, 0, 0) (dRonin's `lqg_set_x0`, on entering the mode).
    pub fn reset(&mut self, gyro_dps: f32) {
        self.x = RateTorqueEstimate {
            rate_dps: gyro_dps,
            torque: 0.0,
            bias: 0.0,
        };
    }

    /// The current estimate.
    pub fn estimate(&self) -> RateTorqueEstimate {
        self.x
    }

    /// The discretised model the filter predicts with.
    pub fn model(&self) -> &EstimatorMatrices<f32> {
        &self.model
    }

    /// `x` propagated one period ahead under output `u` (no measurement): used to look past
    /// outputs that are computed but not yet acting.
    pub fn predict_ahead(&self, x: RateTorqueEstimate, u: f32) -> RateTorqueEstimate {
        let m = &self.model;
        let drive = u - x.bias;
        RateTorqueEstimate {
            rate_dps: x.rate_dps + m.a_rate_torque * x.torque + m.b_rate * drive,
            torque: m.e * x.torque + m.b_torque * drive,
            bias: x.bias,
        }
    }

    /// One loop: predict with `previous_output` (clamped, as actually applied), correct with
    /// `gyro_dps`.
    #[inline]
    pub fn update(&mut self, previous_output: f32, gyro_dps: f32) -> RateTorqueEstimate {
        let m = &self.model;
        let RateTorqueEstimate {
            rate_dps,
            torque,
            bias,
        } = self.x;
        let drive = previous_output - bias;
        let rate_pred = rate_dps + m.a_rate_torque * torque + m.b_rate * drive;
        let torque_pred = m.e * torque + m.b_torque * drive;
        let innovation = gyro_dps - rate_pred;
        let [l_rate, l_torque, l_bias] = self.gain;
        self.x = RateTorqueEstimate {
            rate_dps: rate_pred + l_rate * innovation,
            torque: torque_pred + l_torque * innovation,
            bias: clamp_abs(bias + l_bias * innovation, self.bias_limit),
        };
        self.x
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::design::{KfNoise, kalman_gain};
    use crate::model::AxisModel;

    #[test]
    fn learns_a_constant_input_bias() {
        // Noise-free plant with a 0.1 bias on its input, exact ZOH at 1 kHz.
        let model = AxisModel::new(9.0, 0.03).unwrap();
        let ts = 0.001;
        let noise = KfNoise {
            q_bias: 1e-6,
            r_gyro: 25.0,
            ..KfNoise::default()
        };
        let (k, _) = kalman_gain(&model, ts, &noise).unwrap();
        let m = EstimatorMatrices::<f32>::new(&model, ts as f32);
        let mut kf = Rtkf::new(m, k.map(|v| v as f32), 0.3);
        let (mut w, mut nu) = (0.0f32, 0.0f32);
        let u = 0.05f32;
        // Plant driven by (u − 0.1): rate ramps down; the filter must explain it with b ≈ 0.1.
        for _ in 0..3000 {
            let drive = u - 0.1;
            w += m.a_rate_torque * nu + m.b_rate * drive;
            nu = m.e * nu + m.b_torque * drive;
            kf.update(u, w);
        }
        let est = kf.estimate();
        assert!((est.bias - 0.1).abs() < 0.005, "{est:?}");
        assert!((est.torque - (u - 0.1)).abs() < 0.005, "{est:?}");
        assert!((est.rate_dps - w).abs() < 0.01 * w.abs(), "{est:?} vs {w}");
    }
}
