//! State resets: overwrite part of the state with a direct estimate and give that part a
//! fresh, uncorrelated covariance block. Used by the aiding logic after persistent
//! rejections and for the initial alignment (PX4 EKF2 resets the same way).

use super::equations::xi;
use super::{Filter, covariance, index};
use crate::align::{self, tilt_from_accel};
use crate::quaternion::{self, Quaternion, ned_to_body};
use crate::{Error, check_finite};

impl Filter {
    /// Sets the position states given in `position_ned_m` (`None` keeps an axis) with
    /// variance `var_m2`, uncorrelated with everything else.
    pub fn reset_position(&mut self, position_ned_m: [Option<f32>; 3], var_m2: f32) {
        self.reset_direct(index::POSITION, position_ned_m, var_m2);
    }

    /// Sets the velocity states with variance `var_m2ps2`.
    pub fn reset_velocity(&mut self, velocity_ned_mps: [f32; 3], var_m2ps2: f32) {
        self.reset_direct(index::VELOCITY, velocity_ned_mps.map(Some), var_m2ps2);
    }

    fn reset_direct(&mut self, first: usize, values: [Option<f32>; 3], var: f32) {
        for (offset, value) in values.iter().enumerate() {
            let Some(value) = value.filter(|v| v.is_finite()) else {
                continue;
            };
            let k = first + offset;
            covariance::clear_block(&mut self.p, k, 1);
            if let Some(x) = self.x.get_mut(k) {
                *x = value;
            }
            if let Some(d) = self.p.get_mut(k).and_then(|row| row.get_mut(k)) {
                *d = var;
            }
        }
    }

    /// Raises each gyro-bias variance to at least `var_radps2` (cross terms kept). After a
    /// reset the likeliest culprit is a bias that changed faster than its random walk allows;
    /// this re-opens the bias states so the next measurements can learn it quickly.
    pub fn inflate_gyro_bias_variance(&mut self, var_radps2: f32) {
        for k in index::GYRO_BIAS..index::GYRO_BIAS + 3 {
            if let Some(d) = self.p.get_mut(k).and_then(|row| row.get_mut(k)) {
                *d = d.max(var_radps2);
            }
        }
    }

    /// Sets the gyro-bias random-walk PSD ((rad/s)²/s) used from the next predict on; the
    /// aiding logic lowers it once the estimate has settled and restores it after a reset.
    /// A non-finite or negative value is ignored.
    pub fn set_gyro_bias_walk_psd(&mut self, psd: f32) {
        if psd.is_finite() && psd >= 0.0 {
            self.config.gyro_bias_walk_psd = psd;
        }
    }

    /// Replaces the attitude with `q`; its covariance becomes `tilt_var_rad2` about the two
    /// horizontal axes and `yaw_var_rad2` about the vertical, mapped into quaternion space by
    /// δq = ½Ξ(q)·δθ (DERIVATION.md §5).
    pub fn reset_attitude(&mut self, q: Quaternion, tilt_var_rad2: f32, yaw_var_rad2: f32) {
        let q = quaternion::normalized(q);
        let [q0, q1, q2, q3] = q;
        let [.., a, b, c, d, _, _, _, _] = &mut self.x;
        (*a, *b, *c, *d) = (q0, q1, q2, q3);
        // Body-frame angle covariance: tilt·(I − u·uᵀ) + yaw·u·uᵀ, u = NED down in body axes.
        let [[_, _, u0], [_, _, u1], [_, _, u2]] = ned_to_body(q);
        let u = [u0, u1, u2];
        let mut sigma = [[0.0_f32; 3]; 3];
        for (i, row) in sigma.iter_mut().enumerate() {
            for (j, s) in row.iter_mut().enumerate() {
                let uu = u.get(i).copied().unwrap_or(0.0) * u.get(j).copied().unwrap_or(0.0);
                let eye = if i == j { 1.0 } else { 0.0 };
                *s = tilt_var_rad2 * (eye - uu) + yaw_var_rad2 * uu;
            }
        }
        let x = xi(q);
        let mut block = [[0.0_f32; 4]; 4];
        for (block_row, xi_i) in block.iter_mut().zip(x.iter()) {
            for (b, xi_j) in block_row.iter_mut().zip(x.iter()) {
                let mut acc = 0.0;
                for (xi_ia, sigma_row) in xi_i.iter().zip(sigma.iter()) {
                    for (xi_jb, s) in xi_j.iter().zip(sigma_row.iter()) {
                        acc += xi_ia * s * xi_jb;
                    }
                }
                *b = 0.25 * acc;
            }
        }
        covariance::clear_block(&mut self.p, index::QUATERNION, 4);
        covariance::set_block4(&mut self.p, index::QUATERNION, &block);
    }

    /// Yaw (rad) that makes the magnetometer reading agree with the earth field, given the
    /// current roll and pitch ([`align::heading_from_mag`]).
    #[must_use]
    pub fn yaw_from_mag(&self, mag_body: [f32; 3]) -> Option<f32> {
        let [roll, pitch, _] = quaternion::to_euler(self.attitude());
        align::heading_from_mag(roll, pitch, mag_body, self.config.earth_field_ned)
    }

    /// Keeps roll and pitch, sets yaw from the magnetometer with variance `yaw_var_rad2`.
    pub fn reset_yaw_from_mag(&mut self, mag_body: [f32; 3], yaw_var_rad2: f32) -> bool {
        let Some(yaw) = self.yaw_from_mag(mag_body) else {
            return false;
        };
        let [roll, pitch, _] = quaternion::to_euler(self.attitude());
        let tilt_var = self.tilt_variance();
        self.reset_attitude(
            quaternion::from_euler(roll, pitch, yaw),
            tilt_var,
            yaw_var_rad2,
        );
        true
    }

    /// Keeps yaw, sets roll and pitch from a (low-passed) specific force that is assumed to
    /// be gravity only, with variance `tilt_var_rad2` and yaw variance `yaw_var_rad2`.
    pub fn reset_tilt_from_accel(
        &mut self,
        accel_mps2: [f32; 3],
        tilt_var_rad2: f32,
        yaw_var_rad2: f32,
    ) {
        let [roll, pitch] = tilt_from_accel(accel_mps2);
        let [_, _, yaw] = quaternion::to_euler(self.attitude());
        self.reset_attitude(
            quaternion::from_euler(roll, pitch, yaw),
            tilt_var_rad2,
            yaw_var_rad2,
        );
    }

    /// Initial alignment: roll and pitch from the accelerometer, yaw from the magnetometer,
    /// zero velocity, position at `position_ned_m`, covariance from the config's initial
    /// standard deviations (attitude: `tilt_std_rad`, `yaw_std_rad`).
    ///
    /// # Errors
    /// [`Error::NonFinite`] if an input is not finite.
    pub fn align(
        &mut self,
        accel_mps2: [f32; 3],
        mag_body: [f32; 3],
        position_ned_m: [f32; 3],
        tilt_std_rad: f32,
        yaw_std_rad: f32,
    ) -> Result<(), Error> {
        check_finite(&accel_mps2)?;
        check_finite(&mag_body)?;
        check_finite(&position_ned_m)?;
        *self = Self::new(self.config);
        let q = align::attitude(accel_mps2, Some(mag_body), self.config.earth_field_ned);
        self.reset_attitude(q, tilt_std_rad * tilt_std_rad, yaw_std_rad * yaw_std_rad);
        let [pos_std, ..] = self.config.initial_std;
        self.reset_position(position_ned_m.map(Some), pos_std * pos_std);
        Ok(())
    }

    /// Current tilt variance (rad²), read back from the quaternion block (≈ 4·P_qq trace / 3).
    fn tilt_variance(&self) -> f32 {
        let trace: f32 = (index::QUATERNION..index::QUATERNION + 4)
            .filter_map(|k| self.p.get(k).and_then(|row| row.get(k)))
            .sum();
        (4.0 / 3.0 * trace).max(1e-8)
    }
}
