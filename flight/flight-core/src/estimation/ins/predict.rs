//! Time update: state propagation and P ← Φ·P·Φᵀ + Q_d with Φ = I + F·dt, exploiting the
//! sparsity of Φ (DERIVATION.md §3). The C reference hand-expanded this into 15 kB of code;
//! here one sparse "apply Φ" routine is used twice.

use super::equations::{ProcessJacobian, process_jacobian, xi};
use super::{Covariance, Filter, STATES, covariance};
use crate::estimation::quaternion::{body_to_ned_vector, rotate_by_body_vector};
use crate::estimation::{Error, check_finite};

/// Longest accepted time step (s); a longer gap means samples were lost and the caller
/// should re-initialise rather than extrapolate.
pub const MAX_DT_S: f32 = 0.1;

/// Φ = I + F·dt in factored form (only the blocks that differ from I).
struct Transition {
    dt: f32,
    /// dt·∂v̇/∂q, rows N, E, D.
    dv_dq: [[f32; 4]; 3],
    /// dt·∂v̇/∂abz.
    dv_dab: [f32; 3],
    /// I + dt·∂q̇/∂q.
    qq: [[f32; 4]; 4],
    /// dt·∂q̇/∂b_g.
    qb: [[f32; 3]; 4],
}

impl Transition {
    fn new(j: &ProcessJacobian, dt: f32) -> Self {
        let mut qq = j.dq_dq.map(|row| row.map(|c| c * dt));
        for (i, row) in qq.iter_mut().enumerate() {
            if let Some(d) = row.get_mut(i) {
                *d += 1.0;
            }
        }
        Self {
            dt,
            dv_dq: j.dv_dq.map(|row| row.map(|c| c * dt)),
            dv_dab: j.dv_dbaz.map(|c| c * dt),
            qq,
            qb: j.dq_dbg.map(|row| row.map(|c| c * dt)),
        }
    }
}

/// out[j] = Σₙ kₙ·rowsₙ[j] for the columns `FIRST..14`; the columns before `FIRST` are
/// never read by the second pass (it only needs W[r][m] for m in Φ rows c ≥ r) and stay 0.
/// N and FIRST are constants, so this unrolls with the coefficients held in registers.
#[inline(always)]
fn combine<const N: usize, const FIRST: usize>(
    out: &mut [f32; STATES],
    rows: [&[f32; STATES]; N],
    k: [f32; N],
) {
    for (j, o) in out.iter_mut().enumerate().skip(FIRST) {
        let mut acc = 0.0;
        for (row, kn) in rows.iter().zip(k) {
            acc += kn * row.get(j).copied().unwrap_or(0.0);
        }
        *o = acc;
    }
}

/// Σₙ kₙ·v[first + n] for N consecutive entries of one row.
#[inline(always)]
fn dot<const N: usize>(v: &[f32; STATES], first: usize, k: &[f32; N]) -> f32 {
    let mut acc = 0.0;
    for (x, kn) in v.iter().skip(first).zip(k) {
        acc += kn * x;
    }
    acc
}

impl Filter {
    /// Propagates the estimate by `dt_s` with one IMU sample (gyro rad/s, specific force
    /// m/s², body FRD), then the covariance.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for a non-finite input, [`Error::InvalidTimeStep`] for
    /// `dt_s ∉ (0, 0.1]`, [`Error::Diverged`] if the result is not finite. The filter is
    /// unchanged on the first two.
    pub fn predict(
        &mut self,
        gyro_radps: [f32; 3],
        accel_mps2: [f32; 3],
        dt_s: f32,
    ) -> Result<(), Error> {
        check_finite(&gyro_radps)?;
        check_finite(&accel_mps2)?;
        if !(dt_s > 0.0 && dt_s <= MAX_DT_S) {
            return Err(Error::InvalidTimeStep);
        }
        // F is linearised at the pre-step state, as in the C reference (DERIVATION.md §2, §7).
        let jacobian = process_jacobian(&self.x, gyro_radps, accel_mps2);
        self.predict_state(gyro_radps, accel_mps2, dt_s);
        self.predict_covariance(&jacobian, dt_s);
        if self.is_finite() {
            Ok(())
        } else {
            Err(Error::Diverged)
        }
    }

    fn predict_state(&mut self, gyro: [f32; 3], accel: [f32; 3], dt: f32) {
        let q = self.attitude();
        let [pn, pe, pd, vn, ve, vd, _, _, _, _, bx, by, bz, ab_z] = self.x;
        let [an, ae, ad] = body_to_ned_vector(q, [accel[0], accel[1], accel[2] - ab_z]);
        let ad = ad + Self::gravity_mps2();
        let half_dt2 = 0.5 * dt * dt;
        let theta = [
            (gyro[0] - bx) * dt,
            (gyro[1] - by) * dt,
            (gyro[2] - bz) * dt,
        ];
        let [q0, q1, q2, q3] = rotate_by_body_vector(q, theta);
        // One Newton step of 1/√n around n = 1 is exact to second order in the tiny
        // per-step drift of the norm, and needs no square root.
        let n = q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3;
        let s = 1.5 - 0.5 * n;
        self.x = [
            pn + vn * dt + an * half_dt2,
            pe + ve * dt + ae * half_dt2,
            pd + vd * dt + ad * half_dt2,
            vn + an * dt,
            ve + ae * dt,
            vd + ad * dt,
            q0 * s,
            q1 * s,
            q2 * s,
            q3 * s,
            bx,
            by,
            bz,
            ab_z,
        ];
    }

    fn predict_covariance(&mut self, jacobian: &ProcessJacobian, dt: f32) {
        let phi = Transition::new(jacobian, dt);
        let mut w_top = [[0.0; STATES]; 10];
        phi_times(&phi, &self.p, &mut w_top);
        let [.., p10, p11, p12, p13] = self.p;
        let [w0, w1, w2, w3, w4, w5, w6, w7, w8, w9] = w_top;
        let w = [w0, w1, w2, w3, w4, w5, w6, w7, w8, w9, p10, p11, p12, p13];
        // P' = W·Φᵀ: P'[r][c] = Σₘ W[r][m]·Φ[c][m], only for r ≤ c, each value stored to both
        // triangles; Φ row c's coefficients stay in registers across the r loop.
        let p = &mut self.p;
        // Φ's row blocks by column range; the velocity and quaternion blocks are zipped with
        // their columns, so a Jacobian row can never be missing (it was a zero fallback).
        let rows = |c: usize| w.iter().enumerate().take(c + 1);
        for c in 0..3 {
            for (r, wr) in rows(c) {
                let v = get_row(wr, c) + dt * get_row(wr, c + 3);
                covariance::set_symmetric(p, r, c, v);
            }
        }
        for (c, (a, &ab)) in (3..6).zip(phi.dv_dq.iter().zip(&phi.dv_dab)) {
            for (r, wr) in rows(c) {
                let v = get_row(wr, c) + dot(wr, 6, a) + ab * get_row(wr, 13);
                covariance::set_symmetric(p, r, c, v);
            }
        }
        for (c, (q, b)) in (6..10).zip(phi.qq.iter().zip(&phi.qb)) {
            for (r, wr) in rows(c) {
                let v = dot(wr, 6, q) + dot(wr, 10, b);
                covariance::set_symmetric(p, r, c, v);
            }
        }
        for c in 10..STATES {
            for (r, wr) in rows(c) {
                covariance::set_symmetric(p, r, c, get_row(wr, c));
            }
        }
        self.add_process_noise(dt);
    }

    /// Q_d = G·Q·Gᵀ·dt: accel noise through R_beᵀ (isotropic, so it stays diagonal), gyro
    /// noise through ½Ξ(q), and the bias random walks (DERIVATION.md §3).
    fn add_process_noise(&mut self, dt: f32) {
        let cfg = &self.config;
        let accel = cfg.accel_noise_psd * dt;
        let [g0, g1, g2] = cfg.gyro_noise_psd.map(|g| 0.25 * g * dt);
        let bias = cfg.gyro_bias_walk_psd * dt;
        let ab_z = cfg.accel_bias_walk_psd * dt;
        for (i, row) in self.p.iter_mut().enumerate() {
            match i {
                3..6 => add_diag(row, i, accel),
                10..13 => add_diag(row, i, bias),
                13 => add_diag(row, i, ab_z),
                _ => {}
            }
        }
        // Gyro noise on the quaternion block, upper triangle stored to both halves.
        let x = xi(self.attitude());
        for (i, xi_i) in x.iter().enumerate() {
            for (j, xi_j) in x.iter().enumerate().skip(i) {
                let q =
                    g0 * (xi_i[0] * xi_j[0]) + g1 * (xi_i[1] * xi_j[1]) + g2 * (xi_i[2] * xi_j[2]);
                let (r, c) = (6 + i, 6 + j);
                let v = covariance::get(&self.p, r, c) + q;
                covariance::set_symmetric(&mut self.p, r, c, v);
            }
        }
    }
}

/// Rows 0..10 of W = Φ·P into `w` (Φ's bias rows are the identity, so W's bias rows are
/// P's and are not computed).
fn phi_times(phi: &Transition, p: &Covariance, w: &mut [[f32; STATES]; 10]) {
    let [p0, p1, p2, p3, p4, p5, p6, p7, p8, p9, p10, p11, p12, p13] = p;
    let dt = phi.dt;
    let [a0, a1, a2] = phi.dv_dq;
    let [c0, c1, c2] = phi.dv_dab;
    let [q0, q1, q2, q3] = phi.qq;
    let [b0, b1, b2, b3] = phi.qb;
    let [w0, w1, w2, w3, w4, w5, w6, w7, w8, w9] = w;
    combine::<2, 0>(w0, [p0, p3], [1.0, dt]);
    combine::<2, 0>(w1, [p1, p4], [1.0, dt]);
    combine::<2, 0>(w2, [p2, p5], [1.0, dt]);
    for (wv, pv, a, c) in [(w3, p3, a0, c0), (w4, p4, a1, c1), (w5, p5, a2, c2)] {
        combine::<6, 3>(
            wv,
            [pv, p6, p7, p8, p9, p13],
            [1.0, a[0], a[1], a[2], a[3], c],
        );
    }
    for (wq, q, b) in [(w6, q0, b0), (w7, q1, b1), (w8, q2, b2), (w9, q3, b3)] {
        combine::<7, 6>(
            wq,
            [p6, p7, p8, p9, p10, p11, p12],
            [q[0], q[1], q[2], q[3], b[0], b[1], b[2]],
        );
    }
}

#[inline(always)]
fn get_row(row: &[f32; STATES], j: usize) -> f32 {
    row.get(j).copied().unwrap_or(0.0)
}

fn add_diag(row: &mut [f32; STATES], i: usize, value: f32) {
    if let Some(d) = row.get_mut(i) {
        *d += value;
    }
}
