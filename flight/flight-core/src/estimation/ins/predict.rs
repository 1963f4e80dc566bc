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

/// Φ = I + F·dt in factored form.
struct Transition {
    dt: f32,
    dv_dq: [[f32; 4]; 3],
    dv_dbaz: [f32; 3],
    qq: [[f32; 4]; 4],
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
            dv_dbaz: j.dv_dbaz.map(|c| c * dt),
            qq,
            qb: j.dq_dbg.map(|row| row.map(|c| c * dt)),
        }
    }

    /// Φ·v.
    fn apply(&self, v: &[f32; STATES]) -> [f32; STATES] {
        let [p0, p1, p2, v0, v1, v2, q0, q1, q2, q3, b0, b1, b2, bz] = *v;
        let dt = self.dt;
        let vel = |r: &[f32; 4], rb: f32, base: f32| {
            base + r[0] * q0 + r[1] * q1 + r[2] * q2 + r[3] * q3 + rb * bz
        };
        let quat = |r: &[f32; 4], rb: &[f32; 3]| {
            r[0] * q0 + r[1] * q1 + r[2] * q2 + r[3] * q3 + rb[0] * b0 + rb[1] * b1 + rb[2] * b2
        };
        let [dv0, dv1, dv2] = &self.dv_dq;
        let [db0, db1, db2] = self.dv_dbaz;
        let [qq0, qq1, qq2, qq3] = &self.qq;
        let [qb0, qb1, qb2, qb3] = &self.qb;
        [
            p0 + dt * v0,
            p1 + dt * v1,
            p2 + dt * v2,
            vel(dv0, db0, v0),
            vel(dv1, db1, v1),
            vel(dv2, db2, v2),
            quat(qq0, qb0),
            quat(qq1, qb1),
            quat(qq2, qb2),
            quat(qq3, qb3),
            b0,
            b1,
            b2,
            bz,
        ]
    }
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
        // F is linearised at the pre-step state, as in the C reference (ekf.md §2).
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
        // W = P·Φᵀ: row k of W is Φ applied to row k of P (P symmetric).
        let mut w: Covariance = [[0.0; STATES]; STATES];
        for (w_row, p_row) in w.iter_mut().zip(self.p.iter()) {
            *w_row = phi.apply(p_row);
        }
        // P' = Φ·W: column c of P' is Φ applied to column c of W. P' is symmetric, so
        // writing that column as row c is the same matrix.
        for (c, p_row) in self.p.iter_mut().enumerate() {
            let mut col = [0.0; STATES];
            for (dst, w_row) in col.iter_mut().zip(w.iter()) {
                *dst = w_row.get(c).copied().unwrap_or(0.0);
            }
            *p_row = phi.apply(&col);
        }
        self.add_process_noise(dt);
        covariance::mirror_upper(&mut self.p);
    }

    /// Q_d = G·Q·Gᵀ·dt: accel noise through R_beᵀ (isotropic, so it stays diagonal), gyro
    /// noise through ½Ξ(q), and the bias random walks (DERIVATION.md §3).
    fn add_process_noise(&mut self, dt: f32) {
        let cfg = &self.config;
        let accel = cfg.accel_noise_psd * dt;
        let [g0, g1, g2] = cfg.gyro_noise_psd.map(|g| 0.25 * g * dt);
        let bias = cfg.gyro_bias_walk_psd * dt;
        let ab_z = cfg.accel_bias_walk_psd * dt;
        let x = xi(self.attitude());
        for (i, row) in self.p.iter_mut().enumerate() {
            match i {
                3..6 => add_diag(row, i, accel),
                6..10 => {
                    if let Some(xi_i) = x.get(i - 6) {
                        for (v, xi_j) in row.iter_mut().skip(6).zip(x.iter()) {
                            *v += g0 * xi_i[0] * xi_j[0]
                                + g1 * xi_i[1] * xi_j[1]
                                + g2 * xi_i[2] * xi_j[2];
                        }
                    }
                }
                10..13 => add_diag(row, i, bias),
                13 => add_diag(row, i, ab_z),
                _ => {}
            }
        }
    }
}

fn add_diag(row: &mut [f32; STATES], i: usize, value: f32) {
    if let Some(d) = row.get_mut(i) {
        *d += value;
    }
}
