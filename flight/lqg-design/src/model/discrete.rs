//! Zero-order-hold discretisation of the per-axis model, in a form that stays accurate in f32
//! (`LQG.md` §1 "f32").
//!
//! With x = Ts/τ and e = exp(−x) the exact ZOH matrices need φ1 = 1 − e, φ2 = x − 1 + e and
//! φ3 = x²/2 − x + 1 − e. Written out directly, φ2 and φ3 are differences of nearly equal
//! numbers (φ3 ≈ x³/6); at τ = 80 ms and Ts = 1 ms the naive f32 LQR `B[0]` is 10 % wrong. Here
//! φ1 comes from `expm1` and φ2, φ3 from their alternating Taylor series for x < 1, where every
//! term is smaller than the previous one and nothing cancels. Generic over f32 (flight) and
//! f64 (gain design).

use super::AxisModel;
use core::ops::{Add, Div, Mul, Neg, Sub};

/// The float operations the discretisation needs (implemented for f32 and f64).
pub trait Real:
    Copy
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// exp(self).
    fn exp(self) -> Self;
    /// (exp(self), exp(self) − 1), the second without cancellation.
    fn exp_and_exp_m1(self) -> (Self, Self);
    /// Conversion from f64 (rounds for f32).
    fn from_f64(v: f64) -> Self;
    /// Conversion from f32 (exact).
    fn from_f32(v: f32) -> Self;
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    fn exp(self) -> Self {
        libm::expf(self)
    }
    fn exp_and_exp_m1(self) -> (Self, Self) {
        (libm::expf(self), libm::expm1f(self))
    }
    #[allow(clippy::cast_possible_truncation)] // rounding to f32 is the point
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    fn from_f32(v: f32) -> Self {
        v
    }
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    fn exp(self) -> Self {
        crate::exp::exp(self)
    }
    fn exp_and_exp_m1(self) -> (Self, Self) {
        crate::exp::exp_and_exp_m1(self)
    }
    fn from_f64(v: f64) -> Self {
        v
    }
    fn from_f32(v: f32) -> Self {
        f64::from(v)
    }
}

/// Series length: (x < 1) 1/20! < 1e-18, below f64 resolution relative to the first term.
const SERIES_TERMS: u8 = 20;

/// The cancellation-free exponential functions of x = Ts/τ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Phi<T> {
    /// e = exp(−x): the motor pole per sample.
    pub e: T,
    /// φ1 = 1 − e.
    pub phi1: T,
    /// φ2 = x − 1 + e ≈ x²/2.
    pub phi2: T,
    /// φ3 = x²/2 − x + 1 − e ≈ x³/6.
    pub phi3: T,
    /// g = 1 − (1 + x)·e ≈ x²/2: d(τ·φ1)/d ln τ = τ·g, needed by the identification EKF.
    pub g: T,
}

impl<T: Real> Phi<T> {
    /// Evaluates the φ functions for x = Ts/τ ≥ 0.
    pub fn new(x: T) -> Self {
        let (e, e_m1) = (-x).exp_and_exp_m1();
        let phi1 = -e_m1;
        if x < T::ONE {
            // t_n = (−x)^n / n!: φ2 = Σ_{n≥2} t_n, φ3 = −Σ_{n≥3} t_n, g = Σ_{n≥2} (n−1)·t_n.
            let two = T::ONE + T::ONE;
            let mut term = x * x / two;
            let mut phi2 = term;
            let mut phi3 = T::ZERO;
            let mut g = term;
            let mut n = two;
            for _ in 3..=SERIES_TERMS {
                n = n + T::ONE;
                term = -(term * x / n);
                phi2 = phi2 + term;
                phi3 = phi3 - term;
                g = g + (n - T::ONE) * term;
            }
            Self {
                e,
                phi1,
                phi2,
                phi3,
                g,
            }
        } else {
            // For x ≥ 1 the terms are of order 1 and the closed forms are accurate.
            let two = T::ONE + T::ONE;
            let phi2 = x - phi1;
            Self {
                e,
                phi1,
                phi2,
                phi3: x * x / two - phi2,
                g: phi1 - x * e,
            }
        }
    }
}

/// The RTKF model for x = (ω, ν, b), input u, exact ZOH (`LQG.md` §1):
/// `A = [[1, d·τ·φ1, −B0], [0, e, −φ1], [0, 0, 1]]`, `B = [B0, φ1, 0]`.
/// Only the entries that are not 0 or 1 are stored; the bias column is −B.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimatorMatrices<T> {
    /// `A[0][1] = (β1 − β2)·τ·φ1`: rate gained per sample from the torque state.
    pub a_rate_torque: T,
    /// `A[1][1] = e`.
    pub e: T,
    /// `B[0] = β2·Ts + (β1 − β2)·τ·φ2`.
    pub b_rate: T,
    /// `B[1] = φ1`.
    pub b_torque: T,
}

impl<T: Real> EstimatorMatrices<T> {
    /// Discretises `model` at loop period `ts_s`, entirely in precision `T`.
    pub fn new(model: &AxisModel, ts_s: T) -> Self {
        let tau = T::from_f32(model.tau_s);
        let beta1 = T::from_f32(model.ln_beta1).exp();
        let beta2 = model.ln_beta2.map_or(T::ZERO, |l| T::from_f32(l).exp());
        let d = beta1 - beta2;
        let phi = Phi::new(ts_s / tau);
        Self {
            a_rate_torque: d * tau * phi.phi1,
            e: phi.e,
            b_rate: beta2 * ts_s + d * tau * phi.phi2,
            b_torque: phi.phi1,
        }
    }

    /// Full A (row-major).
    pub fn a(&self) -> [[T; 3]; 3] {
        let (o, z) = (T::ONE, T::ZERO);
        [
            [o, self.a_rate_torque, -self.b_rate],
            [z, self.e, -self.b_torque],
            [z, z, o],
        ]
    }

    /// Full B.
    pub fn b(&self) -> [T; 3] {
        [self.b_rate, self.b_torque, T::ZERO]
    }
}

/// The LQR model for x = (θ, ω, ν), exact ZOH (`LQG.md` §1):
/// `A = [[1, Ts, d·τ²·φ2], [0, 1, d·τ·φ1], [0, 0, e]]`,
/// `B = [β2·Ts²/2 + d·τ²·φ3, β2·Ts + d·τ·φ2, φ1]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LqrMatrices<T> {
    /// Loop period Ts (`A[0][1]`).
    pub ts: T,
    /// `A[0][2] = d·τ²·φ2`.
    pub a_angle_torque: T,
    /// `A[1][2] = d·τ·φ1`.
    pub a_rate_torque: T,
    /// `A[2][2] = e`.
    pub e: T,
    /// B = (angle, rate, torque) response to one sample of u.
    pub b: [T; 3],
}

impl<T: Real> LqrMatrices<T> {
    /// Discretises `model` at loop period `ts_s`, entirely in precision `T`.
    pub fn new(model: &AxisModel, ts_s: T) -> Self {
        let tau = T::from_f32(model.tau_s);
        let beta1 = T::from_f32(model.ln_beta1).exp();
        let beta2 = model.ln_beta2.map_or(T::ZERO, |l| T::from_f32(l).exp());
        let d = beta1 - beta2;
        let phi = Phi::new(ts_s / tau);
        let two = T::ONE + T::ONE;
        Self {
            ts: ts_s,
            a_angle_torque: d * tau * tau * phi.phi2,
            a_rate_torque: d * tau * phi.phi1,
            e: phi.e,
            b: [
                beta2 * ts_s * ts_s / two + d * tau * tau * phi.phi3,
                beta2 * ts_s + d * tau * phi.phi2,
                phi.phi1,
            ],
        }
    }

    /// Full A (row-major).
    pub fn a(&self) -> [[T; 3]; 3] {
        let (o, z) = (T::ONE, T::ZERO);
        [
            [o, self.ts, self.a_angle_torque],
            [z, o, self.a_rate_torque],
            [z, z, self.e],
        ]
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // matrix loops read clearer with indices
mod tests {
    use super::*;

    /// Reference ZOH of the LQR model by a 60-term Taylor series of exp([[A_c, B_c],[0, 0]]·Ts)
    /// in f64: independent of the φ closed forms.
    fn lqr_expm(model: &AxisModel, ts: f64) -> ([[f64; 3]; 3], [f64; 3]) {
        let (b1, b2, tau) = (model.beta1(), model.beta2(), model.tau());
        let mut m = [[0.0f64; 4]; 4];
        m[0][1] = ts;
        m[1][2] = (b1 - b2) * ts;
        m[1][3] = b2 * ts;
        m[2][2] = -ts / tau;
        m[2][3] = ts / tau;
        let mut sum = [[0.0f64; 4]; 4];
        let mut term = [[0.0f64; 4]; 4];
        for i in 0..4 {
            sum[i][i] = 1.0;
            term[i][i] = 1.0;
        }
        for n in 1..60 {
            let mut next = [[0.0f64; 4]; 4];
            for i in 0..4 {
                for j in 0..4 {
                    next[i][j] = (0..4).map(|k| term[i][k] * m[k][j]).sum::<f64>() / f64::from(n);
                }
            }
            term = next;
            for i in 0..4 {
                for j in 0..4 {
                    sum[i][j] += term[i][j];
                }
            }
        }
        let a = [
            [sum[0][0], sum[0][1], sum[0][2]],
            [sum[1][0], sum[1][1], sum[1][2]],
            [sum[2][0], sum[2][1], sum[2][2]],
        ];
        (a, [sum[0][3], sum[1][3], sum[2][3]])
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs().max(1e-300)
    }

    #[test]
    fn f64_and_f32_match_matrix_exponential() {
        let mut worst32 = 0.0f64;
        for ln_beta in [6.0f32, 8.0, 10.0, 12.0] {
            for tau in [0.005f32, 0.015, 0.03, 0.08, 0.25] {
                for ts in [1.0 / 8000.0, 1.0 / 1000.0, 1.0 / 400.0, 1.0 / 333.0] {
                    for yaw in [None, Some(6.0f32)] {
                        let mut m = AxisModel::new(ln_beta, tau).unwrap();
                        if let Some(l2) = yaw {
                            m = m.with_beta2(l2).unwrap();
                        }
                        let (a_ref, b_ref) = lqr_expm(&m, ts);
                        let l64 = LqrMatrices::<f64>::new(&m, ts);
                        let l32 = LqrMatrices::<f32>::new(&m, ts as f32);
                        for i in 0..3 {
                            assert!(rel(l64.b[i], b_ref[i]) < 1e-11, "B{i} {l64:?}");
                            worst32 = worst32.max(rel(f64::from(l32.b[i]), b_ref[i]));
                        }
                        assert!(rel(l64.a_angle_torque, a_ref[0][2]) < 1e-11);
                        assert!(rel(l64.a_rate_torque, a_ref[1][2]) < 1e-11);
                        assert!(rel(l64.e, a_ref[2][2]) < 1e-12);
                        worst32 = worst32.max(rel(f64::from(l32.a_angle_torque), a_ref[0][2]));
                        // The estimator uses the same entries (its B0 is the LQR's B[1]).
                        let e32 = EstimatorMatrices::<f32>::new(&m, ts as f32);
                        worst32 = worst32.max(rel(f64::from(e32.b_rate), b_ref[1]));
                        worst32 = worst32.max(rel(f64::from(e32.a_rate_torque), a_ref[1][2]));
                    }
                }
            }
        }
        // `LQG.md` §1: the φ-form stays within 4.2e-7 in f32 (plus the f32 rounding of
        // exp(ln β)).
        assert!(worst32 < 2e-6, "worst f32 relative error {worst32}");
    }

    #[test]
    fn naive_form_is_the_ten_percent_error_we_avoid() {
        let m = AxisModel::new(10.0, 0.08).unwrap();
        let ts = 0.001f32;
        let (_, b_ref) = lqr_expm(&m, 0.001);
        let (beta, tau) = (libm::expf(10.0), 0.08f32);
        let e = libm::expf(-ts / tau);
        let naive_b0 = beta * ts * ts / 2.0 - beta * tau * tau * (ts / tau - 1.0 + e);
        let good = LqrMatrices::<f32>::new(&m, ts);
        assert!(rel(f64::from(naive_b0), b_ref[0]) > 0.02);
        assert!(rel(f64::from(good.b[0]), b_ref[0]) < 2e-6);
    }

    #[test]
    fn g_series_matches_closed_form() {
        for x in [0.001f64, 0.05, 0.5, 0.99, 1.5, 4.0] {
            let p = Phi::new(x);
            let g = 1.0 - (1.0 + x) * libm::exp(-x);
            assert!(rel(p.g, g) < 1e-9 / x.min(1.0), "x {x}");
            assert!(rel(p.phi2, x - 1.0 + libm::exp(-x)) < 1e-9 / (x * x).min(1.0));
        }
    }
}
