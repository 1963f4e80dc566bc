//! How to fuse: measurement models, innovation gates and sequential scalar Kalman updates.
//! Each public `fuse_*` either applies the whole measurement or none of it, and reports
//! which as a [`Fusion`] outcome.

mod baro;
mod gps;
mod mag;
mod still;

use super::{Filter, STATES, covariance};
use crate::estimation::Error;

/// Smallest variance any state may keep after an update.
const VARIANCE_FLOOR: f32 = 1e-12;

/// What happened to one measurement.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Fusion {
    /// Applied. `test_ratio` is the largest ν²/(gate²·S) among its rows (≤ 1, except for
    /// an ungated pseudo-measurement).
    Fused {
        /// Largest normalised innovation test ratio.
        test_ratio: f32,
    },
    /// Beyond the innovation gate (`test_ratio` > 1): the estimate was left untouched.
    Rejected {
        /// Largest normalised innovation test ratio.
        test_ratio: f32,
    },
}

impl Fusion {
    /// True when the measurement was applied.
    #[must_use]
    pub fn is_fused(&self) -> bool {
        matches!(self, Self::Fused { .. })
    }

    fn from_ratio(test_ratio: f32) -> Self {
        // A NaN ratio (cannot happen with finite inputs) is a rejection too.
        if test_ratio <= 1.0 {
            Self::Fused { test_ratio }
        } else {
            Self::Rejected { test_ratio }
        }
    }
}

impl Filter {
    /// ν²/(gate²·S), the normalised innovation test (PX4's "test ratio").
    fn test_ratio(&self, innovation: f32, innovation_var: f32) -> f32 {
        let gate = self.config.gate_sigma;
        innovation * innovation / (gate * gate * innovation_var)
    }

    /// Gate test of a direct observation of state `k` (H = e_k) with variance `r`.
    fn direct_test(&self, k: usize, measured: f32, r: f32) -> f32 {
        let predicted = self.x.get(k).copied().unwrap_or(0.0);
        let var = self
            .p
            .get(k)
            .and_then(|row| row.get(k))
            .copied()
            .unwrap_or(0.0)
            + r;
        self.test_ratio(measured - predicted, var)
    }

    /// Scalar update for a direct observation of state `k`; the innovation is recomputed
    /// from the current state, so earlier rows of the same measurement are accounted for.
    fn fuse_direct(&mut self, k: usize, measured: f32, r: f32) {
        let ph = covariance::column(&self.p, k);
        let predicted = self.x.get(k).copied().unwrap_or(0.0);
        let s = ph.get(k).copied().unwrap_or(0.0) + r;
        self.apply_update(&ph, s, measured - predicted);
    }

    /// x ← x + ph·ν/s, P ← P − ph·phᵀ/s, for ph = P·hᵀ and s = h·P·hᵀ + r.
    fn apply_update(&mut self, ph: &[f32; STATES], s: f32, innovation: f32) {
        if s.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
            return;
        }
        let inv_s = 1.0 / s;
        let gain = innovation * inv_s;
        for (x, &ph_i) in self.x.iter_mut().zip(ph.iter()) {
            *x += ph_i * gain;
        }
        covariance::subtract_outer(&mut self.p, ph, s);
        covariance::floor_diagonal(&mut self.p, VARIANCE_FLOOR);
    }

    /// Bias limits, quaternion norm and a finiteness check after any update.
    fn finish_update(&mut self) -> Result<(), Error> {
        self.limit_biases();
        self.renormalize();
        if self.is_finite() {
            Ok(())
        } else {
            Err(Error::Diverged)
        }
    }
}
