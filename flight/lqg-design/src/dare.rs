//! Discrete algebraic Riccati equation, single input, in f64, by the structure-preserving
//! doubling algorithm (SDA; `LQG.md` §7: ≤ 24 iterations, ≤ 3.5e-9 relative error over the
//! whole parameter grid, where f32 or absolute-tolerance iteration fail).
//!
//! Solves X = Aᵀ X A − Aᵀ X B (r + Bᵀ X B)⁻¹ Bᵀ X A + Q for the stabilising X ⪰ 0.
//! SDA: A₀ = A, G₀ = B r⁻¹ Bᵀ, H₀ = Q, W = I + G H,
//! A' = A W⁻¹ A, G' = G + A W⁻¹ G Aᵀ, H' = H + Aᵀ H W⁻¹ A; H → X quadratically.
//! It runs once before take-off, so it may be slow; it must never hand back NaN gains.
//!
//! The matrices are [`Square`]s whose size is a runtime value: one loop serves the 2- and
//! 3-state problems, where fixed-size matrices made the optimiser write out every product
//! of every size in soft-float calls (12.5 KB of flash for this file; issue 33). Every
//! product, sum and inverse is evaluated in the order nalgebra's did before, so the solve
//! gives nalgebra's bits for the same matrices.

use core::fmt;

/// Largest state dimension solved for (the 3-state Kalman and attitude models).
pub const MAX_STATES: usize = 3;

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
    /// An input matrix or cost contains NaN/∞, or r ≤ 0, or Q is not ⪰ 0 on its diagonal
    /// (or the sizes disagree).
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

/// A column vector of a [`Square`]'s size (entries past it are 0).
pub type Vector = [f64; MAX_STATES];

/// An n×n matrix, n ≤ [`MAX_STATES`], row-major; entries outside n×n are 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Square {
    n: usize,
    m: [[f64; MAX_STATES]; MAX_STATES],
}

impl Square {
    /// The n×n zero matrix (n clamped to [`MAX_STATES`]).
    pub fn zeros(n: usize) -> Self {
        Self {
            n: n.min(MAX_STATES),
            m: [[0.0; MAX_STATES]; MAX_STATES],
        }
    }

    /// The n×n identity.
    pub fn identity(n: usize) -> Self {
        let mut s = Self::zeros(n);
        for i in 0..s.n {
            s.set(i, i, 1.0);
        }
        s
    }

    /// The leading n×n block of `rows`.
    pub fn from_rows<const C: usize>(n: usize, rows: &[[f64; C]]) -> Self {
        let mut s = Self::zeros(n);
        for (i, row) in rows.iter().enumerate().take(s.n) {
            for (j, &v) in row.iter().enumerate().take(s.n) {
                s.set(i, j, v);
            }
        }
        s
    }

    /// The diagonal matrix of the first n entries of `d`.
    pub fn diagonal(n: usize, d: &[f64]) -> Self {
        let mut s = Self::zeros(n);
        for (i, &v) in d.iter().enumerate().take(s.n) {
            s.set(i, i, v);
        }
        s
    }

    /// Rows (and columns).
    pub fn size(&self) -> usize {
        self.n
    }

    /// Entry (i, j); 0 outside the matrix.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.m.get(i).and_then(|r| r.get(j)).copied().unwrap_or(0.0)
    }

    fn set(&mut self, i: usize, j: usize, v: f64) {
        if let Some(e) = self.m.get_mut(i).and_then(|r| r.get_mut(j)) {
            *e = v;
        }
    }

    /// Column j.
    pub fn column(&self, j: usize) -> Vector {
        let mut c = [0.0; MAX_STATES];
        for (i, e) in c.iter_mut().enumerate().take(self.n) {
            *e = self.get(i, j);
        }
        c
    }

    /// `self · rhs` (rhs of the same size).
    #[inline(never)]
    pub fn mul(&self, rhs: &Square) -> Square {
        let mut out = Square::zeros(self.n);
        for i in 0..self.n {
            for j in 0..self.n {
                let mut acc = 0.0;
                for k in 0..self.n {
                    acc += self.get(i, k) * rhs.get(k, j);
                }
                out.set(i, j, acc);
            }
        }
        out
    }

    /// `self · v`.
    #[inline(never)]
    pub fn mul_vec(&self, v: &Vector) -> Vector {
        let mut out = [0.0; MAX_STATES];
        for (i, o) in out.iter_mut().enumerate().take(self.n) {
            for (k, x) in v.iter().enumerate().take(self.n) {
                *o += self.get(i, k) * x;
            }
        }
        out
    }

    /// `a·self + b·rhs`, entry by entry.
    #[inline(never)]
    fn combine(&self, a: f64, rhs: &Square, b: f64) -> Square {
        let mut out = Square::zeros(self.n);
        for i in 0..self.n {
            for j in 0..self.n {
                out.set(i, j, a * self.get(i, j) + b * rhs.get(i, j));
            }
        }
        out
    }

    /// `self + rhs`.
    pub fn add(&self, rhs: &Square) -> Square {
        self.combine(1.0, rhs, 1.0)
    }

    /// `self − rhs`.
    pub fn sub(&self, rhs: &Square) -> Square {
        self.combine(1.0, rhs, -1.0)
    }

    /// The transpose.
    #[inline(never)]
    pub fn transpose(&self) -> Square {
        let mut out = Square::zeros(self.n);
        for i in 0..self.n {
            for j in 0..self.n {
                out.set(i, j, self.get(j, i));
            }
        }
        out
    }

    /// (self + selfᵀ)/2: round-off makes the doubling's G and H drift from symmetric.
    pub fn symmetrised(&self) -> Square {
        self.combine(0.5, &self.transpose(), 0.5)
    }

    /// `u · vᵀ / divisor` (n×n).
    #[inline(never)]
    pub fn outer(n: usize, u: &Vector, v: &Vector, divisor: f64) -> Square {
        let mut out = Square::zeros(n);
        for (i, ui) in u.iter().enumerate().take(out.n) {
            for (j, vj) in v.iter().enumerate().take(out.n) {
                out.set(i, j, ui * vj / divisor);
            }
        }
        out
    }

    /// The inverse by the adjugate over the determinant; `None` when the determinant is 0
    /// (a non-finite result is the caller's to refuse). One 3×3 cofactor loop serves every
    /// size: a smaller matrix is padded with 1 on the diagonal, which leaves its cofactors
    /// and determinant unchanged. Each cofactor is the product difference nalgebra's
    /// `try_inverse` writes out term by term: the same bits.
    #[inline(never)]
    pub fn inverse(&self) -> Option<Square> {
        if self.n == 0 {
            return None;
        }
        let mut padded = self.m;
        for (i, row) in padded.iter_mut().enumerate().skip(self.n) {
            if let Some(e) = row.get_mut(i) {
                *e = 1.0;
            }
        }
        let g = |i: usize, j: usize| {
            padded
                .get(i % MAX_STATES)
                .and_then(|r| r.get(j % MAX_STATES))
                .copied()
                .unwrap_or(0.0)
        };
        // Entry (i, j) of the adjugate: the cofactor of (j, i).
        let adjugate = |i: usize, j: usize| {
            g(j + 1, i + 1) * g(j + 2, i + 2) - g(j + 1, i + 2) * g(j + 2, i + 1)
        };
        let det = (0..MAX_STATES).fold(0.0, |acc, k| acc + g(0, k) * adjugate(k, 0));
        if det == 0.0 {
            return None;
        }
        let mut out = Square::zeros(self.n);
        for i in 0..self.n {
            for j in 0..self.n {
                out.set(i, j, adjugate(i, j) / det);
            }
        }
        Some(out)
    }

    fn entries(&self) -> impl Iterator<Item = f64> + '_ {
        self.m
            .iter()
            .take(self.n)
            .flat_map(move |r| r.iter().take(self.n).copied())
    }

    /// Every entry finite.
    pub fn all_finite(&self) -> bool {
        self.entries().all(f64::is_finite)
    }

    /// The largest |entry|.
    pub fn amax(&self) -> f64 {
        self.entries().fold(0.0, |m, v| m.max(v.abs()))
    }

    /// The Frobenius norm.
    pub fn norm(&self) -> f64 {
        libm::sqrt(self.entries().map(|v| v * v).sum())
    }
}

/// `u · v` over the first n entries.
pub fn dot(n: usize, u: &Vector, v: &Vector) -> f64 {
    u.iter().zip(v).take(n).map(|(a, b)| a * b).sum()
}

/// The solution and how it was reached.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DareSolution {
    /// The stabilising solution X.
    pub x: Square,
    /// Doubling steps used.
    pub iterations: u32,
}

/// Solves the DARE for (A, b, Q, r) of A's size; see the module doc.
#[inline(never)]
pub fn solve(a: &Square, b: &Vector, q: &Square, r: f64) -> Result<DareSolution, DareError> {
    let n = a.size();
    let diag_ok = (0..n).all(|i| q.get(i, i) >= 0.0);
    let b_finite = b.iter().all(|v| v.is_finite());
    if !(q.size() == n && a.all_finite() && b_finite && q.all_finite() && r.is_finite())
        || !(r > 0.0 && diag_ok)
    {
        return Err(DareError::BadInput);
    }
    let identity = Square::identity(n);
    let mut ak = *a;
    let mut gk = Square::outer(n, b, b, r);
    let mut hk = q.symmetrised();
    for iteration in 1..=MAX_ITERATIONS {
        let w_inv = identity
            .add(&gk.mul(&hk))
            .inverse()
            .ok_or(DareError::Singular)?;
        let aw = ak.mul(&w_inv);
        let a_next = aw.mul(&ak);
        let g_next = gk.add(&aw.mul(&gk).mul(&ak.transpose())).symmetrised();
        let h_next = hk
            .add(&ak.transpose().mul(&hk).mul(&w_inv).mul(&ak))
            .symmetrised();
        if !(a_next.all_finite() && g_next.all_finite() && h_next.all_finite()) {
            return Err(DareError::Diverged);
        }
        // Max-abs norms: the Frobenius norm of a diverging H overflows before H does.
        let change = h_next.sub(&hk).amax();
        let scale = h_next.amax();
        ak = a_next;
        gk = g_next;
        hk = h_next;
        if change <= RELATIVE_TOLERANCE * scale {
            let res = residual(a, b, q, r, &hk);
            // The result must solve the equation and be the *stabilising* solution.
            let k = lqr_gain(a, b, r, &hk);
            let closed = a.sub(&Square::outer(n, b, &k, 1.0));
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
pub fn is_stable(m: &Square) -> bool {
    let mut p = *m;
    for _ in 0..48 {
        p = p.mul(&p);
        if !p.all_finite() {
            return false;
        }
    }
    p.amax() < 1e-6
}

/// ‖Aᵀ X A − Aᵀ X b (r + bᵀ X b)⁻¹ bᵀ X A + Q − X‖_F.
pub fn residual(a: &Square, b: &Vector, q: &Square, r: f64, x: &Square) -> f64 {
    let n = a.size();
    let xb = x.mul_vec(b);
    let s = r + dot(n, b, &xb);
    let atxb = a.transpose().mul_vec(&xb);
    let atxa = a.transpose().mul(x).mul(a);
    let rhs = atxa.sub(&Square::outer(n, &atxb, &atxb, s)).add(q);
    rhs.sub(x).norm()
}

/// LQR gain k = (r + bᵀ X b)⁻¹ bᵀ X A for u = −k·x.
pub fn lqr_gain(a: &Square, b: &Vector, r: f64, x: &Square) -> Vector {
    let n = a.size();
    let xb = x.mul_vec(b);
    let s = r + dot(n, b, &xb);
    a.transpose().mul_vec(&xb).map(|v| v / s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix2;

    #[test]
    fn scalar_case_matches_closed_form() {
        // x = a²x − a²x²b²/(r + b²x) + q, a = 1.1, b = 1, q = 1, r = 1:
        // x² − a²x − q·r... solved: x = (q + a²r − r + √((q + a²r − r)² + 4qr)) / 2 (b = 1).
        let (a, q, r) = (1.1f64, 1.0f64, 1.0f64);
        let s = q + a * a * r - r;
        let expect = (s + (s * s + 4.0 * q * r).sqrt()) / 2.0;
        let sol = solve(
            &Square::from_rows(1, &[[a]]),
            &[1.0, 0.0, 0.0],
            &Square::from_rows(1, &[[q]]),
            r,
        )
        .unwrap();
        assert!((sol.x.get(0, 0) - expect).abs() < 1e-12 * expect);
    }

    #[test]
    fn double_integrator_converges_and_rejects_garbage() {
        let a = Square::from_rows(2, &[[1.0, 0.01], [0.0, 1.0]]);
        let b = [5e-5, 0.01, 0.0];
        let q = Square::diagonal(2, &[1.0, 0.1]);
        let sol = solve(&a, &b, &q, 1.0).unwrap();
        assert!(sol.iterations < 30);
        assert!(residual(&a, &b, &q, 1.0, &sol.x) < 1e-9 * sol.x.norm());
        let k = lqr_gain(&a, &b, 1.0, &sol.x);
        // Closed loop A − b kᵀ must be stable (eigenvalues from an independent solver).
        let cl = a.sub(&Square::outer(2, &b, &k, 1.0));
        let eig = Matrix2::new(cl.get(0, 0), cl.get(0, 1), cl.get(1, 0), cl.get(1, 1))
            .complex_eigenvalues();
        assert!(eig.iter().all(|l| l.re.hypot(l.im) < 1.0));
        assert!(is_stable(&cl));
        assert_eq!(solve(&a, &b, &q, 0.0).unwrap_err(), DareError::BadInput);
        let nan_q = Square::diagonal(2, &[f64::NAN, 0.1]);
        assert_eq!(solve(&a, &b, &nan_q, 1.0).unwrap_err(), DareError::BadInput);
        assert_eq!(
            solve(&a, &b, &Square::identity(3), 1.0).unwrap_err(),
            DareError::BadInput,
            "sizes disagree"
        );
        // Uncontrollable unstable mode: no stabilising solution.
        let bad = solve(
            &Square::from_rows(2, &[[1.2, 0.0], [0.0, 0.5]]),
            &[0.0, 1.0, 0.0],
            &q,
            1.0,
        );
        assert!(bad.is_err(), "{bad:?}");
    }

    #[test]
    fn inverse_is_exact_and_refuses_singular() {
        let m = Square::from_rows(3, &[[0.0, 2.0, 1.0], [1.0, 1.0, 0.0], [3.0, 0.0, 1.0]]);
        let inv = m.inverse().unwrap();
        let id = m.mul(&inv);
        for i in 0..3 {
            for j in 0..3 {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((id.get(i, j) - want).abs() < 1e-15, "{id:?}");
            }
        }
        let singular = Square::from_rows(2, &[[1.0, 2.0], [2.0, 4.0]]);
        assert_eq!(singular.inverse(), None);
    }

    #[test]
    fn operations_give_nalgebras_bits() {
        // The design's earlier nalgebra code, operation by operation: the same bits for the
        // same matrices.
        use nalgebra::{Matrix3, Vector3};
        let mut state = 0x1234_5678_9ABC_DEF0_u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
        };
        for _ in 0..1000 {
            let rows = [
                [next(), next(), next()],
                [next(), next(), next()],
                [next(), next(), next()],
            ];
            let other = [
                [next(), next(), next()],
                [next(), next(), next()],
                [next(), next(), next()],
            ];
            let (a, b) = (Square::from_rows(3, &rows), Square::from_rows(3, &other));
            let (na, nb) = (
                Matrix3::from(rows).transpose(),
                Matrix3::from(other).transpose(),
            );
            let same = |s: &Square, m: &Matrix3<f64>| {
                (0..3).all(|i| (0..3).all(|j| s.get(i, j).to_bits() == m[(i, j)].to_bits()))
            };
            assert!(same(&a.mul(&b), &(na * nb)));
            assert!(same(&a.inverse().unwrap(), &na.try_inverse().unwrap()));
            assert!(same(&a.symmetrised(), &((na + na.transpose()) * 0.5)));
            let v = [next(), next(), next()];
            let nv = Vector3::from(v);
            let r = next().abs() + 0.5;
            assert!(same(
                &Square::outer(3, &v, &v, r),
                &(nv * nv.transpose() / r)
            ));
            let mv = a.mul_vec(&v);
            let nmv = na * nv;
            assert!((0..3).all(|i| mv[i].to_bits() == nmv[i].to_bits()));
            assert_eq!(dot(3, &v, &mv).to_bits(), nv.dot(&nmv).to_bits());
            let two = Square::from_rows(2, &rows);
            let n2 = nalgebra::Matrix2::new(rows[0][0], rows[0][1], rows[1][0], rows[1][1]);
            let inv2 = two.inverse().unwrap();
            let ninv2 = n2.try_inverse().unwrap();
            assert!(
                (0..2).all(|i| (0..2).all(|j| inv2.get(i, j).to_bits() == ninv2[(i, j)].to_bits()))
            );
        }
    }
}
