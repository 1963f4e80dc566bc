//! Time update: state propagation and P ← Φ·P·Φᵀ + Q_d with Φ = I + F·dt, exploiting the
//! structure of Φ (DERIVATION.md §3). The C reference hand-expanded this into 15 kB of code;
//! here one "apply Φ to a vector" routine is used twice, with Φ's blocks held as the eleven
//! distinct values they are made of.

use super::equations::{ProcessJacobian, process_jacobian, xi};
use super::{Covariance, Filter, STATES, covariance};
use crate::quaternion::{body_to_ned_vector, rotate_by_body_vector};
use crate::{Error, check_finite};

/// Longest accepted time step (s); a longer gap means samples were lost and the caller
/// should re-initialise rather than extrapolate.
pub const MAX_DT_S: f32 = 0.1;

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

    /// P ← Φ P Φᵀ in two passes over the rows (DERIVATION.md §3). Φ = I + J with
    /// J = F·dt, whose blocks are few distinct values ([`ProcessJacobian`]), so applying Φ to
    /// a vector keeps them in registers and reads each element of the vector once.
    ///
    /// 1. W = Φ P: column m of W is Φ applied to row m of P (P is symmetric). Only W's
    ///    velocity rows (columns 3..) and quaternion rows (columns 6..) are kept: its position
    ///    rows are formed in pass 2 from P's, its bias rows are P's.
    /// 2. Row r of P' = W Φᵀ is Φ applied to row r of W; only c ≥ r is formed and each
    ///    value is stored to both triangles, so P stays exactly symmetric. Rows are done in
    ///    order, and row r reads only columns ≥ r of P's rows r and r + 3, which the earlier
    ///    rows' mirrored stores (columns < r) have not touched. The bias block of P' is
    ///    P's (Φ is the identity there): nothing to do.
    fn predict_covariance(&mut self, jacobian: &ProcessJacobian, dt: f32) {
        let j = jacobian.scaled(dt);
        let p = &mut self.p;
        // Column m of W's velocity rows is wv[m − 3], of its quaternion rows wq[m − 6].
        let wv: [[f32; 3]; STATES - 3] =
            core::array::from_fn(|k| phi_velocity(&j, &covariance::column(p, k + 3)));
        let wq: [[f32; 4]; STATES - 6] =
            core::array::from_fn(|k| phi_quaternion(&j, &covariance::column(p, k + 6)));
        for r in 0..3 {
            let (pr, pv) = (covariance::column(p, r), covariance::column(p, r + 3));
            let w: [f32; STATES] = core::array::from_fn(|m| {
                pr.get(m).copied().unwrap_or(0.0) + dt * pv.get(m).copied().unwrap_or(0.0)
            });
            store_phi_row(p, r, &j, dt, &w);
        }
        for (i, r) in (3..6).enumerate() {
            let w = core::array::from_fn(|m| cell(&wv, m.wrapping_sub(3), i));
            store_phi_row(p, r, &j, dt, &w);
        }
        for (i, r) in (6..10).enumerate() {
            let w = core::array::from_fn(|m| cell(&wq, m.wrapping_sub(6), i));
            store_phi_row(p, r, &j, dt, &w);
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
        let p = &mut self.p;
        for i in 3..6 {
            add_at(p, i, accel);
        }
        for i in 10..13 {
            add_at(p, i, bias);
        }
        add_at(p, 13, ab_z);
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

/// The velocity rows of Φ applied to `y`: y_v + (∂v̇/∂q)·y_q + (∂v̇/∂ab_z)·y_ab (J = F·dt).
#[inline(always)]
fn phi_velocity(j: &ProcessJacobian, y: &[f32; STATES]) -> [f32; 3] {
    let [_, _, _, v0, v1, v2, q0, q1, q2, q3, _, _, _, ab] = *y;
    let [c0, c1, c2] = j.dv_dbaz();
    j.dv_dq_times_add([q0, q1, q2, q3], [v0 + c0 * ab, v1 + c1 * ab, v2 + c2 * ab])
}

/// The quaternion rows of Φ applied to `y`: y_q + (∂q̇/∂q)·y_q + (∂q̇/∂b_g)·y_b.
#[inline(always)]
fn phi_quaternion(j: &ProcessJacobian, y: &[f32; STATES]) -> [f32; 4] {
    let [_, _, _, _, _, _, q0, q1, q2, q3, b0, b1, b2, _] = *y;
    let q = [q0, q1, q2, q3];
    j.dq_dbg_times_add([b0, b1, b2], j.dq_dq_times_add(q, q))
}

/// Row r of P' = W Φᵀ from row r of W (`w`): stores (Φ·w)[c] to P[r][c] and P[c][r] for
/// every c ≥ r.
#[inline(always)]
fn store_phi_row(p: &mut Covariance, r: usize, j: &ProcessJacobian, dt: f32, w: &[f32; STATES]) {
    let [w0, w1, w2, w3, w4, w5, ..] = *w;
    for (c, v) in [w0 + dt * w3, w1 + dt * w4, w2 + dt * w5]
        .into_iter()
        .enumerate()
    {
        if c >= r {
            covariance::set_symmetric(p, r, c, v);
        }
    }
    if r < 6 {
        for (c, v) in (3..6).zip(phi_velocity(j, w)) {
            if c >= r {
                covariance::set_symmetric(p, r, c, v);
            }
        }
    }
    for (c, v) in (6..10).zip(phi_quaternion(j, w)) {
        if c >= r {
            covariance::set_symmetric(p, r, c, v);
        }
    }
    for (c, &v) in w.iter().enumerate().skip(10) {
        covariance::set_symmetric(p, r, c, v);
    }
}

/// `rows[m][i]` (0 outside, which covers the columns before a buffer's first).
#[inline(always)]
fn cell<const N: usize, const M: usize>(rows: &[[f32; N]; M], m: usize, i: usize) -> f32 {
    rows.get(m)
        .and_then(|row| row.get(i))
        .copied()
        .unwrap_or(0.0)
}

/// P[i][i] += value.
#[inline(always)]
fn add_at(p: &mut Covariance, i: usize, value: f32) {
    if let Some(d) = p.get_mut(i).and_then(|row| row.get_mut(i)) {
        *d += value;
    }
}
