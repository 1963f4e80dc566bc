//! Discrete algebraic Riccati equation, single input, in f64, by the structure-preserving
//! doubling algorithm (SDA; `control/LQG.md` §7: ≤ 24 iterations, ≤ 3.5e-9 relative error over the
//! whole parameter grid, where f32 or absolute-tolerance iteration fail).
//!
//! Solves X = Aᵀ X A − Aᵀ X B (r + Bᵀ X B)⁻¹ Bᵀ X A + Q for the stabilising X ⪰ 0.
//! SDA: A₀ = A, G₀ = B r⁻¹ Bᵀ, H₀ = Q, W = I + G H,
//! A' = A W⁻¹ A, G' = G + A W⁻¹ G Aᵀ, H' = H + Aᵀ H W⁻¹ A; H → X quadratically.
//! It runs once before take-off, so it may be slow; it must never hand back NaN gains.

use core::fmt;
use nalgebra::{SMatrix, SVector};

/// Upper bound on doubling steps: each doubles the horizon, 64 steps cover 2⁶⁴ samples.
pub const MAX_ITERATIONS: u32 = 64;
/// Convergence: ‖ΔH‖_F ≤ this · ‖H‖_F.
const RELATIVE_TOLERANCE: f64 = 1e-13;
/// Accept the result only if the Riccati residual is this small relative to ‖X‖_F.
const RESIDUAL_TOLERANCE: f64 = 1e-8;

/// Why the Riccati solve failed (the caller keeps flying on its previous gains or stays
/// disarmed; it never gets a NaN gain).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DareError {
    /// An input matrix or cost contains NaN/∞, or r ≤ 0, or Q is not ⪰ 0 on its diagonal.
    BadInput,
    /// I + G·H became singular: the problem is not stabilisable/detectable.
    Singular,
    /// No convergence within [`MAX_ITERATIONS`] doubling steps.
    NotConverged,
    /// The iteration produced a non-finite value or the result fails the residual check.
    Diverged,
}

impl fmt::Display for DareError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DareError::BadInput => "DARE input not finite or costs invalid",
            DareError::Singular => "DARE doubling matrix singular",
            DareError::NotConverged => "DARE did not converge",
            DareError::Diverged => "DARE diverged or failed the residual check",
        })
    }
}

impl core::error::Error for DareError {}

/// The solution and how it was reached.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DareSolution<const N: usize> {
    /// The stabilising solution X.
    pub x: SMatrix<f64, N, N>,
    /// Doubling steps used.
    pub iterations: u32,
}

fn all_finite<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> bool {
    m.iter().all(|v| v.is_finite())
}

/// Solves the DARE for (A, b, Q, r); see the module doc.
pub fn solve<const N: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SVector<f64, N>,
    q: &SMatrix<f64, N, N>,
    r: f64,
) -> Result<DareSolution<N>, DareError> {
    let diag_ok = q.diagonal().iter().all(|v| *v >= 0.0);
    if !(all_finite(a) && all_finite(b) && all_finite(q) && r.is_finite() && r > 0.0 && diag_ok) {
        return Err(DareError::BadInput);
    }
    let identity = SMatrix::<f64, N, N>::identity();
    let mut ak = *a;
    let mut gk = b * b.transpose() / r;
    let mut hk = (q + q.transpose()) * 0.5;
    for iteration in 1..=MAX_ITERATIONS {
        let w_inv = (identity + gk * hk)
            .try_inverse()
            .ok_or(DareError::Singular)?;
        let aw = ak * w_inv;
        let a_next = aw * ak;
        let g_next = gk + aw * gk * ak.transpose();
        let h_next = hk + ak.transpose() * hk * w_inv * ak;
        // Round-off makes G and H drift from symmetric; symmetrise every step.
        let g_next = (g_next + g_next.transpose()) * 0.5;
        let h_next = (h_next + h_next.transpose()) * 0.5;
        if !(all_finite(&a_next) && all_finite(&g_next) && all_finite(&h_next)) {
            return Err(DareError::Diverged);
        }
        // Max-abs norms: the Frobenius norm of a diverging H overflows before H does.
        let change = (h_next - hk).amax();
        let scale = h_next.amax();
        ak = a_next;
        gk = g_next;
        hk = h_next;
        if change <= RELATIVE_TOLERANCE * scale {
            let res = residual(a, b, q, r, &hk);
            // The result must solve the equation and be the *stabilising* solution.
            let k = lqr_gain(a, b, r, &hk);
            let closed = a - b * k.transpose();
            if !(res.is_finite() && res <= RESIDUAL_TOLERANCE * hk.norm() && is_stable(&closed)) {
                return Err(DareError::Diverged);
            }
            return Ok(DareSolution {
                x: hk,
                iterations: iteration,
            });
        }
    }
    Err(DareError::NotConverged)
}

/// Spectral radius < 1, tested without an eigen-solver: M^(2^48) must have decayed (an
/// eigenvalue 1 − 1e-9 decays to e^-2.8e5 there, one ≥ 1 does not).
pub fn is_stable<const N: usize>(m: &SMatrix<f64, N, N>) -> bool {
    let mut p = *m;
    for _ in 0..48 {
        p = p * p;
        if !all_finite(&p) {
            return false;
        }
    }
    p.amax() < 1e-6
}

/// ‖Aᵀ X A − Aᵀ X b (r + bᵀ X b)⁻¹ bᵀ X A + Q − X‖_F.
pub fn residual<const N: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SVector<f64, N>,
    q: &SMatrix<f64, N, N>,
    r: f64,
    x: &SMatrix<f64, N, N>,
) -> f64 {
    let xb = x * b;
    let s = r + b.dot(&xb);
    let atxb = a.transpose() * xb;
    let rhs = a.transpose() * x * a - atxb * atxb.transpose() / s + q;
    (rhs - x).norm()
}

/// LQR gain k = (r + bᵀ X b)⁻¹ bᵀ X A for u = −k·x.
pub fn lqr_gain<const N: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SVector<f64, N>,
    r: f64,
    x: &SMatrix<f64, N, N>,
) -> SVector<f64, N> {
    let xb = x * b;
    (a.transpose() * xb) / (r + b.dot(&xb))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Vector2};

    #[test]
    fn scalar_case_matches_closed_form() {
        // x = a²x − a²x²b²/(r + b²x) + q, a = 1.1, b = 1, q = 1, r = 1:
        // x² − a²x − q·r... solved: x = (q + a²r − r + √((q + a²r − r)² + 4qr)) / 2 (b = 1).
        let (a, q, r) = (1.1f64, 1.0f64, 1.0f64);
        let s = q + a * a * r - r;
        let expect = (s + (s * s + 4.0 * q * r).sqrt()) / 2.0;
        let sol = solve(
            &SMatrix::<f64, 1, 1>::new(a),
            &SVector::<f64, 1>::new(1.0),
            &SMatrix::<f64, 1, 1>::new(q),
            r,
        )
        .unwrap();
        assert!((sol.x[(0, 0)] - expect).abs() < 1e-12 * expect);
    }

    #[test]
    fn double_integrator_converges_and_rejects_garbage() {
        let a = Matrix2::new(1.0, 0.01, 0.0, 1.0);
        let b = Vector2::new(5e-5, 0.01);
        let q = Matrix2::new(1.0, 0.0, 0.0, 0.1);
        let sol = solve(&a, &b, &q, 1.0).unwrap();
        assert!(sol.iterations < 30);
        assert!(residual(&a, &b, &q, 1.0, &sol.x) < 1e-9 * sol.x.norm());
        let k = lqr_gain(&a, &b, 1.0, &sol.x);
        // Closed loop A − b kᵀ must be stable.
        let cl = a - b * k.transpose();
        let eig = cl.complex_eigenvalues();
        assert!(eig.iter().all(|l| l.re.hypot(l.im) < 1.0));
        assert_eq!(solve(&a, &b, &q, 0.0).unwrap_err(), DareError::BadInput);
        assert_eq!(
            solve(&a, &b, &(q * f64::NAN), 1.0).unwrap_err(),
            DareError::BadInput
        );
        // Uncontrollable unstable mode: no stabilising solution.
        let bad = solve(
            &Matrix2::new(1.2, 0.0, 0.0, 0.5),
            &Vector2::new(0.0, 1.0),
            &q,
            1.0,
        );
        assert!(bad.is_err(), "{bad:?}");
    }
}
