//! How to fuse: measurement models, innovation gates and sequential scalar Kalman updates.
//! Each public `fuse_*` either applies the whole measurement or none of it, and reports
//! which as a [`Fusion`] outcome.

mod baro;
mod gps;
mod mag;
mod still;

use super::{Filter, STATES, covariance};
use crate::Error;

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

    /// One scalar row of a measurement whose rows are fused one after the other:
    /// `ph_prior` is P·hᵀ of the covariance before the measurement, `earlier` the u vectors
    /// of the rows already fused, `h_dot` applies h to a vector. P·hᵀ after the earlier rows
    /// is P_prior·hᵀ − Σ u_l·(h·u_l) (each row subtracted u_l·u_lᵀ from P), so P itself is
    /// only updated once, for all rows ([`covariance::subtract_outers`]). Applies
    /// x ← x + P·hᵀ·ν/s now (`innovation` = ν, taken from the state after the earlier rows)
    /// and returns u = P·hᵀ/√s for the covariance pass (zeros if s is not positive: the
    /// row is skipped).
    fn sequential_row(
        &mut self,
        earlier: &[[f32; STATES]],
        ph_prior: [f32; STATES],
        h_dot: impl Fn(&[f32; STATES]) -> f32,
        r: f32,
        innovation: f32,
    ) -> [f32; STATES] {
        let mut ph = ph_prior;
        for u in earlier {
            let c = h_dot(u);
            for (a, b) in ph.iter_mut().zip(u.iter()) {
                *a -= c * b;
            }
        }
        let s = h_dot(&ph) + r;
        if s.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
            return [0.0; STATES];
        }
        let inv_sqrt_s = crate::math::inv_sqrt(s);
        let u = ph.map(|v| v * inv_sqrt_s);
        let gain = innovation * inv_sqrt_s;
        for (x, &u_i) in self.x.iter_mut().zip(u.iter()) {
            *x += u_i * gain;
        }
        u
    }

    /// Direct observations of the states `rows[..].0` with variances `rows[..].1` and
    /// measured values `measured`, fused one after the other (each innovation from the state
    /// after the earlier rows), the covariance updated once.
    fn fuse_direct<const K: usize>(&mut self, rows: [(usize, f32); K], measured: [f32; K]) {
        let mut u = [[0.0_f32; STATES]; covariance::ROWS];
        for (n, (&(k, r), &z)) in rows.iter().zip(measured.iter()).enumerate() {
            let ph = covariance::column(&self.p, k);
            let predicted = self.x.get(k).copied().unwrap_or(0.0);
            let (earlier, rest) = u.split_at_mut(n);
            if let Some(slot) = rest.first_mut() {
                *slot = self.sequential_row(
                    earlier,
                    ph,
                    |v| v.get(k).copied().unwrap_or(0.0),
                    r,
                    z - predicted,
                );
            }
        }
        self.subtract_outers(&u);
    }

    /// P ← P − Σ u·uᵀ, then the variance floor.
    fn subtract_outers(&mut self, u: &[[f32; STATES]; covariance::ROWS]) {
        covariance::subtract_outers(&mut self.p, u);
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
