//! Autotune: analytic PID gains from the identified (β, τ) (`control/LQG.md` §6, the Tau Labs GCS
//! derivation) and the LQG models for the identified frame.
//!
//! The loop β/(s(τs + 1)) with C = kp + ki/s + kd·s/(τ_d·s + 1) has a 4th-order
//! characteristic polynomial, matched to (s² + 2ζωn·s + ωn²)(s + a)(s + b). ζ sets the
//! damping, ghf the high-frequency gain (noise) of the derivative path.

use super::ekf::Identification;
use crate::control::design::FrameInvariantCosts;
use crate::control::pid::PidGains;
use crate::model::{AxisModel, ModelError};

/// The designer's knobs (Tau Labs defaults).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AutotuneSettings {
    /// Closed-loop damping ζ (TL slider 110 → 1.10).
    pub damping: f64,
    /// High-frequency gain ghf (TL slider 10 → 0.010).
    pub noise_gain: f64,
    /// Ratio that places the real pole a (TL 20, dRonin 25).
    pub pole_ratio: f64,
    /// Outer attitude loop damping ζo (1.3).
    pub outer_damping: f64,
    /// dRonin's soft limit of the outer kp above 7: 3·ln(kp − 4) + 7 − 3·ln 3.
    pub soften_outer_kp: bool,
}

impl AutotuneSettings {
    /// dRonin's GCS defaults: ζ 1.05, ghf 0.010, N = 25, outer kp softened above 7.
    pub fn dronin() -> Self {
        Self {
            damping: 1.05,
            noise_gain: 0.010,
            pole_ratio: 25.0,
            outer_damping: 1.3,
            soften_outer_kp: true,
        }
    }
}

impl Default for AutotuneSettings {
    fn default() -> Self {
        Self {
            damping: 1.10,
            noise_gain: 0.010,
            pole_ratio: 20.0,
            outer_damping: 1.3,
            soften_outer_kp: false,
        }
    }
}

/// Analytic PID result for roll, pitch, yaw.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PidTune {
    /// Rate PID gains per axis (τ_d shared).
    pub rate: [PidGains; 3],
    /// Outer attitude kp, (deg/s)/deg.
    pub outer_kp: f32,
    /// Natural frequency ωn, rad/s.
    pub natural_frequency_rad_s: f64,
    /// Derivative filter τ_d, s.
    pub derivative_tau_s: f64,
}

const ITERATIONS: usize = 30;

#[allow(clippy::cast_possible_truncation)] // f64 design → f32 gains
fn gains_for(beta: f64, tau: f64, td: f64, wn: f64, z: f64, a: f64, b: f64) -> PidGains {
    let tt = tau * td;
    let ki = a * b * wn * wn * tt / beta;
    let kp = tt * ((a + b) * wn * wn + 2.0 * a * b * z * wn) / beta - ki * td;
    let kd = (tt * (a * b + wn * wn + 2.0 * z * wn * (a + b)) - 1.0) / beta - kp * td;
    PidGains::new(kp as f32, ki as f32, kd as f32, td as f32)
}

/// Analytic PID from ln β (roll, pitch, yaw) and the shared τ.
pub fn analytic_pid(
    ln_beta: [f32; 3],
    tau_s: f32,
    s: &AutotuneSettings,
) -> Result<PidTune, ModelError> {
    // Validate through the model type.
    let models = ln_beta.map(|lb| AxisModel::new(lb, tau_s));
    let [r, p, y] = models;
    let (r, p, y) = (r?, p?, y?);
    let tau = r.tau();
    let z = s.damping;
    let betas = [r.beta1(), p.beta1()];
    let mut wn = 1.0 / tau;
    let mut td = 0.0;
    for _ in 0..ITERATIONS {
        // The larger τ_d of roll and pitch (the weaker axis) is kept.
        td = betas
            .iter()
            .map(|beta| {
                (2.0 * z * tau * wn - 1.0)
                    / (4.0 * tau * z * z * wn * wn - 2.0 * z * wn - tau * wn * wn
                        + s.noise_gain * beta)
            })
            .fold(f64::MIN, f64::max);
        wn = (tau + td) / (tau * td) / (2.0 * z + 2.0);
    }
    let sum = (tau + td) / (tau * td) - 2.0 * z * wn;
    let a = sum / s.pole_ratio;
    let b = sum - a;
    if !(td.is_finite() && td > 0.0 && wn.is_finite() && wn > 0.0) {
        return Err(ModelError::NonFinite);
    }
    #[allow(clippy::cast_possible_truncation)]
    let mut outer_kp = wn / (4.0 * s.outer_damping * s.outer_damping);
    if s.soften_outer_kp && outer_kp > 7.0 {
        // Continuous at 7 (3·ln 3 + 7 − 3·ln 3) and growing only logarithmically above.
        outer_kp = 3.0 * libm::log(outer_kp - 4.0) + 7.0 - 3.0 * libm::log(3.0);
    }
    let outer_kp = outer_kp as f32;
    Ok(PidTune {
        rate: [r.beta1(), p.beta1(), y.beta1()].map(|beta| gains_for(beta, tau, td, wn, z, a, b)),
        outer_kp,
        natural_frequency_rad_s: wn,
        derivative_tau_s: td,
    })
}

/// The per-axis LQG models of an identified frame (roll, pitch, yaw; shared τ). Design gains
/// with [`crate::control::design::design_axis`] and frame-invariant costs (q3 = β1·q4).
pub fn lqg_models(id: &Identification) -> Result<[AxisModel; 3], ModelError> {
    let [r, p, y] = id.ln_beta.map(|lb| AxisModel::new(lb, id.tau_s));
    Ok([r?, p?, y?])
}

/// Attitude bandwidth of the LQG relative to the PID's outer loop: √(q1/q2) = 3·kp_outer
/// (chosen in closed-loop simulation: faster than the PID on ln β 8–11, τ 15–50 ms without
/// saturating the weakest frames).
const LQG_ATTITUDE_BANDWIDTH_RATIO: f64 = 3.0;

/// Rate bandwidth of the LQG relative to the PID design: √(q2/q4) = 2·ωn, with q4 kept in
/// [0.04, 0.3] (stiffer torque costs ring, softer ones are needlessly slow).
const LQG_RATE_BANDWIDTH_RATIO: f64 = 2.0;
const Q4_RANGE: (f64, f64) = (0.04, 0.3);

/// LQG costs for the identified frame: frame-invariant costs whose rate (q2/q4) and angle
/// (q1/q2) bandwidths are matched to what the frame (β, τ) supports, taken from the
/// analytic PID design (ωn and the outer kp).
pub fn lqg_costs(tune: &PidTune) -> FrameInvariantCosts {
    let base = FrameInvariantCosts::default();
    let w_rate = LQG_RATE_BANDWIDTH_RATIO * tune.natural_frequency_rad_s;
    let q4 = (base.q2_rate / (w_rate * w_rate)).clamp(Q4_RANGE.0, Q4_RANGE.1);
    let w = LQG_ATTITUDE_BANDWIDTH_RATIO * f64::from(tune.outer_kp);
    FrameInvariantCosts {
        q1_angle: base.q2_rate * w * w,
        q4_torque: q4,
        ..base
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_reference_example() {
        // `control/LQG.md` §6: ln β 10, τ 30 ms → ωn 49.3, τ_d 5.75 ms, kp 2.22e-3, ki 8.81e-3,
        // kd 4.84e-5, outer kp 7.30.
        let t = analytic_pid([10.0, 10.0, 10.0], 0.03, &AutotuneSettings::default()).unwrap();
        assert!((t.natural_frequency_rad_s - 49.3).abs() < 0.05, "{t:?}");
        assert!((t.derivative_tau_s - 5.75e-3).abs() < 0.005e-3);
        let g = t.rate[0];
        assert!((g.kp - 2.22e-3).abs() < 0.005e-3, "{g:?}");
        assert!((g.ki - 8.81e-3).abs() < 0.005e-3);
        assert!((g.kd - 4.84e-5).abs() < 0.005e-5);
        assert!((t.outer_kp - 7.30).abs() < 0.01);
        // dRonin: same formulas with ζ 1.05 and N 25; its outer kp 7.x is softened.
        let d = analytic_pid([10.0, 10.0, 10.0], 0.03, &AutotuneSettings::dronin()).unwrap();
        let raw = d.natural_frequency_rad_s / (4.0 * 1.3 * 1.3);
        assert!(raw > 7.0);
        let soft = 3.0 * libm::log(raw - 4.0) + 7.0 - 3.0 * libm::log(3.0);
        assert!((f64::from(d.outer_kp) - soft).abs() < 1e-5 && f64::from(d.outer_kp) < raw);
        assert!(d.natural_frequency_rad_s != t.natural_frequency_rad_s);
        assert!(analytic_pid([10.0, 10.0, 10.0], 0.0, &AutotuneSettings::default()).is_err());
    }
}
