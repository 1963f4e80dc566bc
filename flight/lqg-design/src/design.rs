//! LQG gain design for one axis, in f64 before take-off: the steady-state Kalman gain of the
//! rate/torque/bias estimator (RTKF) and the LQR gains for rate and attitude (`LQG.md`
//! §2–3).
//!
//! Costs are per sample with r = 1. The torque cost can be given frame-invariantly as
//! q3 = β1·q4 (the blog's "frame invariant" costs): a frame with twice the authority needs
//! twice the torque penalty for the same closed-loop shape.

use super::dare::{self, DareError, Square};
use crate::model::{AxisModel, EstimatorMatrices, LqrMatrices, ModelError, check_sample_period};
use core::fmt;

/// The torque (ν) cost: absolute, or scaled by β1.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TorqueCost {
    /// q3 used as given (Tau Labs' LQRSettings).
    Absolute(f64),
    /// q3 = β1·q4, frame-invariant.
    PerBeta(f64),
}

impl TorqueCost {
    /// The q3 that enters Q for a frame with authority `beta1`.
    pub fn q3(self, beta1: f64) -> f64 {
        match self {
            TorqueCost::Absolute(q) => q,
            TorqueCost::PerBeta(q4) => beta1 * q4,
        }
    }
}

/// LQR state costs, per sample, r = 1.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LqrCosts {
    /// Angle error cost, 1/deg² (attitude mode only).
    pub q_angle: f64,
    /// Rate error cost, 1/(deg/s)².
    pub q_rate: f64,
    /// Torque cost.
    pub q_torque: TorqueCost,
}

impl Default for LqrCosts {
    /// Tau Labs' LQRSettings attitude costs (4, 0.04, 10000), absolute.
    fn default() -> Self {
        Self {
            q_angle: 4.0,
            q_rate: 0.04,
            q_torque: TorqueCost::Absolute(10000.0),
        }
    }
}

/// Costs that give the same closed-loop shape on any β: q3 = β1·q4 (the blog's frame-
/// invariant torque cost) together with q_angle = q1/β1 and q_rate = q2/β1.
///
/// Why the rate and angle costs scale too: with ω = β·ω̃ the cost becomes
/// β·(q1·θ̃² + q2·ω̃² + q4·ν²) + u², whose minimiser does not depend on β once q4·β ≫ 1
/// (u² negligible). With q3 = β1·q4 alone and a fixed q_rate the rise time still falls as
/// β^(−1/2) (measured in tests/quad-sim/tests/control_closed_loop.rs).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FrameInvariantCosts {
    /// q1: angle cost × β1.
    pub q1_angle: f64,
    /// q2: rate cost × β1.
    pub q2_rate: f64,
    /// q4: torque cost / β1.
    pub q4_torque: f64,
}

impl Default for FrameInvariantCosts {
    /// Chosen in closed-loop simulation at 1 kHz (tests/quad-sim): rate rise ≈ 20 ms where
    /// the frame allows it, < 3 % overshoot, faster than the analytic PID on ln β 8–11,
    /// τ 15–50 ms. q1 gives a ≈ 0.2 s attitude rise; autotune matches it to the frame
    /// (`sysid::autotune::lqg_costs`).
    fn default() -> Self {
        Self {
            q1_angle: 1.0e5,
            q2_rate: 1000.0,
            q4_torque: 0.1,
        }
    }
}

impl FrameInvariantCosts {
    /// The absolute per-sample costs for a frame with authority `beta1`.
    pub fn for_beta(&self, beta1: f64) -> LqrCosts {
        LqrCosts {
            q_angle: self.q1_angle / beta1,
            q_rate: self.q2_rate / beta1,
            q_torque: TorqueCost::PerBeta(self.q4_torque),
        }
    }
}

/// RTKF noise, per sample: process (ω in (deg/s)², ν and bias in unit²) and gyro variance.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct KfNoise {
    /// Rate process noise Q1.
    pub q_rate: f64,
    /// Torque process noise Q2.
    pub q_torque: f64,
    /// Bias random-walk Q3.
    pub q_bias: f64,
    /// Gyro measurement variance R, (deg/s)².
    pub r_gyro: f64,
}

impl Default for KfNoise {
    /// Tau Labs' LQRSettings (`LQG.md` §2 table): Q = (1, 1e-5, 1e-7), R = 1000 for raw
    /// gyro.
    fn default() -> Self {
        Self {
            q_rate: 1.0,
            q_torque: 1e-5,
            q_bias: 1e-7,
            r_gyro: 1000.0,
        }
    }
}

/// Why the gain design failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DesignError {
    /// The model or sample period is invalid.
    Model(ModelError),
    /// A Riccati solve failed.
    Dare(DareError),
    /// A cost or noise value is negative or not finite.
    BadCost,
}

impl fmt::Display for DesignError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DesignError::Model(e) => write!(f, "model: {e}"),
            DesignError::Dare(e) => write!(f, "riccati: {e}"),
            DesignError::BadCost => f.write_str("cost or noise not finite and positive"),
        }
    }
}

impl core::error::Error for DesignError {}

impl From<ModelError> for DesignError {
    fn from(e: ModelError) -> Self {
        DesignError::Model(e)
    }
}

impl From<DareError> for DesignError {
    fn from(e: DareError) -> Self {
        DesignError::Dare(e)
    }
}

/// The f64 design result (also what the host `lqg gains` command prints).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisDesign {
    /// Filter gain L = P⁻c/(cᵀP⁻c + R) for (ω, ν, b).
    pub kalman: [f64; 3],
    /// Rate LQR gain (k_ω, k_ν) from the 2-state (ω, ν) model.
    pub rate: [f64; 2],
    /// Attitude LQR gain (k_θ, k_ω, k_ν) from the 3-state model.
    pub attitude: [f64; 3],
    /// Doubling steps of the three solves (kalman, rate, attitude).
    pub iterations: [u32; 3],
}

fn positive(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

/// Steady-state filter gain of the RTKF.
pub fn kalman_gain(
    model: &AxisModel,
    ts_s: f64,
    noise: &KfNoise,
) -> Result<([f64; 3], u32), DesignError> {
    check_sample_period(ts_s)?;
    if ![noise.q_rate, noise.q_torque, noise.q_bias, noise.r_gyro]
        .into_iter()
        .all(positive)
    {
        return Err(DesignError::BadCost);
    }
    let m = EstimatorMatrices::<f64>::new(model, ts_s);
    let a = Square::from_rows(3, &m.a());
    let q = Square::diagonal(3, &[noise.q_rate, noise.q_torque, noise.q_bias]);
    // Filter DARE = control DARE of the dual system (Aᵀ, cᵀ).
    let sol = dare::solve(&a.transpose(), &[1.0, 0.0, 0.0], &q, noise.r_gyro)?;
    // L = P⁻cᵀ/(cP⁻cᵀ + R): the first column of P⁻ over its first entry plus R.
    let pc = sol.x.column(0);
    let s = pc[0] + noise.r_gyro;
    Ok((pc.map(|v| v / s), sol.iterations))
}

/// Rate LQR gain (k_ω, k_ν) on the (ω, ν) sub-model.
pub fn rate_gain(
    model: &AxisModel,
    ts_s: f64,
    costs: &LqrCosts,
) -> Result<([f64; 2], u32), DesignError> {
    check_sample_period(ts_s)?;
    let q3 = costs.q_torque.q3(model.beta1());
    if !(positive(costs.q_rate) && positive(q3)) {
        return Err(DesignError::BadCost);
    }
    let m = LqrMatrices::<f64>::new(model, ts_s);
    let a = Square::from_rows(2, &[[1.0, m.a_rate_torque], [0.0, m.e]]);
    let [_, b1, b2] = m.b;
    let b = [b1, b2, 0.0];
    let q = Square::diagonal(2, &[costs.q_rate, q3]);
    let sol = dare::solve(&a, &b, &q, 1.0)?;
    let [k0, k1, _] = dare::lqr_gain(&a, &b, 1.0, &sol.x);
    Ok(([k0, k1], sol.iterations))
}

/// Attitude LQR gain (k_θ, k_ω, k_ν) on the (θ, ω, ν) model.
pub fn attitude_gain(
    model: &AxisModel,
    ts_s: f64,
    costs: &LqrCosts,
) -> Result<([f64; 3], u32), DesignError> {
    check_sample_period(ts_s)?;
    let q3 = costs.q_torque.q3(model.beta1());
    if ![costs.q_angle, costs.q_rate, q3].into_iter().all(positive) {
        return Err(DesignError::BadCost);
    }
    let m = LqrMatrices::<f64>::new(model, ts_s);
    let a = Square::from_rows(3, &m.a());
    let q = Square::diagonal(3, &[costs.q_angle, costs.q_rate, q3]);
    let sol = dare::solve(&a, &m.b, &q, 1.0)?;
    let k = dare::lqr_gain(&a, &m.b, 1.0, &sol.x);
    Ok((k, sol.iterations))
}

/// All three solves for one axis.
pub fn design_axis(
    model: &AxisModel,
    ts_s: f64,
    rate_costs: &LqrCosts,
    attitude_costs: &LqrCosts,
    noise: &KfNoise,
) -> Result<AxisDesign, DesignError> {
    let (kalman, ik) = kalman_gain(model, ts_s, noise)?;
    let (rate, ir) = rate_gain(model, ts_s, rate_costs)?;
    let (attitude, ia) = attitude_gain(model, ts_s, attitude_costs)?;
    Ok(AxisDesign {
        kalman,
        rate,
        attitude,
        iterations: [ik, ir, ia],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kalman_gain_has_expected_signs() {
        // Positive rate and torque gains, negative bias gain (a rate above the prediction
        // means more torque or less input bias); full agreement with scipy is tested in
        // tests/quad-sim/tests/control_reference_dare.rs.
        let m = AxisModel::new(10.0, 0.03).unwrap();
        let (k, it) = kalman_gain(
            &m,
            1.0 / 400.0,
            &KfNoise {
                q_torque: 1e-3,
                q_bias: 1e-5,
                ..KfNoise::default()
            },
        )
        .unwrap();
        assert!(it <= 30, "{it}");
        assert!(
            k[0] > 0.0 && k[0] < 1.0 && k[1] > 0.0 && k[2] < 0.0,
            "{k:?}"
        );
    }

    #[test]
    fn frame_invariant_cost_scales_with_beta() {
        assert_eq!(TorqueCost::PerBeta(0.5).q3(20000.0), 10000.0);
        assert_eq!(TorqueCost::Absolute(7.0).q3(20000.0), 7.0);
        let m = AxisModel::new(10.0, 0.03).unwrap();
        let bad = LqrCosts {
            q_rate: f64::NAN,
            ..LqrCosts::default()
        };
        assert_eq!(
            rate_gain(&m, 0.001, &bad).unwrap_err(),
            DesignError::BadCost
        );
        assert!(matches!(
            rate_gain(&m, 0.0, &LqrCosts::default()),
            Err(DesignError::Model(_))
        ));
    }
}
