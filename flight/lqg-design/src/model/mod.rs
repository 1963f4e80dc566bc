//! The per-axis airframe model shared by the LQG controller, its gain design and the
//! identification EKF (`LQG.md` §1): θ' = ω, ω' = (β1 − β2)·ν + β2·u, ν' = (u − ν)/τ.
//!
//! β is stored as ln β everywhere (`LQG.md` §4), because identification works on ln β and
//! real frames span two decades of β; τ is stored in seconds (dRonin's convention).

pub mod discrete;

pub use discrete::{EstimatorMatrices, LqrMatrices, Phi};

use core::fmt;

/// Parameters of one rotation axis.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AxisModel {
    /// ln β1: lagged control authority, ln((deg/s²) per actuator unit).
    pub ln_beta1: f32,
    /// ln β2: lag-free authority (yaw reaction torque of spinning up props); `None` = 0.
    pub ln_beta2: Option<f32>,
    /// Motor/ESC/prop time constant τ in seconds.
    pub tau_s: f32,
}

/// Why an [`AxisModel`] or sample period was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ModelError {
    /// A parameter is NaN or infinite.
    NonFinite,
    /// ln β outside 0–20: no airframe has that authority, the value is garbage.
    LnBetaOutOfRange,
    /// τ outside 1 ms – 1 s (dRonin refuses τ ≤ 1 ms as well).
    TauOutOfRange,
    /// The loop period is not inside 10 µs – 100 ms.
    SamplePeriodOutOfRange,
}

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ModelError::NonFinite => "model parameter is not finite",
            ModelError::LnBetaOutOfRange => "ln beta outside 0..20",
            ModelError::TauOutOfRange => "tau outside 1 ms..1 s",
            ModelError::SamplePeriodOutOfRange => "sample period outside 10 us..100 ms",
        })
    }
}

impl core::error::Error for ModelError {}

fn check_ln_beta(v: f32) -> Result<(), ModelError> {
    if !v.is_finite() {
        Err(ModelError::NonFinite)
    } else if !(0.0..=20.0).contains(&v) {
        Err(ModelError::LnBetaOutOfRange)
    } else {
        Ok(())
    }
}

/// Checks a control-loop period in seconds.
pub fn check_sample_period(ts_s: f64) -> Result<(), ModelError> {
    if !ts_s.is_finite() {
        Err(ModelError::NonFinite)
    } else if !(1e-5..=0.1).contains(&ts_s) {
        Err(ModelError::SamplePeriodOutOfRange)
    } else {
        Ok(())
    }
}

impl AxisModel {
    /// A roll/pitch-style axis (β2 = 0).
    pub fn new(ln_beta1: f32, tau_s: f32) -> Result<Self, ModelError> {
        check_ln_beta(ln_beta1)?;
        if !tau_s.is_finite() {
            return Err(ModelError::NonFinite);
        }
        if !(0.001..=1.0).contains(&tau_s) {
            return Err(ModelError::TauOutOfRange);
        }
        Ok(Self {
            ln_beta1,
            ln_beta2: None,
            tau_s,
        })
    }

    /// The same axis with a lag-free (yaw-direct) authority ln β2.
    pub fn with_beta2(self, ln_beta2: f32) -> Result<Self, ModelError> {
        check_ln_beta(ln_beta2)?;
        Ok(Self {
            ln_beta2: Some(ln_beta2),
            ..self
        })
    }

    /// β1 in (deg/s²)/unit, f64 for the gain design.
    pub fn beta1(&self) -> f64 {
        discrete::Real::exp(f64::from(self.ln_beta1))
    }

    /// β2 in (deg/s²)/unit (0 when absent), f64 for the gain design.
    pub fn beta2(&self) -> f64 {
        self.ln_beta2
            .map_or(0.0, |l| discrete::Real::exp(f64::from(l)))
    }

    /// τ in seconds as f64.
    pub fn tau(&self) -> f64 {
        f64::from(self.tau_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation_rejects_garbage() {
        assert_eq!(AxisModel::new(f32::NAN, 0.03), Err(ModelError::NonFinite));
        assert_eq!(
            AxisModel::new(25.0, 0.03),
            Err(ModelError::LnBetaOutOfRange)
        );
        assert_eq!(AxisModel::new(10.0, 0.0005), Err(ModelError::TauOutOfRange));
        assert_eq!(
            check_sample_period(0.0),
            Err(ModelError::SamplePeriodOutOfRange)
        );
        let m = AxisModel::new(10.0, 0.03).unwrap().with_beta2(6.0).unwrap();
        assert!((m.beta1() - 22_026.465_794_806_718).abs() < 1e-6);
        assert!((m.beta2() - 403.428_793_492_735_1).abs() < 1e-9);
    }
}
